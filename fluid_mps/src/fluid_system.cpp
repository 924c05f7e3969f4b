#include "cosim/fluid_mps/fluid_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/pressure_solver.hpp"

// Loops run in parallel from 4096 items on (the `if` clauses below): under that the OpenMP
// fork/join costs more than the work, and oversubscribed CI cores make it far worse.
namespace cosim::mps {
namespace {

bool is_fluid(ParticleKind kind) {
  return kind == ParticleKind::fluid;
}

bool is_inactive(ParticleKind kind) {
  return kind == ParticleKind::inactive;
}

// Grid over the active particles (inactive ones of the open-boundary pool are left out), periodic
// in x when enabled; `include` is filled only if some particle is inactive.
NeighbourGrid active_grid(const MpsParameters& p, const std::vector<Eigen::Vector3d>& positions,
                          const std::vector<ParticleKind>& kinds, double margin, double cell,
                          std::vector<char>& include) {
  include.clear();
  std::vector<Eigen::Vector3d> active;
  const bool any_inactive = std::any_of(kinds.begin(), kinds.end(), is_inactive);
  if (any_inactive) {
    include.resize(kinds.size());
    for (std::size_t i = 0; i < kinds.size(); ++i) {
      include[i] = is_inactive(kinds[i]) ? 0 : 1;
      if (include[i]) active.push_back(positions[i]);
    }
  }
  return NeighbourGrid(p.dimension,
                       bounding_box(any_inactive ? active : positions, p.dimension, margin), cell,
                       p.periodic);
}

void validate(const MpsParameters& p) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("MpsParameters: ") + what);
  };
  require(p.dimension == 2 || p.dimension == 3, "dimension must be 2 or 3");
  require(p.particle_spacing > 0.0, "particle_spacing must be positive");
  require(p.density > 0.0, "density must be positive");
  require(p.kinematic_viscosity >= 0.0, "kinematic_viscosity must be >= 0");
  require(p.radius_density_over_l0 > 1.0 && p.radius_gradient_over_l0 > 1.0 &&
              p.radius_laplacian_over_l0 > 1.0,
          "influence radii must exceed l0");
  require(p.surface_threshold > 0.0 && p.surface_threshold < 1.0,
          "surface_threshold must be in (0, 1)");
  require(p.collision_distance_ratio >= 0.0 && p.collision_distance_ratio <= 1.5,
          "collision_distance_ratio must be in [0, 1.5]");
  require(p.collision_restitution >= -1.0 && p.collision_restitution <= 1.0,
          "collision_restitution must be in [-1, 1]");
  require(p.courant > 0.0 && p.courant <= 1.0, "courant must be in (0, 1]");
  require(p.max_dt > 0.0, "max_dt must be positive");
  require(p.pcg_tolerance > 0.0 && p.pcg_max_iterations > 0, "PCG tolerance and iterations");
  require(p.compressibility >= 0.0, "compressibility must be >= 0");
  require(p.pressure_relaxation > 0.0 && p.pressure_relaxation <= 1.0,
          "pressure_relaxation must be in (0, 1]");
  const double largest_radius = std::max({p.radius_density_over_l0, p.radius_gradient_over_l0,
                                          p.radius_laplacian_over_l0, p.collision_distance_ratio}) *
                                p.particle_spacing;
  require(!p.periodic.enabled || p.periodic.length() >= 3.0 * largest_radius,
          "periodic length must be at least three times the largest influence radius");
}

}  // namespace

FluidSystem::FluidSystem(MpsParameters parameters, ParticleSet particles)
    : parameters_(std::move(parameters)),
      positions_(std::move(particles.positions)),
      velocities_(std::move(particles.velocities)),
      kinds_(std::move(particles.kinds)) {
  if (velocities_.empty()) velocities_.assign(positions_.size(), Eigen::Vector3d::Zero());
  pressures_.assign(positions_.size(), 0.0);
  initialise();
}

FluidSystem::FluidSystem(MpsParameters parameters, const MpsState& state)
    : parameters_(std::move(parameters)),
      positions_(state.positions),
      velocities_(state.velocities),
      pressures_(state.pressures),
      kinds_(state.kinds),
      time_(state.time),
      step_(state.step) {
  if (pressures_.size() != positions_.size()) {
    throw std::invalid_argument("MpsState: pressures and positions differ in size");
  }
  initialise();
}

void FluidSystem::initialise() {
  validate(parameters_);
  const std::size_t n = positions_.size();
  if (kinds_.size() != n || velocities_.size() != n) {
    throw std::invalid_argument("FluidSystem: positions, kinds and velocities differ in size");
  }
  const MpsParameters& p = parameters_;
  const double l0 = p.particle_spacing;
  density_sums_ = lattice_sums(p.dimension, p.radius_density_over_l0);
  gradient_sums_ = lattice_sums(p.dimension, p.radius_gradient_over_l0);
  laplacian_sums_ = lattice_sums(p.dimension, p.radius_laplacian_over_l0);
  particle_mass_ = p.density * std::pow(l0, p.dimension);
  external_accelerations_.assign(n, Eigen::Vector3d::Zero());

  domain_box_ = p.domain;
  if (domain_box_.isEmpty()) {
    for (const auto& x : positions_) domain_box_.extend(x);
    const Eigen::Vector3d margin = Eigen::Vector3d::Constant(20.0 * l0);
    domain_box_ = Eigen::AlignedBox3d(domain_box_.min() - margin, domain_box_.max() + margin);
    parameters_.domain = domain_box_;
  }
  if (p.dimension == 2) {  // 2D particles have z = 0; give the box a z extent
    domain_box_.min().z() = -l0;
    domain_box_.max().z() = l0;
  }
  if (p.periodic.enabled) {
    for (auto& x : positions_) x = p.periodic.fold(x);
  }
  check_stability(step_);
  // Initial number densities for the accessor (the step recomputes them at r*).
  const double re_n = p.radius_density_over_l0 * l0;
  std::vector<char> include;
  NeighbourGrid grid = active_grid(p, positions_, kinds_, re_n, re_n, include);
  grid.build(positions_, include.empty() ? nullptr : &include);
  NeighbourList list = grid.neighbours(positions_, re_n);
  remove_partition_crossings(list, positions_, p.partitions, p.periodic, &kinds_);
  number_densities_.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = list.begin(static_cast<int>(i)); k < list.end(static_cast<int>(i)); ++k) {
      number_densities_[i] += weight(list.distance[k], re_n);
    }
  }
}

double FluidSystem::lambda_laplacian() const {
  const double l0 = parameters_.particle_spacing;
  return laplacian_sums_.lambda_over_l0sq * l0 * l0;
}

double FluidSystem::stable_dt() const {
  const MpsParameters& p = parameters_;
  const double l0 = p.particle_spacing;
  double max_speed = 0.0;
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    if (is_fluid(kinds_[i])) max_speed = std::max(max_speed, velocities_[i].norm());
  }
  double dt = p.max_dt;
  if (max_speed > 0.0) dt = std::min(dt, p.courant * l0 / max_speed);
  if (p.kinematic_viscosity > 0.0) {
    dt = std::min(dt, p.diffusion_number * l0 * l0 / p.kinematic_viscosity);
  }
  return dt;
}

void FluidSystem::check_stability(long step) const {
  const int n = particle_count();
  const bool two_d = parameters_.dimension == 2;
  for (int i = 0; i < n; ++i) {
    if (is_inactive(kinds_[i])) continue;  // pooled by the open boundaries
    const Eigen::Vector3d& x = positions_[i];
    const Eigen::Vector3d& u = velocities_[i];
    if (!x.allFinite()) throw StabilityError(step, i, "position", "not finite");
    if (!u.allFinite()) throw StabilityError(step, i, "velocity", "not finite");
    if (!std::isfinite(pressures_[i])) throw StabilityError(step, i, "pressure", "not finite");
    bool inside = true;
    for (int axis = 0; axis < (two_d ? 2 : 3); ++axis) {
      inside = inside && x[axis] >= domain_box_.min()[axis] && x[axis] <= domain_box_.max()[axis];
    }
    if (!inside) {
      std::ostringstream detail;
      detail << "escaped the domain box at (" << x.x() << ", " << x.y() << ", " << x.z() << ")";
      throw StabilityError(step, i, "position", detail.str());
    }
    const double speed = u.norm();
    if (speed > parameters_.runaway_speed) {
      std::ostringstream detail;
      detail << "speed " << speed << " m/s exceeds runaway_speed " << parameters_.runaway_speed;
      throw StabilityError(step, i, "velocity", detail.str());
    }
  }
}

StepReport FluidSystem::step(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument("FluidSystem::step: dt must be positive and finite");
  }
  const MpsParameters& p = parameters_;
  const int n = particle_count();
  const int d = p.dimension;
  const double l0 = p.particle_spacing;
  const double re_n = p.radius_density_over_l0 * l0;
  const double re_g = p.radius_gradient_over_l0 * l0;
  const double re_l = p.radius_laplacian_over_l0 * l0;
  const double n0_n = density_sums_.n0;
  const double n0_g = gradient_sums_.n0;
  const double n0_l = laplacian_sums_.n0;
  const double lambda = lambda_laplacian();
  const double collision_distance = p.collision_distance_ratio * l0;
  const double search_radius = std::max({re_n, re_g, re_l, collision_distance});
  const long this_step = step_ + 1;
  StepReport report;
  report.dt = dt;

  // Particles move less than l0 per step, so one grid box (around r^n, grown by two search
  // radii) holds r* too; cells are clamped at its edges anyway.
  // Periodic runs wrap the cells in x (seed 001 section 2.2(4)); inactive particles are left out.
  std::vector<char> include;
  NeighbourGrid grid =
      active_grid(p, positions_, kinds_, 2.0 * search_radius, search_radius, include);
  const std::vector<char>* included = include.empty() ? nullptr : &include;
  const PeriodicBoundary& periodic = p.periodic;
  auto build_list = [&](const std::vector<Eigen::Vector3d>& x, double radius) {
    grid.build(x, included);
    NeighbourList result = grid.neighbours(x, radius);
    remove_partition_crossings(result, x, p.partitions, periodic,
                               &kinds_);  // seed 001 section 2.2(1)
    return result;
  };
  // Constant streamwise pressure difference of a periodic channel as a body force (seed 000
  // section 3.1): a = dp / (rho L).
  Eigen::Vector3d driving = Eigen::Vector3d::Zero();
  if (periodic.enabled)
    driving.x() = periodic.driving_pressure_drop / (p.density * periodic.length());

  // 1. Explicit part at r^n: viscosity (seed 000 eq. (3)), gravity and coupling forces.
  NeighbourList list = build_list(positions_, re_l);
  const double viscous_factor = p.kinematic_viscosity * 2.0 * d / (n0_l * lambda);
  // Number density at r^n, for the density-error part of the mixed source term.
  std::vector<double> density_now(n, 0.0);
  std::vector<Eigen::Vector3d> velocity_star(velocities_);
  std::vector<Eigen::Vector3d> position_star(positions_);
  std::vector<Eigen::Vector3d> wall_viscous(n, Eigen::Vector3d::Zero());
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (is_inactive(kinds_[i])) continue;
    double density_sum = 0.0;
    for (int k = list.begin(i); k < list.end(i); ++k) density_sum += weight(list.distance[k], re_n);
    density_now[i] = density_sum;
    if (is_fluid(kinds_[i])) {
      Eigen::Vector3d laplacian = Eigen::Vector3d::Zero();
      for (int k = list.begin(i); k < list.end(i); ++k) {
        const int j = list.index[k];
        const Eigen::Vector3d term =
            (velocities_[j] - velocities_[i]) * weight(list.distance[k], re_l);
        laplacian += term;
        if (!is_fluid(kinds_[j])) wall_viscous[i] += term;
      }
      velocity_star[i] +=
          dt * (viscous_factor * laplacian + p.gravity + driving + external_accelerations_[i]);
    }
    position_star[i] += dt * velocity_star[i];
  }
  for (int i = 0; i < n; ++i) {
    report.wall_viscous_force += wall_viscous[i];
    if (is_fluid(kinds_[i])) {
      report.external_impulse += external_accelerations_[i];
      report.body_impulse += p.gravity + driving;
    }
  }
  report.external_impulse *= particle_mass_ * dt;
  report.body_impulse *= particle_mass_ * dt;
  report.wall_viscous_force *= particle_mass_ * viscous_factor;
  for (int i = 0; i < n; ++i) {
    if (!position_star[i].allFinite() || !velocity_star[i].allFinite()) {
      throw StabilityError(this_step, i, "velocity", "not finite after the explicit step");
    }
  }

  // 2. Collision model (seed 001 eqs. (10), (11)): an approaching pair closer than d_c has its
  // normal approach velocity V_r replaced by a repulsion (1 + C_c) V_r. V_r is the share of the
  // relative normal velocity that the pair's mass ratio gives to particle i (all of it against a
  // wall, half between two fluid particles), so fluid-fluid collisions conserve momentum.
  // All corrections use the pre-collision velocities: order independent, thus deterministic.
  if (collision_distance > 0.0) {
    list = build_list(position_star, collision_distance);
    std::vector<Eigen::Vector3d> correction(n, Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> wall_correction(n, Eigen::Vector3d::Zero());
    std::vector<int> collided(n, 0);
#pragma omp parallel for schedule(static) if (n >= 4096)
    for (int i = 0; i < n; ++i) {
      if (!is_fluid(kinds_[i])) continue;
      for (int k = list.begin(i); k < list.end(i); ++k) {
        const int j = list.index[k];
        const double r = list.distance[k];
        if (r <= 0.0) continue;
        const Eigen::Vector3d normal = periodic.wrap(position_star[j] - position_star[i]) / r;
        const double approach = (velocity_star[j] - velocity_star[i]).dot(normal);
        if (approach >= 0.0) continue;
        const double share = is_fluid(kinds_[j]) ? 0.5 : 1.0;
        const Eigen::Vector3d change = (1.0 + p.collision_restitution) * share * approach * normal;
        correction[i] += change;
        if (!is_fluid(kinds_[j])) wall_correction[i] += change;
        ++collided[i];
      }
    }
    for (int i = 0; i < n; ++i) {
      if (collided[i] == 0) continue;
      velocity_star[i] += correction[i];
      position_star[i] += dt * correction[i];
      report.collisions += collided[i];
      report.collision_impulse += particle_mass_ * correction[i];
      report.wall_collision_impulse += particle_mass_ * wall_correction[i];
    }
  }

  // 3. Number density at r* (seed 001 eq. (7)) and free-surface detection (n* < beta n0).
  list = build_list(position_star, search_radius);
  // Velocity divergence at r* with the density radius (seed 001 eq. (8) applied to u . r_ij).
  number_densities_.assign(n, 0.0);
  std::vector<double> divergence(n, 0.0);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double sum = 0.0, divergence_sum = 0.0;
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const double r = list.distance[k];
      const double w = weight(r, re_n);
      if (w <= 0.0) continue;
      const int j = list.index[k];
      sum += w;
      divergence_sum += (velocity_star[j] - velocity_star[i])
                            .dot(periodic.wrap(position_star[j] - position_star[i])) /
                        (r * r) * w;
    }
    number_densities_[i] = sum;
    divergence[i] = d / n0_n * divergence_sum;
  }
  // Unknowns: fluid and wall particles off the free surface; dummy particles carry no pressure.
  std::vector<int> unknown(n, -1);
  std::vector<int> unknown_particle;
  for (int i = 0; i < n; ++i) {
    if (kinds_[i] == ParticleKind::dummy || is_inactive(kinds_[i])) continue;
    if (number_densities_[i] < p.surface_threshold * n0_n) {
      ++report.surface_particles;
      continue;
    }
    unknown[i] = static_cast<int>(unknown_particle.size());
    unknown_particle.push_back(i);
  }
  const int m = static_cast<int>(unknown_particle.size());
  report.pressure_unknowns = m;

  // 4. Pressure Poisson equation with the Laplacian model (seed 001 eq. (9)):
  //    <lap p>_i - rho alpha p_i / dt^2 = -gamma rho / dt^2 (n*_i - n0) / n0,
  // multiplied by -lambda n0 / (2d) so the matrix is symmetric positive definite:
  //    sum_j w_ij (p_i - p_j) + c alpha p_i = c gamma (n*_i - n0) / n0,
  //    c = lambda n0 rho / (2d dt^2);
  // with the mixed source the right side is c (gamma (n^k_i - n0) / n0 - dt <div u*>_i).
  const double scale = lambda * n0_l * p.density / (2.0 * d * dt * dt);
  SparseRows matrix;
  std::vector<std::int64_t> row_length(m + 1, 0);
#pragma omp parallel for schedule(static) if (m >= 4096)
  for (int row = 0; row < m; ++row) {
    const int i = unknown_particle[row];
    std::int64_t count = 1;
    for (int k = list.begin(i); k < list.end(i); ++k) {
      if (unknown[list.index[k]] >= 0 && list.distance[k] < re_l) ++count;
    }
    row_length[row + 1] = count;
  }
  for (int row = 0; row < m; ++row) row_length[row + 1] += row_length[row];
  matrix.offset = row_length;
  matrix.column.resize(row_length[m]);
  matrix.value.resize(row_length[m]);
  std::vector<double> rhs(m), solution(m);
#pragma omp parallel for schedule(static) if (m >= 4096)
  for (int row = 0; row < m; ++row) {
    const int i = unknown_particle[row];
    std::int64_t slot = matrix.offset[row];
    const std::int64_t diagonal_slot = slot++;
    double diagonal = scale * p.compressibility;
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const int j = list.index[k];
      if (kinds_[j] == ParticleKind::dummy) continue;
      const double w = weight(list.distance[k], re_l);
      if (w <= 0.0) continue;
      diagonal += w;  // Dirichlet neighbours (p = 0) only add to the diagonal
      if (unknown[j] >= 0) {
        matrix.column[slot] = unknown[j];
        matrix.value[slot] = -w;
        ++slot;
      }
    }
    // Zero weight exactly at r = re_l was counted in pass 1 when distance < re_l; pad.
    for (; slot < matrix.offset[row + 1]; ++slot) {
      matrix.column[slot] = row;
      matrix.value[slot] = 0.0;
    }
    matrix.column[diagonal_slot] = row;
    matrix.value[diagonal_slot] = diagonal;
    rhs[row] =
        p.source_term == MpsParameters::SourceTerm::density
            ? scale * p.pressure_relaxation * (number_densities_[i] - n0_n) / n0_n
            : scale * (p.pressure_relaxation * (density_now[i] - n0_n) / n0_n - dt * divergence[i]);
    solution[row] = pressures_[i];  // warm start from the previous step
  }
  const PcgResult pcg = solve_pcg(
      matrix, rhs, solution, p.pcg_tolerance, p.pcg_max_iterations,
      p.pcg_incomplete_cholesky ? Preconditioner::incomplete_cholesky : Preconditioner::jacobi);
  report.pcg_iterations = pcg.iterations;
  report.pcg_residual = pcg.relative_residual;
  report.pcg_converged = pcg.converged;
  // Negative pressures are clamped to zero: MPS has no tension (standard practice).
  std::vector<double> pressure(n, 0.0);
  for (int row = 0; row < m; ++row) {
    pressure[unknown_particle[row]] = std::max(0.0, solution[row]);
  }

  // 5. Pressure gradient (seed 000 eq. (2), radius re_g) with the minimum neighbour pressure
  // p^_i in place of p_i (Koshizuka-Oka) so that inter-particle forces stay repulsive, or the
  // symmetric pair form (MpsParameters::GradientForm), and the correction
  // u' = -dt/rho <grad p>, r^{n+1} = r* + dt u'.
  std::vector<Eigen::Vector3d> next_velocity(velocity_star);
  std::vector<Eigen::Vector3d> next_position(position_star);
  std::vector<Eigen::Vector3d> pressure_change(n, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> wall_pressure_change(n, Eigen::Vector3d::Zero());
  const double gradient_factor = dt / p.density * d / n0_g;
  const bool symmetric = p.gradient_form == MpsParameters::GradientForm::symmetric;
  std::vector<double> minimum(n, 0.0);  // p^_i
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds_[i]) || symmetric) continue;
    double smallest = pressure[i];
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const int j = list.index[k];
      if (kinds_[j] != ParticleKind::dummy && list.distance[k] < re_g) {
        smallest = std::min(smallest, pressure[j]);
      }
    }
    minimum[i] = smallest;
  }
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds_[i])) continue;
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero(), wall_gradient = Eigen::Vector3d::Zero();
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const int j = list.index[k];
      const double r = list.distance[k];
      if (kinds_[j] == ParticleKind::dummy || r >= re_g) continue;
      const double difference = symmetric ? pressure[i] + pressure[j] : pressure[j] - minimum[i];
      const Eigen::Vector3d term = difference / (r * r) * weight(r, re_g) *
                                   periodic.wrap(position_star[j] - position_star[i]);
      gradient += term;
      if (!is_fluid(kinds_[j])) wall_gradient += term;
    }
    const Eigen::Vector3d correction = -gradient_factor * gradient;
    next_velocity[i] += correction;
    next_position[i] += dt * correction;
    pressure_change[i] = correction;
    wall_pressure_change[i] = -gradient_factor * wall_gradient;
  }

  for (int i = 0; i < n; ++i) {  // serial sums: the same result with any thread count
    report.pressure_impulse += particle_mass_ * pressure_change[i];
    report.wall_pressure_impulse += particle_mass_ * wall_pressure_change[i];
  }
  positions_ = std::move(next_position);
  if (periodic.enabled) {  // re-entry at x_min (seed 001 fig. 2.4 (2))
    for (int i = 0; i < n; ++i) positions_[i] = periodic.fold(positions_[i]);
  }
  velocities_ = std::move(next_velocity);
  pressures_ = std::move(pressure);
  // The point forces stay for the next step of the same window (set_point_forces).
  time_ += dt;
  step_ = this_step;
  for (int i = 0; i < n; ++i) {
    if (is_fluid(kinds_[i])) report.max_speed = std::max(report.max_speed, velocities_[i].norm());
  }
  check_stability(step_);
  return report;
}

void FluidSystem::set_particle(int i, ParticleKind kind, const Eigen::Vector3d& position,
                               const Eigen::Vector3d& velocity) {
  if (i < 0 || i >= particle_count()) throw std::out_of_range("set_particle: bad index");
  kinds_[i] = kind;
  positions_[i] = position;
  positions_[i] = parameters_.periodic.fold(position);
  velocities_[i] = velocity;
  pressures_[i] = 0.0;
  external_accelerations_[i].setZero();
}

void FluidSystem::set_velocity(int i, const Eigen::Vector3d& velocity) {
  if (i < 0 || i >= particle_count()) throw std::out_of_range("set_velocity: bad index");
  velocities_[i] = velocity;
}

MpsState FluidSystem::save_state() const {
  return MpsState{positions_, velocities_, pressures_, kinds_, time_, step_};
}

}  // namespace cosim::mps

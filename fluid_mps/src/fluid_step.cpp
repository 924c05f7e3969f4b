// The semi-implicit MPS step (Koshizuka-Oka; seed 000 section 2(1), seed 001 section 2) as a list
// of stages: predict, collide, measure density, assemble and solve the pressure equation,
// correct. All stages share one pair list (update_neighbours) and the work arrays of the system.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/operators.hpp"

// Loops run in parallel from 4096 items on (the `if` clauses below): under that the OpenMP
// fork/join costs more than the work, and oversubscribed CI cores make it far worse.
namespace cosim::mps {
namespace {

const Eigen::Vector3d kZero = Eigen::Vector3d::Zero();

template <class T>
void fill(std::vector<T>& v, std::size_t n, const T& value) {
  v.assign(n, value);  // no allocation once the capacity is there
}

}  // namespace

struct FluidSystem::StepConstants {
  double dt;
  int n, d;
  double re_n, re_g, re_l, collision_distance;
  double n0_n, n0_g, n0_l, lambda;
  Eigen::Vector3d driving;  // periodic channel: constant pressure drop as a body force
};

StepReport FluidSystem::step(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument("FluidSystem::step: dt must be positive and finite");
  }
  const MpsParameters& p = parameters_;
  const double l0 = p.particle_spacing;
  StepConstants c{};
  c.dt = dt;
  c.n = particle_count();
  c.d = p.dimension;
  c.re_n = p.radius_density_over_l0 * l0;
  c.re_g = p.radius_gradient_over_l0 * l0;
  c.re_l = p.radius_laplacian_over_l0 * l0;
  c.collision_distance = p.collision_distance_ratio * l0;
  c.n0_n = density_sums_.n0;
  c.n0_g = gradient_sums_.n0;
  c.n0_l = laplacian_sums_.n0;
  c.lambda = lambda_laplacian();
  // Constant streamwise pressure difference of a periodic channel (seed 000 section 3.1):
  // a = dp / (rho L).
  c.driving = Eigen::Vector3d::Zero();
  if (p.periodic.enabled) {
    c.driving.x() = p.periodic.driving_pressure_drop / (p.density * p.periodic.length());
  }

  StepReport report;
  report.dt = dt;
  predict(c, report);
  collide(c, report);
  measure_density(c, report);
  assemble_pressure_equation(c);
  solve_pressure(report);
  correct_with_pressure_gradient(c, report);
  finish_step(c, report);
  return report;
}

void FluidSystem::update_neighbours(const std::vector<Eigen::Vector3d>& x, StepReport& report,
                                    const std::vector<int>* moved) {
  const MpsParameters& p = parameters_;
  const int n = particle_count();
  const double l0 = p.particle_spacing;
  const double skin = kSkinOverL0 * l0;
  // Two particles that each moved less than half the skin are still listed if now in reach.
  bool valid = neighbours_valid_ && static_cast<int>(search_positions_.size()) == n;
  if (valid) {
    double largest_move2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : largest_move2) if (n >= 4096)
    for (int i = 0; i < n; ++i) {
      if (is_inactive(kinds_[i])) continue;
      largest_move2 =
          std::max(largest_move2, p.periodic.wrap(x[i] - search_positions_[i]).squaredNorm());
    }
    valid = 4.0 * largest_move2 < skin * skin;
  }
  if (!valid) {
    const double list_radius = largest_influence_radius(p) + skin;
    include_.clear();
    const bool any_inactive = std::any_of(kinds_.begin(), kinds_.end(), is_inactive);
    std::vector<Eigen::Vector3d> active;
    if (any_inactive) {
      include_.resize(n);
      for (int i = 0; i < n; ++i) {
        include_[i] = is_inactive(kinds_[i]) ? 0 : 1;
        if (include_[i]) active.push_back(x[i]);
      }
    }
    NeighbourGrid grid(p.dimension,
                       bounding_box(any_inactive ? active : x, p.dimension, list_radius),
                       list_radius, p.periodic);
    grid.build(x, any_inactive ? &include_ : nullptr);
    neighbours_ = grid.neighbours(x, list_radius);
    // Partners in ascending index order: the order of every sum is then a property of the
    // pairs, not of the cells they were found in at the search.
#pragma omp parallel for schedule(static) if (n >= 4096)
    for (int i = 0; i < n; ++i) {
      std::sort(neighbours_.index.begin() + neighbours_.begin(i),
                neighbours_.index.begin() + neighbours_.end(i));
    }
    search_positions_ = x;
    neighbours_valid_ = true;
    ++report.neighbour_searches;
  }
  // Distances at x; pairs cut by a thin partition (seed 001 section 2.2(1)) at x get infinity.
  const bool partial = valid && moved;
  if (partial && std::none_of(moved->begin(), moved->end(), [](int m) { return m != 0; })) {
    return;
  }
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    const bool i_moved = partial && (*moved)[i] != 0;
    for (int k = neighbours_.begin(i); k < neighbours_.end(i); ++k) {
      const int j = neighbours_.index[k];
      if (partial && !i_moved && (*moved)[j] == 0) continue;
      neighbours_.distance[k] = p.periodic.wrap(x[j] - x[i]).norm();
    }
  }
  mask_partition_crossings(neighbours_, x, p.partitions, p.periodic, &kinds_);
}

// 1. Explicit part at r^n: viscosity (seed 000 eq. (3)), gravity, driving and point forces;
// also the number density at r^n for the density-error part of the mixed source term.
void FluidSystem::predict(const StepConstants& c, StepReport& report) {
  const MpsParameters& p = parameters_;
  const int n = c.n;
  const double dt = c.dt;
  update_neighbours(positions_, report);
  const NeighbourList& list = neighbours_;
  const double viscous_factor = p.kinematic_viscosity * laplacian_factor(c.d, c.n0_l, c.lambda);
  fill(density_now_, n, 0.0);
  velocity_star_ = velocities_;
  position_star_ = positions_;
  fill(wall_viscous_, n, kZero);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (is_inactive(kinds_[i])) continue;
    double density_sum = 0.0;
    Eigen::Vector3d laplacian = Eigen::Vector3d::Zero();
    const bool fluid = is_fluid(kinds_[i]);
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const double r = list.distance[k];
      if (r < c.re_n) density_sum += weight(r, c.re_n);
      if (!fluid || r >= c.re_l) continue;
      const int j = list.index[k];
      const Eigen::Vector3d term = (velocities_[j] - velocities_[i]) * weight(r, c.re_l);
      laplacian += term;
      if (!is_fluid(kinds_[j])) wall_viscous_[i] += term;
    }
    density_now_[i] = density_sum;
    if (fluid) {
      velocity_star_[i] +=
          dt * (viscous_factor * laplacian + p.gravity + c.driving + external_accelerations_[i]);
    }
    position_star_[i] += dt * velocity_star_[i];
  }
  for (int i = 0; i < n; ++i) {
    report.wall_viscous_force += wall_viscous_[i];
    if (is_fluid(kinds_[i])) {
      report.external_impulse += external_accelerations_[i];
      report.body_impulse += p.gravity + c.driving;
    }
  }
  report.external_impulse *= particle_mass_ * dt;
  report.body_impulse *= particle_mass_ * dt;
  report.wall_viscous_force *= particle_mass_ * viscous_factor;
  for (int i = 0; i < n; ++i) {
    if (!position_star_[i].allFinite() || !velocity_star_[i].allFinite()) {
      throw StabilityError(step_ + 1, i, "velocity", "not finite after the explicit step");
    }
  }
}

// 2. Collision model (seed 001 eqs. (10), (11)): an approaching pair closer than d_c has its
// normal approach velocity V_r replaced by a repulsion (1 + C_c) V_r. V_r is the share of the
// relative normal velocity that the pair's mass ratio gives to particle i (all of it against a
// wall, half between two fluid particles), so fluid-fluid collisions conserve momentum.
// All corrections use the pre-collision velocities: order independent, thus deterministic.
void FluidSystem::collide(const StepConstants& c, StepReport& report) {
  if (!(c.collision_distance > 0.0)) return;
  const MpsParameters& p = parameters_;
  const int n = c.n;
  update_neighbours(position_star_, report);
  const NeighbourList& list = neighbours_;
  fill(correction_, n, kZero);
  fill(wall_correction_, n, kZero);
  fill(collided_, n, 0);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds_[i])) continue;
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const double r = list.distance[k];
      if (r >= c.collision_distance || r <= 0.0) continue;
      const int j = list.index[k];
      const Eigen::Vector3d normal = p.periodic.wrap(position_star_[j] - position_star_[i]) / r;
      const double approach = (velocity_star_[j] - velocity_star_[i]).dot(normal);
      if (approach >= 0.0) continue;
      const double share = is_fluid(kinds_[j]) ? 0.5 : 1.0;
      const Eigen::Vector3d change = (1.0 + p.collision_restitution) * share * approach * normal;
      correction_[i] += change;
      if (!is_fluid(kinds_[j])) wall_correction_[i] += change;
      ++collided_[i];
    }
  }
  collisions_refreshed_ = true;
  for (int i = 0; i < n; ++i) {
    if (collided_[i] == 0) continue;
    velocity_star_[i] += correction_[i];
    position_star_[i] += c.dt * correction_[i];
    report.collisions += collided_[i];
    report.collision_impulse += particle_mass_ * correction_[i];
    report.wall_collision_impulse += particle_mass_ * wall_correction_[i];
  }
}

// 3. Number density at r* (seed 001 eq. (7)), velocity divergence at r* with the density radius,
// and the unknowns: fluid and wall particles off the free surface (n* >= beta n0); dummy
// particles carry no pressure.
void FluidSystem::measure_density(const StepConstants& c, StepReport& report) {
  const MpsParameters& p = parameters_;
  const int n = c.n;
  // After the collision stage only the particles it moved need new distances.
  update_neighbours(position_star_, report, collisions_refreshed_ ? &collided_ : nullptr);
  collisions_refreshed_ = false;
  update_solid_fractions(position_star_);
  const NeighbourList& list = neighbours_;
  fill(number_densities_, n, 0.0);
  fill(divergence_, n, 0.0);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double sum = 0.0, divergence_sum = 0.0;
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const double r = list.distance[k];
      if (r >= c.re_n) continue;
      const int j = list.index[k];
      sum += weight(r, c.re_n);
      divergence_sum +=
          divergence_pair_term(velocity_star_[j] - velocity_star_[i],
                               p.periodic.wrap(position_star_[j] - position_star_[i]), r, c.re_n);
    }
    number_densities_[i] = sum;
    divergence_[i] = gradient_factor(c.d, c.n0_n) * divergence_sum;
  }
  fill(unknown_, n, -1);
  unknown_particle_.clear();
  for (int i = 0; i < n; ++i) {
    if (kinds_[i] == ParticleKind::dummy || is_inactive(kinds_[i])) continue;
    // Where solids take a share phi of the space, the fluid's full density is (1 - phi) n0.
    if (number_densities_[i] < p.surface_threshold * c.n0_n * (1.0 - solid_fraction_[i])) {
      ++report.surface_particles;
      continue;
    }
    unknown_[i] = static_cast<int>(unknown_particle_.size());
    unknown_particle_.push_back(i);
  }
  report.pressure_unknowns = static_cast<int>(unknown_particle_.size());
}

// 4. Pressure Poisson equation with the Laplacian model (seed 001 eq. (9)):
//    <lap p>_i - rho alpha p_i / dt^2 = -gamma rho / dt^2 (n*_i - n0) / n0,
// multiplied by -lambda n0 / (2d) so the matrix is symmetric positive definite:
//    sum_j w_ij (p_i - p_j) + c alpha p_i = c gamma (n*_i - n0) / n0,
//    c = lambda n0 rho / (2d dt^2);
// with the mixed source the right side is c (gamma (n^k_i - n0) / n0 - dt <div u*>_i).
void FluidSystem::assemble_pressure_equation(const StepConstants& c) {
  const MpsParameters& p = parameters_;
  const int m = static_cast<int>(unknown_particle_.size());
  const double scale = c.lambda * c.n0_l * p.density / (2.0 * c.d * c.dt * c.dt);
  assemble_laplacian_rows(c.re_l, scale * p.compressibility, matrix_);
  rhs_.resize(m);
  solution_.resize(m);
#pragma omp parallel for schedule(static) if (m >= 4096)
  for (int row = 0; row < m; ++row) {
    const int i = unknown_particle_[row];
    // Target (1 - phi_i) n0 (set_solid_volumes); the row keeps the n0 scaling so the matrix
    // stays symmetric. The divergence part has no d phi / dt term: with solids, the density
    // error is what pushes the displaced water away.
    const double target = c.n0_n * (1.0 - solid_fraction_[i]);
    rhs_[row] = p.source_term == MpsParameters::SourceTerm::density
                    ? scale * p.pressure_relaxation * (number_densities_[i] - target) / c.n0_n
                    : scale * (p.pressure_relaxation * (density_now_[i] - target) / c.n0_n -
                               c.dt * divergence_[i]);
    solution_[row] = pressures_[i];  // warm start from the previous step
  }
  if (pressure_solver_.uses_amg(m)) {
    // The multigrid hierarchy comes from the same equation with the short radius: a quarter of
    // the entries per row in 2D, so the set-up costs far less, and CG on the full matrix does
    // not care that its preconditioner approximates a slightly different Laplacian.
    const double hierarchy_scale = hierarchy_sums_.lambda_over_l0sq * p.particle_spacing *
                                   p.particle_spacing * hierarchy_sums_.n0 * p.density /
                                   (2.0 * c.d * c.dt * c.dt);
    assemble_laplacian_rows(hierarchy_radius(), hierarchy_scale * p.compressibility,
                            hierarchy_matrix_);
  }
}

// Rows sum_j w_ij (p_i - p_j) + shift p_i of the unknowns (Laplacian model of radius `radius`):
// Dirichlet neighbours (free surface, p = 0) only add to the diagonal; dummy particles are left
// out.
void FluidSystem::assemble_laplacian_rows(double radius, double diagonal_shift,
                                          SparseRows& matrix) {
  const NeighbourList& list = neighbours_;
  const int m = static_cast<int>(unknown_particle_.size());
  fill(row_length_, static_cast<std::size_t>(m) + 1, std::int64_t{0});
#pragma omp parallel for schedule(static) if (m >= 4096)
  for (int row = 0; row < m; ++row) {
    const int i = unknown_particle_[row];
    std::int64_t count = 1;
    for (int k = list.begin(i); k < list.end(i); ++k) {
      if (unknown_[list.index[k]] >= 0 && list.distance[k] < radius) ++count;
    }
    row_length_[row + 1] = count;
  }
  for (int row = 0; row < m; ++row) row_length_[row + 1] += row_length_[row];
  matrix.offset = row_length_;
  matrix.column.resize(row_length_[m]);
  matrix.value.resize(row_length_[m]);
#pragma omp parallel for schedule(static) if (m >= 4096)
  for (int row = 0; row < m; ++row) {
    const int i = unknown_particle_[row];
    std::int64_t slot = matrix.offset[row];
    const std::int64_t diagonal_slot = slot++;
    double diagonal = diagonal_shift;
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const int j = list.index[k];
      if (kinds_[j] == ParticleKind::dummy) continue;
      const double w = weight(list.distance[k], radius);
      if (w <= 0.0) continue;
      diagonal += w;
      if (unknown_[j] >= 0) {
        matrix.column[slot] = unknown_[j];
        matrix.value[slot] = -w;
        ++slot;
      }
    }
    // Zero weight exactly at r = radius was counted in the first pass when distance < radius.
    for (; slot < matrix.offset[row + 1]; ++slot) {
      matrix.column[slot] = row;
      matrix.value[slot] = 0.0;
    }
    matrix.column[diagonal_slot] = row;
    matrix.value[diagonal_slot] = diagonal;
  }
}

void FluidSystem::solve_pressure(StepReport& report) {
  const bool amg = pressure_solver_.uses_amg(matrix_.rows());
  const PcgResult pcg =
      pressure_solver_.solve(matrix_, rhs_, solution_, parameters_.pcg_tolerance,
                             parameters_.pcg_max_iterations, amg ? &hierarchy_matrix_ : nullptr);
  report.pcg_iterations = pcg.iterations;
  report.pcg_residual = pcg.relative_residual;
  report.pcg_converged = pcg.converged;
  // Negative pressures are clamped to zero: MPS has no tension (standard practice).
  fill(pressure_, static_cast<std::size_t>(particle_count()), 0.0);
  for (std::size_t row = 0; row < unknown_particle_.size(); ++row) {
    pressure_[unknown_particle_[row]] = std::max(0.0, solution_[row]);
  }
}

// 5. Pressure gradient (seed 000 eq. (2), radius re_g) with the minimum neighbour pressure p^_i
// in place of p_i (Koshizuka-Oka) so that inter-particle forces stay repulsive, or the symmetric
// pair form (MpsParameters::GradientForm), and the correction u' = -dt/rho <grad p>,
// r^{n+1} = r* + dt u'.
void FluidSystem::correct_with_pressure_gradient(const StepConstants& c, StepReport& report) {
  const MpsParameters& p = parameters_;
  const NeighbourList& list = neighbours_;
  const int n = c.n;
  const double factor = c.dt / p.density * gradient_factor(c.d, c.n0_g);
  const bool symmetric = p.gradient_form == MpsParameters::GradientForm::symmetric;
  fill(pressure_change_, n, kZero);
  fill(wall_pressure_change_, n, kZero);
  fill(minimum_, n, 0.0);  // p^_i
  if (!symmetric) {
#pragma omp parallel for schedule(static) if (n >= 4096)
    for (int i = 0; i < n; ++i) {
      if (!is_fluid(kinds_[i])) continue;
      double smallest = pressure_[i];
      for (int k = list.begin(i); k < list.end(i); ++k) {
        const int j = list.index[k];
        if (kinds_[j] != ParticleKind::dummy && list.distance[k] < c.re_g) {
          smallest = std::min(smallest, pressure_[j]);
        }
      }
      minimum_[i] = smallest;
    }
  }
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds_[i])) continue;
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero(), wall_gradient = Eigen::Vector3d::Zero();
    for (int k = list.begin(i); k < list.end(i); ++k) {
      const int j = list.index[k];
      const double r = list.distance[k];
      if (kinds_[j] == ParticleKind::dummy || r >= c.re_g) continue;
      const double difference =
          symmetric ? pressure_[i] + pressure_[j] : pressure_[j] - minimum_[i];
      const Eigen::Vector3d term = gradient_pair_term(
          difference, r, c.re_g, p.periodic.wrap(position_star_[j] - position_star_[i]));
      gradient += term;
      if (!is_fluid(kinds_[j])) wall_gradient += term;
    }
    // Applied below: the loop still reads the partners' r*. Among solids the neighbourhood is
    // (1 - phi) full, so the sum is normalised by (1 - phi) n0.
    const double local_factor = factor / (1.0 - solid_fraction_[i]);
    pressure_change_[i] = -local_factor * gradient;
    wall_pressure_change_[i] = -local_factor * wall_gradient;
  }
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    velocity_star_[i] += pressure_change_[i];
    position_star_[i] += c.dt * pressure_change_[i];
  }
  for (int i = 0; i < n; ++i) {  // serial sums: the same result with any thread count
    report.pressure_impulse += particle_mass_ * pressure_change_[i];
    report.wall_pressure_impulse += particle_mass_ * wall_pressure_change_[i];
  }
}

// The corrected state becomes r^{n+1}, u^{n+1}; periodic particles re-enter at x_min (seed 001
// fig. 2.4 (2)). The point forces stay for the next step of the same window (set_point_forces).
void FluidSystem::finish_step(const StepConstants& c, StepReport& report) {
  const int n = c.n;
  std::swap(positions_, position_star_);
  std::swap(velocities_, velocity_star_);
  std::swap(pressures_, pressure_);
  if (parameters_.periodic.enabled) {
    for (int i = 0; i < n; ++i) positions_[i] = parameters_.periodic.fold(positions_[i]);
  }
  time_ += c.dt;
  step_ += 1;
  for (int i = 0; i < n; ++i) {
    if (is_fluid(kinds_[i])) report.max_speed = std::max(report.max_speed, velocities_[i].norm());
  }
  check_stability(step_);
}

}  // namespace cosim::mps

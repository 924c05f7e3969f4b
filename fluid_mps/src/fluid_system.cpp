#include "cosim/fluid_mps/fluid_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/operators.hpp"
#include "cosim/fluid_mps/pressure_solver.hpp"

// Loops run in parallel from 4096 items on (the `if` clauses below): under that the OpenMP
// fork/join costs more than the work, and oversubscribed CI cores make it far worse.
namespace cosim::mps {

void validate_parameters(const MpsParameters& p) {
  scenario::check_parameters(p, "MpsParameters");
  // The seam is set by the scene builders, not by a key.
  if (p.periodic.enabled && p.periodic.length() < 3.0 * largest_influence_radius(p)) {
    throw scenario::ParameterError(
        "MpsParameters", "periodic",
        "the period must be at least three times the largest influence radius");
  }
  if (p.fill_lattice == MpsParameters::FillLattice::fcc && p.dimension != 3) {
    throw scenario::ParameterError("MpsParameters", "fill_lattice",
                                   "fcc is a 3D lattice (dimension = 3)");
  }
}

LatticeSums fill_lattice_sums(const MpsParameters& p, double radius_over_l0) {
  if (p.fill_lattice == MpsParameters::FillLattice::fcc) {
    return fcc_lattice_sums(radius_over_l0, p.fill_stretch);
  }
  return lattice_sums(p.dimension, radius_over_l0);
}

double fill_volume_per_particle(const MpsParameters& p) {
  const double cell = std::pow(p.particle_spacing, p.dimension);
  if (p.fill_lattice == MpsParameters::FillLattice::fcc) return cell * p.fill_stretch.prod();
  return cell;
}

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
  pressure_solver_.restore_setup(state.pressure_setup);
}

void FluidSystem::initialise() {
  validate_parameters(parameters_);
  const std::size_t n = positions_.size();
  if (kinds_.size() != n || velocities_.size() != n) {
    throw std::invalid_argument("FluidSystem: positions, kinds and velocities differ in size");
  }
  const MpsParameters& p = parameters_;
  const double l0 = p.particle_spacing;
  density_sums_ = fill_lattice_sums(p, p.radius_density_over_l0);
  gradient_sums_ = fill_lattice_sums(p, p.radius_gradient_over_l0);
  laplacian_sums_ = fill_lattice_sums(p, p.radius_laplacian_over_l0);
  hierarchy_sums_ = fill_lattice_sums(p, hierarchy_radius() / l0);
  particle_mass_ = p.density * fill_volume_per_particle(p);
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
  using Kind = MpsParameters::PressurePreconditioner;
  switch (p.pressure_preconditioner) {
    case Kind::jacobi:
      pressure_solver_ = PressureSolver(Preconditioner::jacobi);
      break;
    case Kind::incomplete_cholesky:
      pressure_solver_ = PressureSolver(Preconditioner::incomplete_cholesky);
      break;
    case Kind::amg:
      pressure_solver_ = PressureSolver(Preconditioner::amg);
      break;
    case Kind::aggregation:
      pressure_solver_ = PressureSolver(Preconditioner::aggregation);
      break;
    case Kind::automatic:
      pressure_solver_ =
          PressureSolver(Preconditioner::automatic,
                         p.dimension == 3 ? kAggregationFromUnknowns3d : kAggregationFromUnknowns);
      break;
  }
  pressure_solver_.set_single_precision_product(p.single_precision_product);
  pressure_solver_.set_setup_reuse(p.pressure_setup_reuse);
  using Product = MpsParameters::PressureProduct;
  pressure_solver_.set_upper_triangle_product(
      p.pressure_product == Product::upper_triangle ||
      (p.pressure_product == Product::automatic && p.dimension == 3));
  StepReport unused;
  gather_state();
  update_neighbours(x_, unused, true);
  const double re = p.radius_density_over_l0 * l0;
  find_near_pairs(x_, re);
  number_densities_.assign(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    double sum = 0.0;
    for (std::int64_t pair = near_.offset[k]; pair < near_end_[k]; ++pair) {
      sum += weight(near_.distance[pair], re);
    }
    number_densities_[order_[k]] =
        kind_[k] == ParticleKind::dummy ? std::numeric_limits<double>::quiet_NaN() : sum;
  }
}

double FluidSystem::hierarchy_radius() const {
  return std::min(parameters_.multigrid_radius_over_l0, parameters_.radius_laplacian_over_l0) *
         parameters_.particle_spacing;
}

double FluidSystem::lambda_laplacian() const {
  const double l0 = parameters_.particle_spacing;
  return laplacian_sums_.lambda_over_l0sq * l0 * l0;
}

double FluidSystem::max_fluid_speed() const {
  double max_speed = 0.0;
  const int n = particle_count();
#pragma omp parallel for schedule(static) reduction(max : max_speed) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (is_fluid(kinds_[i])) max_speed = std::max(max_speed, velocities_[i].norm());
  }
  return max_speed;
}

double FluidSystem::stable_dt() const {
  const MpsParameters& p = parameters_;
  const double l0 = p.particle_spacing;
  const double max_speed = max_fluid_speed();
  double dt = p.max_dt;
  if (max_speed > 0.0) dt = std::min(dt, p.courant * l0 / max_speed);
  if (p.kinematic_viscosity > 0.0) {
    dt = std::min(dt, p.diffusion_number * l0 * l0 / p.kinematic_viscosity);
  }
  return dt;
}

// The first particle (in index order) that fails a check is found in parallel, so the error is
// the one a serial scan would throw first.
void FluidSystem::check_stability(long step) const {
  const int n = particle_count();
  int first = n;
#pragma omp parallel for schedule(static) reduction(min : first) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (instability(step, i)) first = std::min(first, i);
  }
  if (first < n) throw *instability(step, first);
}

// The error of particle i's first failing check, in the order the checks are listed; none if
// it passes them all.
std::optional<StabilityError> FluidSystem::instability(long step, int i) const {
  if (is_inactive(kinds_[i])) return std::nullopt;  // pooled by the open boundaries
  const Eigen::Vector3d& x = positions_[i];
  const Eigen::Vector3d& u = velocities_[i];
  if (!x.allFinite()) return StabilityError(step, i, "position", "not finite");
  if (!u.allFinite()) return StabilityError(step, i, "velocity", "not finite");
  if (!std::isfinite(pressures_[i])) return StabilityError(step, i, "pressure", "not finite");
  bool inside = true;
  for (int axis = 0; axis < (parameters_.dimension == 2 ? 2 : 3); ++axis) {
    inside = inside && x[axis] >= domain_box_.min()[axis] && x[axis] <= domain_box_.max()[axis];
  }
  if (!inside) {
    std::ostringstream detail;
    detail << "escaped the domain box at (" << x.x() << ", " << x.y() << ", " << x.z() << ")";
    return StabilityError(step, i, "position", detail.str());
  }
  const double speed = u.norm();
  if (speed > parameters_.runaway_speed) {
    std::ostringstream detail;
    detail << "speed " << speed << " m/s exceeds runaway_speed " << parameters_.runaway_speed;
    return StabilityError(step, i, "velocity", detail.str());
  }
  return std::nullopt;
}

void FluidSystem::set_particle(int i, ParticleKind kind, const Eigen::Vector3d& position,
                               const Eigen::Vector3d& velocity) {
  if (i < 0 || i >= particle_count()) throw std::out_of_range("set_particle: bad index");
  // The pair list stays valid (gather_state parks inactive particles out of reach, and the skin
  // test catches a particle that enters) unless a dummy is involved: dummies have no rows.
  if (kind == ParticleKind::dummy || kinds_[i] == ParticleKind::dummy) neighbours_valid_ = false;
  ++state_generation_;  // the coupling hooks' kept grid (point_grid) is out of date
  kinds_[i] = kind;
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
  return MpsState{
      positions_, velocities_, pressures_, kinds_, time_, step_, pressure_solver_.setup_state()};
}

}  // namespace cosim::mps

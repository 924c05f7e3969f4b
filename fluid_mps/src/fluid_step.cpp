// The semi-implicit MPS step (Koshizuka-Oka; seed 000 section 2(1), seed 001 section 2) as a list
// of stages: predict, collide, measure density, assemble and solve the pressure equation
// (pressure_equation.cpp), correct. All stages share one pair list (update_neighbours) and the
// work arrays of the system.
#include <algorithm>
#include <cmath>
#include <limits>

#include <omp.h>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/hydrostatic_background.hpp"
#include "cosim/fluid_mps/operators.hpp"
#include "cosim/fluid_mps/pressure_gradient.hpp"
#include "particle_loops.hpp"
#include "step_constants.hpp"

// Loops run in parallel from 4096 items on (the `if` clauses below): under that the OpenMP
// fork/join costs more than the work, and oversubscribed CI cores make it far worse.
namespace cosim::mps {
namespace {

const Eigen::Vector3d kZero = Eigen::Vector3d::Zero();

// visit(j, r) for the partners j of i in `list` closer than about `cutoff` at x, in list order
// (the stages compare r with their radii): distances computed here, not stored, for a stage
// that is their only user.
template <class Visit>
void visit_partners(const NeighbourList& list, const std::vector<Eigen::Vector3d>& x,
                    const PeriodicBoundary& periodic, int i, double cutoff, Visit&& visit) {
  const double cutoff2 = cutoff * cutoff * (1.0 + 1e-12);  // as FluidSystem::near_cutoff2
  const Eigen::Vector3d xi = x[i];
  const int* index = list.index.data();
  const Eigen::Vector3d* position = x.data();
  const int begin = list.begin(i), end = list.end(i);
  if (periodic.enabled) {
    for (int k = begin; k < end; ++k) {
      const int j = index[k];
      const double r2 = periodic.wrap(position[j] - xi).squaredNorm();
      if (r2 <= cutoff2) visit(j, std::sqrt(r2));
    }
    return;
  }
  // The same distances without the periodic test in the loop.
  for (int k = begin; k < end; ++k) {
    const int j = index[k];
    const double r2 = (position[j] - xi).squaredNorm();
    if (r2 <= cutoff2) visit(j, std::sqrt(r2));
  }
}

}  // namespace

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
  c.wall_collision_distance = p.wall_collision_factor * c.collision_distance;
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
  StageSeconds& seconds = report.stage_seconds;
  // Each stage's wall time, less the neighbour search it ran (update_neighbours books that).
  auto mark = StageClock::now();
  double searched = 0.0;
  auto lap = [&](double& stage) {
    const auto now = StageClock::now();
    stage += seconds_between(mark, now) - (seconds.search - searched);
    searched = seconds.search;
    mark = now;
  };
  predict(c, report);
  lap(seconds.explicit_part);
  collide(c, report);
  lap(seconds.collision);
  measure_density(c, report);
  lap(seconds.density);
  assemble_pressure_equation(c);
  lap(seconds.assembly);
  solve_pressure(report);
  lap(seconds.pressure_solve);
  seconds.pressure_solve -= seconds.pressure_setup;  // set by solve_pressure
  correct_with_pressure_gradient(c, report);
  lap(seconds.correction);
  finish_step(c, report);
  lap(seconds.finish);
  return report;
}

// 1. Explicit part at r^n: viscosity (seed 000 eq. (3)), gravity, driving and point forces;
// also the number density at r^n for the density-error part of the mixed source term.
void FluidSystem::predict(const StepConstants& c, StepReport& report) {
  const MpsParameters& p = parameters_;
  const int n = c.n;
  const double dt = c.dt;
  gather_state();
  update_neighbours(x_, report, true);
  const bool masked = !p.partitions.empty();
  // n^k only enters the mixed source term; without it walls and dummies have nothing to sum.
  const bool mixed = p.source_term == MpsParameters::SourceTerm::mixed;
  const double cutoff = mixed ? std::max(c.re_n, c.re_l) : c.re_l;
  if (masked) find_near_pairs(x_, cutoff);  // measure_density finds them again at r*
  const double cutoff2 = near_cutoff2(cutoff);
  const double viscous_factor = p.kinematic_viscosity * laplacian_factor(c.d, c.n0_l, c.lambda);
  // Sized here, set in the loop (one pass over the particles instead of four).
  density_now_.resize(n);
  velocity_star_.resize(n);
  position_star_.resize(n);
  wall_viscous_.resize(n);
  if (pair_rows_.size() < static_cast<std::size_t>(omp_get_max_threads()))
    pair_rows_.resize(omp_get_max_threads());
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    velocity_star_[i] = u_[i];
    position_star_[i] = x_[i];
    density_now_[i] = 0.0;
    wall_viscous_[i] = kZero;
    if (is_inactive(kind_[i])) continue;
    double density_sum = 0.0;
    Eigen::Vector3d laplacian = Eigen::Vector3d::Zero();
    const bool fluid = is_fluid(kind_[i]);
    if (!fluid && !mixed) {
      position_star_[i] += dt * velocity_star_[i];
      continue;
    }
    Eigen::Vector3d wall_laplacian = Eigen::Vector3d::Zero();  // the walls' share of it
    const Eigen::Vector3d ui = u_[i];
    auto pair = [&](int j, double r) {
      if (mixed) density_sum += weight(r, c.re_n);  // zero from re_n on: no branch on r
      if (!fluid || r >= c.re_l) return;
      const Eigen::Vector3d term = (u_[j] - ui) * weight(r, c.re_l);
      laplacian += term;
      if (!is_fluid(kind_[j])) wall_laplacian += term;
    };
    if (masked) {
      for (std::int64_t k = near_.offset[i]; k < near_end_[i]; ++k) {
        pair(near_.index[k], near_.distance[k]);
      }
    } else {
      // Without partitions the row is found here: its distances in one branch-free pass, then
      // the sums over the pairs in reach, in list order. No later stage reads the pairs at r^n,
      // so they go to the thread's own row (in L1), not to near_ (11 MB a step in
      // honami_field, written and never read back from there).
      PairRow& row = pair_rows_[omp_get_thread_num()];
      const std::size_t room = static_cast<std::size_t>(neighbours_.end(i) - neighbours_.begin(i));
      if (row.index.size() < room) {
        row.index.resize(room);
        row.distance.resize(room);
      }
      const std::int64_t count = find_row(i, x_, cutoff2, row.index.data(), row.distance.data());
      for (std::int64_t k = 0; k < count; ++k) pair(row.index[k], row.distance[k]);
    }
    density_now_[i] = density_sum;
    wall_viscous_[i] = wall_laplacian;
    if (fluid) {
      velocity_star_[i] +=
          dt * (viscous_factor * laplacian + p.gravity + c.driving + acceleration_[i]);
    }
    position_star_[i] += dt * velocity_star_[i];
  }
  for (int id = 0; id < n; ++id) {  // particle order: the same sums in any internal order
    const int i = rank_[id];
    report.wall_viscous_force += wall_viscous_[i];
    if (is_fluid(kind_[i])) {
      report.external_impulse += acceleration_[i];
      report.body_impulse += p.gravity + c.driving;
    }
  }
  report.external_impulse *= particle_mass_ * dt;
  report.body_impulse *= particle_mass_ * dt;
  report.wall_viscous_force *= particle_mass_ * viscous_factor;
  // The first particle id (not internal index) that is not finite, found in parallel.
  int first = n;
#pragma omp parallel for schedule(static) reduction(min : first) if (n >= 4096)
  for (int id = 0; id < n; ++id) {
    const int i = rank_[id];
    if (!position_star_[i].allFinite() || !velocity_star_[i].allFinite())
      first = std::min(first, id);
  }
  if (first < n) {
    throw StabilityError(step_ + 1, first, "velocity", "not finite after the explicit step");
  }
}

// 2. Collision model (seed 001 eqs. (10), (11)): an approaching pair closer than d_c has its
// normal approach velocity V_r replaced by a repulsion (1 + C_c) V_r. V_r is the share of the
// relative normal velocity that the pair's mass ratio gives to particle i (all of it against a
// wall, half between two fluid particles), so fluid-fluid collisions conserve momentum.
// All corrections use the pre-collision velocities: order independent, thus deterministic.
void FluidSystem::collide(const StepConstants& c, StepReport& report) {
  const double reach = std::max(c.collision_distance, c.wall_collision_distance);
  if (!(reach > 0.0)) return;
  const MpsParameters& p = parameters_;
  const int n = c.n;
  update_neighbours(position_star_, report);
  const bool masked = !p.partitions.empty();
  if (masked) find_near_pairs(position_star_, reach);
  fill(correction_, n, kZero);
  fill(wall_correction_, n, kZero);
  fill(collided_, n, 0);
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kind_[i])) continue;
    auto pair = [&](int j, double r) {
      const double limit = is_fluid(kind_[j]) ? c.collision_distance : c.wall_collision_distance;
      if (r >= limit || r <= 0.0) return;
      const Eigen::Vector3d normal = p.periodic.wrap(position_star_[j] - position_star_[i]) / r;
      const double approach = (velocity_star_[j] - velocity_star_[i]).dot(normal);
      if (approach >= 0.0) return;
      const double share = is_fluid(kind_[j]) ? 0.5 : 1.0;
      const Eigen::Vector3d change = (1.0 + p.collision_restitution) * share * approach * normal;
      correction_[i] += change;
      if (!is_fluid(kind_[j])) wall_correction_[i] += change;
      ++collided_[i];
    };
    if (masked) {
      for (std::int64_t k = near_.offset[i]; k < near_end_[i]; ++k) {
        pair(near_.index[k], near_.distance[k]);
      }
    } else {
      visit_partners(neighbours_, position_star_, p.periodic, i, reach, pair);
    }
  }
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (collided_[i] == 0) continue;
    velocity_star_[i] += correction_[i];
    position_star_[i] += c.dt * correction_[i];
  }
  for (int id = 0; id < n; ++id) {  // particle order: the same sums in any internal order
    const int i = rank_[id];
    if (collided_[i] == 0) continue;
    report.collisions += collided_[i];
    report.collision_impulse += particle_mass_ * correction_[i];
    report.wall_collision_impulse += particle_mass_ * wall_correction_[i];
  }
}

// 3. Number density at r* (seed 001 eq. (7)), velocity divergence at r* with the density radius,
// and the unknowns: fluid and wall particles off the free surface (n* >= beta n0); dummy
// particles carry no pressure. The pairs within the stage radii at r* (near_) serve the rest of
// the step.
void FluidSystem::measure_density(const StepConstants& c, StepReport& report) {
  const MpsParameters& p = parameters_;
  const int n = c.n;
  update_neighbours(position_star_, report);
  const double cutoff = std::max({c.re_n, c.re_g, c.re_l});
  // Without partitions each row is found and summed in one go, while it is in cache.
  const bool fused = p.partitions.empty();
  if (!fused) find_near_pairs(position_star_, cutoff);
  near_.radius = cutoff;
  const double cutoff2 = near_cutoff2(cutoff);
  update_phi();
  const NeighbourList& list = near_;
  const bool mixed = p.source_term == MpsParameters::SourceTerm::mixed;
  fill(density_star_, n, 0.0);
  fill(divergence_, n, 0.0);
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (fused) find_near_row(i, position_star_, cutoff2, false);
    double sum = 0.0, divergence_sum = 0.0;
    const std::int64_t begin = list.offset[i], end = near_end_[i];
    if (!mixed) {
      // weight() is zero from re_n on: every pair summed, no branch on r (the same sum).
      for (std::int64_t k = begin; k < end; ++k) sum += weight(list.distance[k], c.re_n);
    } else {
      for (std::int64_t k = begin; k < end; ++k) {
        const double r = list.distance[k];
        if (r >= c.re_n) continue;
        sum += weight(r, c.re_n);
        // The divergence only enters the mixed source term.
        const int j = list.index[k];
        divergence_sum +=
            divergence_pair_term(velocity_star_[j] - velocity_star_[i],
                                 p.periodic.wrap(position_star_[j] - position_star_[i]), r, c.re_n);
      }
    }
    density_star_[i] = sum;
    divergence_[i] = gradient_factor(c.d, c.n0_n) * divergence_sum;
  }
  unknown_particle_.clear();
  for (int id = 0; id < n; ++id) {  // in particle order, then along space
    const int i = rank_[id];
    if (kind_[i] == ParticleKind::dummy || is_inactive(kind_[i])) continue;
    // Where solids take a share phi of the space, the fluid's full density is (1 - phi) n0.
    if (density_star_[i] < p.surface_threshold * c.n0_n * (1.0 - phi_[i])) {
      ++report.surface_particles;
      continue;
    }
    unknown_particle_.push_back(i);
  }
  // Rows of neighbours near in number, so that the full rows' product gathers x and the
  // assembly reads the pair lists from cache; the cells are the Laplacian's reach, the matrix's
  // stencil. Not with the upper triangle's product: its windows of fixed blocks cost more on
  // these rows than on the filled lattice's id order (docs/performance.md).
  if (!pressure_solver_.upper_triangle_product()) {
    order_along_cells(position_star_, c.re_l, p.dimension, unknown_particle_, unknown_order_work_);
  }
  fill(unknown_, n, -1);
  for (std::size_t row = 0; row < unknown_particle_.size(); ++row)
    unknown_[unknown_particle_[row]] = static_cast<int>(row);
  report.pressure_unknowns = static_cast<int>(unknown_particle_.size());
}

// phi at r* (solid_volume.cpp works in particle order), then in the internal order.
void FluidSystem::update_phi() {
  const int n = particle_count();
  if (solid_points_.empty()) {
    update_solid_fractions(positions_);  // zeros; the positions are not read
    fill(phi_, static_cast<std::size_t>(n), 0.0);
    return;
  }
  scratch_.resize(n);
  for (int k = 0; k < n; ++k) scratch_[order_[k]] = position_star_[k];
  update_solid_fractions(scratch_);
  phi_.resize(n);
  for (int k = 0; k < n; ++k) phi_[k] = solid_fraction_[order_[k]];
}

// Hydrostatic background at r* for the correction (pressure_background: hydrostatic;
// hydrostatic_background.hpp), faded in over the gradient radius below the surface: there the
// operator keeps carrying the surface particles' weight, as without the background
// (docs/validation.md: with no fade-in the top particles float on the background and still water
// reads 14 % low 5 cm down).
void FluidSystem::measure_background() {
  const MpsParameters& p = parameters_;
  BackgroundInput b;
  b.dimension = p.dimension;
  b.gravity = p.gravity;
  b.density = p.density;
  b.particle_spacing = p.particle_spacing;
  b.taper_depth = p.radius_gradient_over_l0 * p.particle_spacing;
  b.fade_depth = p.background_fade_depth_over_re * b.taper_depth;
  b.blend_fade = p.background_fade == MpsParameters::BackgroundFade::blend;
  b.positions = &position_star_;
  b.kinds = &kind_;
  b.periodic = &p.periodic;
  hydrostatic_background(b, background_);
}

// 5. Pressure gradient (seed 000 eq. (2), radius re_g) by MpsParameters::GradientForm
// (pressure_gradient.cpp; by default the minimum form of Koshizuka-Oka, whose neighbour minimum
// p^_i keeps the pair forces repulsive) on the pairs at r* (near_), and the correction
// u' = -dt/rho <grad p>, r^{n+1} = r* + dt u'; then particle shifting if it is switched on.
void FluidSystem::correct_with_pressure_gradient(const StepConstants& c, StepReport& report) {
  const MpsParameters& p = parameters_;
  const int n = c.n;
  const double factor = c.dt / p.density * gradient_factor(c.d, c.n0_g);
  GradientInput in;
  in.dimension = c.d;
  in.radius = c.re_g;
  in.n0 = c.n0_g;
  in.neighbours = &near_;
  in.row_end = &near_end_;
  in.positions = &position_star_;
  in.kinds = &kind_;
  in.pressure = &pressure_;
  in.periodic = &p.periodic;
  in.unknown = &unknown_;
  in.surface_threshold = p.surface_threshold;
  in.solid_fraction = &phi_;
  const bool background = p.pressure_background == MpsParameters::PressureBackground::hydrostatic;
  if (background) {
    // S (<grad q> + grad p_b) + (1 - S) <grad p>, q = p - p_b: each estimate only where its weight
    // is not zero (with S = 1 everywhere, as in rigid_canopy, the second costs nothing).
    measure_background();
    dynamic_pressure_.resize(n);
    trusted_.resize(n);
    untrusted_.resize(n);
#pragma omp parallel for schedule(static) if (n >= 4096)
    for (int i = 0; i < n; ++i) {
      dynamic_pressure_[i] = pressure_[i] - background_.pressure[i];
      trusted_[i] = background_.trust[i] > 0.0;
      untrusted_[i] = background_.trust[i] < 1.0;
    }
    in.pressure = &dynamic_pressure_;
    pressure_gradients(p.gradient_form, in, pressure_change_, wall_pressure_change_, minimum_,
                       &trusted_);
    if (p.background_repulsion == MpsParameters::BackgroundRepulsion::full) {
      add_full_pressure_repulsion(p.gradient_form, in, minimum_, pressure_, background_.fade,
                                  &trusted_, pressure_change_, wall_pressure_change_,
                                  full_minimum_);
    }
    if (p.background_replaces == MpsParameters::BackgroundReplaces::layer_mean) {
      // Into the trusted estimate (weighed by S below), booked with the fluid's own pressure:
      // a layer's deviations sum to zero, walls' partners included. Layers l0 / 2 of depth.
      const double layer = p.density * p.gravity.norm() * 0.5 * p.particle_spacing;  // [Pa]
      keep_layer_deviation(p.gradient_form, in, background_.pressure, layer, trusted_, rank_,
                           background_taylor_, pressure_change_);
    }
    in.pressure = &pressure_;
    pressure_gradients(p.gradient_form, in, untrusted_change_, untrusted_wall_change_, minimum_,
                       &untrusted_);
  } else {
    pressure_gradients(p.gradient_form, in, pressure_change_, wall_pressure_change_, minimum_);
  }
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kind_[i])) continue;
    // Among solids the neighbourhood is (1 - phi) full, so the sum is normalised by (1 - phi) n0.
    const double local_factor = factor / (1.0 - phi_[i]);
    if (background) {
      const double trusted = background_.trust[i], untrusted = 1.0 - trusted;
      pressure_change_[i] = trusted * pressure_change_[i] + untrusted * untrusted_change_[i];
      wall_pressure_change_[i] =
          trusted * wall_pressure_change_[i] + untrusted * untrusted_wall_change_[i];
    }
    pressure_change_[i] = -local_factor * pressure_change_[i];
    wall_pressure_change_[i] = -local_factor * wall_pressure_change_[i];
    // The background's own gradient is exact: no neighbourhood to normalise. It is booked with
    // the fluid's pressure, not the walls' (it is the water column's weight).
    if (background)
      pressure_change_[i] -= c.dt / p.density * background_.trust[i] * background_.gradient[i];
  }
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    velocity_star_[i] += pressure_change_[i];
    position_star_[i] += c.dt * pressure_change_[i];
  }
  for (int id = 0; id < n; ++id) {  // serial sums in particle order: the same bits always
    const int i = rank_[id];
    report.pressure_impulse += particle_mass_ * pressure_change_[i];
    report.wall_pressure_impulse += particle_mass_ * wall_pressure_change_[i];
  }
  if (p.shifting_coefficient > 0.0) {
    // The concentration gradient at the corrected positions, over the density radius; the
    // pairs found again there (with the partition mask).
    update_neighbours(position_star_, report);
    find_near_pairs(position_star_, c.re_n);
    in.radius = c.re_n;
    in.n0 = c.n0_n;
    const bool taylor = p.shifted_velocity == MpsParameters::ShiftedVelocity::taylor;
    if (taylor) unshifted_velocity_ = velocity_star_;
    ShiftingOptions shifting;
    shifting.coefficient = p.shifting_coefficient;
    shifting.dt = c.dt;
    shifting.particle_spacing = p.particle_spacing;
    shifting.max_shift = 0.1 * p.particle_spacing;
    shifting.taylor = taylor;
    shifting.tangential_at_walls =
        p.shifting_near_walls == MpsParameters::ShiftingNearWalls::tangential;
    shift_particles(in, velocity_star_, unknown_, shifting, position_star_);
    if (taylor) {
      for (int id = 0; id < n; ++id) {  // particle order: the same bits always
        const int i = rank_[id];
        report.shifting_impulse += particle_mass_ * (velocity_star_[i] - unshifted_velocity_[i]);
      }
    }
  }
}

// The corrected state becomes r^{n+1}, u^{n+1}; periodic particles re-enter at x_min (seed 001
// fig. 2.4 (2)). The point forces stay for the next step of the same window (set_point_forces).
void FluidSystem::finish_step(const StepConstants& c, StepReport& report) {
  const int n = c.n;
  scatter_state();
  if (parameters_.periodic.enabled) {
#pragma omp parallel for schedule(static) if (n >= 4096)
    for (int i = 0; i < n; ++i) positions_[i] = parameters_.periodic.fold(positions_[i]);
  }
  report.max_speed = max_fluid_speed();
  time_ += c.dt;
  step_ += 1;
  check_stability(step_);
}

}  // namespace cosim::mps

// The sub-cycled implicit Newmark step of the plant field (seed eq. 22-23): initial
// accelerations, Newton iterations of a sub-step with their corrections, cutbacks, and the
// window's sub-steps with the drag impulse.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <omp.h>

#include "beam_elements.hpp"
#include "cosim/vegetation_beam/banded_matrix.hpp"
#include "cosim/vegetation_beam/plant_field.hpp"
#include "newmark_constants.hpp"
#include "plant_messages.hpp"

namespace cosim::vegetation {
namespace {

constexpr int kHalfBandwidth = 8;  // 3 dofs per node, bending couples neighbours two apart
// A sub-step whose Newton attempts both fail is halved, at most this often (down to 1/64).
constexpr int kMaxCutbacks = 6;

}  // namespace

void PlantField::initialise_accelerations(const std::vector<Eigen::Vector3d>& ambient) {
  const bool contact = plants_may_touch() && !parameters_.rigid;
  if (contact) {
    update_contact_candidates();
    compute_contact_forces(positions_, velocities_, true);
  }
  for (int p = 0; p < plant_count(); ++p) {
    compute_forces(p, positions_, velocities_, ambient, contact, forces_, drag_, nullptr, 0, 0);
    const Plant& plant = plants_[p];
    accelerations_[plant.first].setZero();
    for (int i = 1; i <= plant.links; ++i) {
      const int node = plant.first + i;
      accelerations_[node] = parameters_.rigid ? Eigen::Vector3d::Zero().eval()
                                               : (forces_[node] / node_mass_[node]).eval();
    }
  }
  accelerations_valid_ = true;
}

PlantField::Correction PlantField::apply_newton_correction(
    int plant_index, BandedMatrix& jacobian, const std::vector<Eigen::Vector3d>& residual,
    bool factorize, std::vector<double>& correction) {
  const Plant& plant = plants_[plant_index];
  Correction result;
  int failed_row = 0;
  if (factorize && !jacobian.factorize(&failed_row)) {
    result.singular = true;
    result.largest = std::numeric_limits<double>::infinity();
    result.node = failed_row / 3 + 1;
    return result;
  }
  correction.resize(3 * plant.links);
  for (int i = 1; i <= plant.links; ++i)
    for (int d = 0; d < 3; ++d) correction[3 * (i - 1) + d] = -residual[plant.first + i][d];
  jacobian.solve(correction);
  double largest = 0;
  for (int i = 1; i <= plant.links; ++i) {
    const Eigen::Vector3d dx(correction[3 * (i - 1)], correction[3 * (i - 1) + 1],
                             correction[3 * (i - 1) + 2]);
    positions_[plant.first + i] += dx;
    // std::max drops NaN, so a non-finite correction is caught explicitly.
    const double size =
        dx.allFinite() ? dx.cwiseAbs().maxCoeff() : std::numeric_limits<double>::infinity();
    if (size > largest || (i == 1 && size == largest)) {
      largest = size;
      result.node = i;
    }
  }
  result.largest = largest / plant.link_length;
  return result;
}

void PlantField::locate_largest_residual(const std::vector<char>& converged,
                                         NewtonOutcome& outcome) const {
  outcome.residual = -1;
  for (int p = 0; p < plant_count(); ++p) {
    if (converged[p]) continue;
    const Plant& plant = plants_[p];
    for (int i = 1; i <= plant.links; ++i) {
      const Eigen::Vector3d& r = residual_[plant.first + i];
      const double size = r.allFinite() ? r.norm() : std::numeric_limits<double>::infinity();
      if (size > outcome.residual) {
        outcome.residual = size;
        outcome.plant = p;
        outcome.node = i;
      }
    }
  }
}

void PlantField::newmark_kinematics(double dt, double mass_weight) {
  for (const Plant& plant : plants_) newmark_kinematics_of(plant, dt, mass_weight);
}

void PlantField::newmark_kinematics_of(const Plant& plant, double dt, double mass_weight) {
  // Newmark relations (eq. 22-23) give acceleration and velocity from the trial position.
  for (int k = plant.first + 1; k <= plant.first + plant.links; ++k) {
    if (node_mass_[k] == 0) continue;
    accelerations_[k] =
        (positions_[k] - previous_positions_[k] - dt * previous_velocities_[k]) * mass_weight -
        (0.5 / kBeta - 1.0) * previous_accelerations_[k];
    velocities_[k] = previous_velocities_[k] +
                     dt * ((1 - kGamma) * previous_accelerations_[k] + kGamma * accelerations_[k]);
  }
  accelerations_[plant.first].setZero();  // clamped base
  velocities_[plant.first].setZero();
}

// One Newton iteration of one plant: its residual, the Jacobian when due, and the correction.
bool PlantField::newton_iteration(int p, const NewtonSweep& sweep, NewtonProgress& progress,
                                  std::vector<double>& scratch) {
  if (progress.converged[p] && !plant_in_contact_[p]) return false;
  // Gauss-Seidel across plants: contact forces see the partners already corrected in this
  // iteration, which halves the iterations of densely touching plants against Jacobi.
  if (sweep.contact && sweep.iteration > 1 && plant_in_contact_[p])
    refresh_contact_forces(p, sweep.dt);
  const Plant& plant = plants_[p];
  // Modified Newton: the Jacobian of the first iteration is kept for the sub-step (later
  // iterations mostly resolve plant-to-plant contact, which it treats per node anyway), and
  // over the window's later sub-steps of the same length for a plant out of contact: the mass
  // term 1 / (beta dt^2) dominates it, and the shape changes little in a sub-step.
  const bool in_contact = sweep.contact && plant_in_contact_[p];
  if (sweep.iteration == 1)
    progress.kept[p] = sweep.reuse && !in_contact && jacobian_dt_[p] == sweep.dt;
  const bool factorize = (sweep.iteration == 1 && !progress.kept[p]) || progress.refresh[p];
  BandedMatrix& jacobian = jacobians_[p];
  if (factorize) {
    progress.kept[p] = 0;
    jacobian.resize(3 * plant.links, kHalfBandwidth);
  }
  compute_forces(p, positions_, velocities_, *sweep.ambient, sweep.contact, forces_, drag_,
                 factorize ? &jacobian : nullptr, 1.0, sweep.damping_weight, sweep.robust);
  for (int i = 1; i <= plant.links; ++i) {
    const int k = plant.first + i;
    residual_[k] = node_mass_[k] * accelerations_[k] - forces_[k];
    if (!factorize) continue;
    for (int d = 0; d < 3; ++d)
      jacobian.add_diagonal(3 * (i - 1) + d, node_mass_[k] * sweep.mass_weight);
  }
  const Correction correction = apply_newton_correction(p, jacobian, residual_, factorize, scratch);
  progress.corrections[p] = correction;
  if (factorize) {
    const bool keepable = !sweep.robust && !in_contact && !correction.singular;
    jacobian_dt_[p] = keepable ? sweep.dt : 0.0;
  }
  // Robust attempt, or a Jacobian kept from an earlier sub-step: a correction that did not fall
  // by 4 means the kept Jacobian is too far from the current one; refactorise at the next
  // iteration (contact-free plants only: contact iterations converge by Gauss-Seidel sweeps,
  // which a new Jacobian does not speed up).
  progress.refresh[p] = (sweep.robust || progress.kept[p]) && sweep.iteration > 1 &&
                        !plant_in_contact_[p] &&
                        correction.largest > 0.25 * progress.last_correction[p];
  progress.last_correction[p] = correction.largest;
  progress.converged[p] = correction.largest <= parameters_.newton_tolerance;
  return factorize;
}

// Plants out of contact do not see each other: solved side by side (each writes only its own
// nodes and entries, so the bits are those of the loop in order). Plants in contact follow in
// index order (Gauss-Seidel). As in the plain loop, the failure reported is the lowest failing
// plant, and plants after it do not matter (the attempt is then discarded).
int PlantField::newton_sweep(const NewtonSweep& sweep, NewtonProgress& progress,
                             int& factorizations) {
  const int count = plant_count();
  const auto in_contact = [&](int p) { return sweep.contact && plant_in_contact_[p] != 0; };
  const auto fails = [&](int p) {
    return progress.corrections[p].singular || !std::isfinite(progress.corrections[p].largest);
  };
  int free_plants = 0;
  for (int p = 0; p < count; ++p) free_plants += in_contact(p) ? 0 : 1;
  const bool side_by_side = free_plants >= kPlantsSideBySide;
  if (newton_scratch_.size() < static_cast<std::size_t>(omp_get_max_threads()))
    newton_scratch_.resize(omp_get_max_threads());
  std::fill(progress.corrections.begin(), progress.corrections.end(), Correction{});
  int failed = count, factorized = 0;
#pragma omp parallel for schedule(dynamic, 4) reduction(min : failed) reduction(+ : factorized) \
    if (side_by_side)
  for (int p = 0; p < count; ++p) {
    if (in_contact(p)) continue;
    factorized += newton_iteration(p, sweep, progress, newton_scratch_[omp_get_thread_num()]);
    if (fails(p)) failed = std::min(failed, p);
  }
  for (int p = 0; p < std::min(failed, count); ++p) {
    if (!in_contact(p)) continue;
    factorized += newton_iteration(p, sweep, progress, newton_scratch_[0]);
    if (fails(p)) failed = p;
  }
  factorizations += factorized;
  return failed;
}

PlantField::NewtonOutcome PlantField::newton_attempt(double dt,
                                                     const std::vector<Eigen::Vector3d>& ambient,
                                                     bool robust) {
  NewtonOutcome outcome;
  const double mass_weight = 1.0 / (kBeta * dt * dt);
  positions_ = previous_positions_;
  velocities_ = previous_velocities_;
  accelerations_ = previous_accelerations_;
  // Predictor. Constant acceleration is the better guess while the step resolves the springs
  // (1 iteration per sub-step at safety_factor 0.5). Far above the spring-mass limit the last
  // accelerations are dominated by the unresolved axial modes (after a load step at t = 0 they
  // are F/m), and that predictor stretches the links: the Jacobian there carries a transverse
  // geometric stiffness (1 - l0/L) EA/l0 several times the bending stiffness and modified
  // Newton stalls (measured: contraction 0.56 per iteration at safety_factor 500). Constant
  // velocity keeps the links near their length.
  for (const Plant& plant : plants_) {
    for (int i = 1; i <= plant.links; ++i) {
      const int k = plant.first + i;
      if (robust)
        positions_[k] += dt * velocities_[k];
      else
        positions_[k] += dt * velocities_[k] + 0.5 * dt * dt * accelerations_[k];
    }
  }
  NewtonSweep sweep;
  sweep.dt = dt;
  sweep.mass_weight = mass_weight;
  sweep.damping_weight = kGamma / (kBeta * dt);
  sweep.robust = robust;
  sweep.contact = plants_may_touch();
  sweep.ambient = &ambient;
  sweep.reuse = parameters_.reuse_jacobian && !robust;
  if (sweep.contact) update_contact_candidates();
  NewtonProgress progress;
  progress.converged.assign(plants_.size(), 0);
  progress.refresh.assign(plants_.size(), 0);
  progress.kept.assign(plants_.size(), 0);
  progress.last_correction.assign(plants_.size(), 0.0);
  progress.corrections.resize(plants_.size());
  jacobians_.resize(plants_.size());
  jacobian_dt_.resize(plants_.size(), 0.0);
  for (int iteration = 1; iteration <= parameters_.max_newton_iterations; ++iteration) {
    outcome.iterations = iteration;
    sweep.iteration = iteration;
    newmark_kinematics(dt, mass_weight);
    if (sweep.contact && iteration == 1) {
      compute_contact_forces(positions_, velocities_, true);
      outcome.plants_in_contact =
          static_cast<int>(std::count(plant_in_contact_.begin(), plant_in_contact_.end(), char{1}));
    }
    const int failed = newton_sweep(sweep, progress, outcome.factorizations);
    if (failed < plant_count()) {
      const Correction& correction = progress.corrections[failed];
      const Plant& plant = plants_[failed];
      outcome.failure =
          correction.singular ? "singular Newton Jacobian" : "Newton correction is not finite";
      outcome.plant = failed;
      outcome.node = correction.node;
      const Eigen::Vector3d& r = residual_[plant.first + correction.node];
      outcome.residual = r.allFinite() ? r.norm() : std::numeric_limits<double>::infinity();
      outcome.correction = correction.largest;
      return outcome;
    }
    if (std::all_of(progress.converged.begin(), progress.converged.end(),
                    [](char c) { return c != 0; })) {
      newmark_kinematics(dt, mass_weight);  // state consistent with the final position
      outcome.converged = true;
      return outcome;
    }
  }
  outcome.failure = "Newton iteration did not converge";
  locate_largest_residual(progress.converged, outcome);
  outcome.correction = progress.last_correction[outcome.plant];
  return outcome;
}

void PlantField::substep(double t0, double dt, const std::vector<Eigen::Vector3d>& ambient_start,
                         const std::vector<Eigen::Vector3d>& ambient_end, int depth,
                         std::vector<Eigen::Vector3d>& impulse, WindowReport& report) {
  const std::size_t n = positions_.size();
  const double half = 0.5 * dt;
  previous_drag_ = drag_;
  if (parameters_.rigid) {  // nodes stay put; only the drag at rest is needed
    for (const Plant& plant : plants_) {
      for (int i = 0; i <= plant.links; ++i) {
        const int lo = plant.first + std::max(i - 1, 0);
        const int hi = plant.first + std::min(i + 1, plant.links);
        const double share = (i == 0 || i == plant.links) ? 0.5 : 1.0;
        drag_[plant.first + i] = node_drag((positions_[hi] - positions_[lo]).normalized(),
                                           ambient_end[plant.first + i], Eigen::Vector3d::Zero(),
                                           share * plant.link_length * plant.drag_factor *
                                               water_fraction_[plant.first + i])
                                     .force;
      }
    }
  } else {
    previous_positions_ = positions_;
    previous_velocities_ = velocities_;
    previous_accelerations_ = accelerations_;
    // Fast attempt first, unless it already failed in this window (then the step is in the
    // regime where only the robust one converges; trying fast first would waste its iterations).
    const NewtonOutcome first = newton_attempt(dt, ambient_end, robust_first_);
    int iterations = first.iterations;
    report.factorizations += first.factorizations;
    report.most_plants_in_contact =
        std::max(report.most_plants_in_contact, first.plants_in_contact);
    NewtonOutcome outcome = first;
    if (!first.converged) {
      outcome = newton_attempt(dt, ambient_end, !robust_first_);
      iterations += outcome.iterations;
      report.factorizations += outcome.factorizations;
      if (!robust_first_ && outcome.converged) {
        robust_first_ = true;
        ++report.newton_restarts;
      }
    }
    report.max_newton_iterations = std::max(report.max_newton_iterations, iterations);
    if (!outcome.converged) {
      // Both attempts failed: the motion within the step is too large for Newton from either
      // predictor (e.g. a blade laid flat by a 3.8 m/s stream started from rest, Ca = 3000, at
      // safety_factor 100). Halve the step, interpolating the ambient flow to the midpoint.
      positions_ = previous_positions_;
      velocities_ = previous_velocities_;
      accelerations_ = previous_accelerations_;
      drag_ = previous_drag_;
      if (depth < kMaxCutbacks) {
        ++report.cutbacks;
        std::vector<Eigen::Vector3d> middle(n);
        for (std::size_t k = 0; k < n; ++k) middle[k] = 0.5 * (ambient_start[k] + ambient_end[k]);
        substep(t0, half, ambient_start, middle, depth + 1, impulse, report);
        substep(t0 + half, half, middle, ambient_end, depth + 1, impulse, report);
        return;
      }
      const NewtonOutcome& robust = robust_first_ ? first : outcome;
      std::ostringstream out;
      out.precision(3);
      out << robust.failure << " in the sub-step from t = " << t0 << " s (dt = " << dt
          << " s, the window's sub-step halved " << depth << " times): residual |m a - F| "
          << robust.residual << " N is largest here, last correction " << robust.correction
          << " link lengths against newton_tolerance = " << parameters_.newton_tolerance
          << ", with max_newton_iterations = " << parameters_.max_newton_iterations
          << " per attempt (from the constant-acceleration and the constant-velocity "
             "predictor). Lower safety_factor (now "
          << parameters_.safety_factor
          << "; at 1 the sub-step is the spring-mass limit), or raise max_newton_iterations or "
             "newton_tolerance (keys of the vegetation_beam section)";
      throw StabilityError(plant_message(robust.plant, robust.node, out.str()));
    }
  }
  // Trapezoidal drag impulse, the same weighting Newmark's velocity update gives it.
  for (std::size_t k = 0; k < n; ++k) impulse[k] += half * previous_drag_[k];
  for (std::size_t k = 0; k < n; ++k) impulse[k] += half * drag_[k];
}

}  // namespace cosim::vegetation

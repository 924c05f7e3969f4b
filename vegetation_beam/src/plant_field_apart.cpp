// Windows in which no two plants can touch, solved plant by plant over all their sub-steps.
//
// The sub-step-synchronous path (plant_field_newmark.cpp) joins all plants at every Newton
// iteration of every sub-step, for the contact forces and the shared fast / robust attempt. When
// no two plants can touch during a window, each plant's sub-steps depend on its own nodes only,
// so the plants run their whole window side by side: one parallel loop a window instead of one
// an iteration. Each plant takes exactly the steps it takes in the synchronous path (the same
// predictor, iterations, kept Jacobians and impulse), so the bits are the same; anything that
// path would do differently (a robust attempt, a cutback, a failed state check, a contact) makes
// the window fall back to it from the window's start.
#include <algorithm>
#include <atomic>
#include <cmath>

#include <omp.h>

#include "cosim/vegetation_beam/plant_field.hpp"
#include "newmark_constants.hpp"

namespace cosim::vegetation {

struct PlantField::ApartWindow {
  const std::vector<Eigen::Vector3d>* ambient_begin = nullptr;
  const std::vector<Eigen::Vector3d>* ambient_end = nullptr;
  std::vector<Eigen::Vector3d>* ambient = nullptr;  // each plant writes its own nodes
  std::vector<Eigen::Vector3d>* impulse = nullptr;
  NewtonProgress* progress = nullptr;
  int substeps = 0;
  double dt = 0;
  bool contact = false;  // plant-to-plant contact is on: drift and candidates are tracked
  // Largest squared drift of a node from clearance_positions_ that still rules out a contact.
  double drift_limit2 = 0;
  std::atomic<int>* iterations = nullptr;
  std::atomic<int>* factorizations = nullptr;
};

bool PlantField::plants_clear() {
  if (!plants_may_touch()) return true;
  if (clearance_valid_ &&
      largest_move(positions_, clearance_positions_) <= 0.25 * clearance_margin_)
    return plants_clear_;
  clearance_positions_ = positions_;
  clearance_valid_ = true;
  plants_clear_ = true;
  for_each_close_pair(positions_, clearance_margin_,
                      [&](int, int) { return plants_clear_ = false; });
  return plants_clear_;
}

bool PlantField::advance_plants_apart(const std::vector<Eigen::Vector3d>& ambient_begin,
                                      const std::vector<Eigen::Vector3d>& ambient_end,
                                      std::vector<Eigen::Vector3d>& impulse, WindowReport& report) {
  const int count = plant_count();
  const std::size_t n = positions_.size();
  start_positions_ = positions_;
  start_velocities_ = velocities_;
  start_accelerations_ = accelerations_;
  start_drag_ = drag_;
  for (auto* scratch :
       {&previous_positions_, &previous_velocities_, &previous_accelerations_, &previous_drag_})
    scratch->resize(n);
  ApartWindow window;
  window.contact = plants_may_touch();
  // No pair is within reach (plants_clear()): what the first sub-step's contact search finds.
  if (window.contact) clear_contact_state();
  std::vector<Eigen::Vector3d> ambient(n);
  NewtonProgress progress;
  progress.converged.assign(count, 0);
  progress.refresh.assign(count, 0);
  progress.kept.assign(count, 0);
  progress.last_correction.assign(count, 0.0);
  progress.corrections.assign(count, Correction{});
  jacobians_.resize(count);
  jacobian_dt_.assign(count, 0.0);  // fresh Jacobians each window, as the synchronous path
  if (newton_scratch_.size() < static_cast<std::size_t>(omp_get_max_threads()))
    newton_scratch_.resize(omp_get_max_threads());
  if (window.contact) substep_starts_.resize(static_cast<std::size_t>(report.substeps - 1) * n);
  std::atomic<int> iterations{0}, factorizations{0};
  std::atomic<bool> apart{true};
  window.ambient_begin = &ambient_begin;
  window.ambient_end = &ambient_end;
  window.ambient = &ambient;
  window.impulse = &impulse;
  window.progress = &progress;
  window.substeps = report.substeps;
  window.dt = report.substep;
  window.drift_limit2 = 0.25 * clearance_margin_ * clearance_margin_;
  window.iterations = &iterations;
  window.factorizations = &factorizations;
#pragma omp parallel for schedule(dynamic, 4) if (count >= kPlantsSideBySide)
  for (int p = 0; p < count; ++p) {
    if (!apart.load(std::memory_order_relaxed)) continue;
    if (!advance_plant_apart(p, window, newton_scratch_[omp_get_thread_num()]))
      apart.store(false, std::memory_order_relaxed);
  }
  if (!apart.load()) {
    positions_ = start_positions_;
    velocities_ = start_velocities_;
    accelerations_ = start_accelerations_;
    drag_ = start_drag_;
    std::fill(impulse.begin(), impulse.end(), Eigen::Vector3d::Zero());
    return false;
  }
  report.max_newton_iterations = iterations.load();
  report.factorizations += factorizations.load();
  report.plants_apart = true;
  if (window.contact) settle_contact_state(report.substeps);
  return true;
}

bool PlantField::advance_plant_apart(int p, const ApartWindow& window,
                                     std::vector<double>& scratch) {
  const Plant& plant = plants_[p];
  const int first = plant.first, last = plant.first + plant.links;
  const std::size_t n = positions_.size();
  const double dt = window.dt, half = 0.5 * dt;
  const double mass_weight = 1.0 / (kBeta * dt * dt);
  NewtonSweep sweep;
  sweep.dt = dt;
  sweep.mass_weight = mass_weight;
  sweep.damping_weight = kGamma / (kBeta * dt);
  sweep.contact = window.contact;  // as the synchronous path: no pair of this plant is active
  sweep.ambient = window.ambient;
  sweep.reuse = parameters_.reuse_jacobian;
  NewtonProgress& progress = *window.progress;
  std::vector<Eigen::Vector3d>& ambient = *window.ambient;
  std::vector<Eigen::Vector3d>& impulse = *window.impulse;
  const auto within_clearance = [&] {
    if (!window.contact) return true;
    for (int k = first; k <= last; ++k) {
      if ((positions_[k] - clearance_positions_[k]).squaredNorm() > window.drift_limit2)
        return false;
    }
    return true;
  };
  int most_iterations = 0, factorized = 0;
  for (int step = 1; step <= window.substeps; ++step) {
    const double s = static_cast<double>(step) / window.substeps;
    for (int k = first; k <= last; ++k)
      ambient[k] = (1 - s) * (*window.ambient_begin)[k] + s * (*window.ambient_end)[k];
    if (window.contact && step > 1) {
      std::copy(positions_.begin() + first, positions_.begin() + last + 1,
                substep_starts_.begin() + static_cast<std::ptrdiff_t>((step - 2) * n + first));
    }
    for (int k = first; k <= last; ++k) {
      previous_drag_[k] = drag_[k];
      previous_positions_[k] = positions_[k];
      previous_velocities_[k] = velocities_[k];
      previous_accelerations_[k] = accelerations_[k];
    }
    // The fast attempt of newton_attempt(): constant-acceleration predictor.
    for (int k = first + 1; k <= last; ++k)
      positions_[k] += dt * velocities_[k] + 0.5 * dt * dt * accelerations_[k];
    progress.converged[p] = 0;
    progress.refresh[p] = 0;
    progress.kept[p] = 0;
    progress.last_correction[p] = 0.0;
    int iteration = 1;
    for (;; ++iteration) {
      if (iteration > parameters_.max_newton_iterations) return false;
      sweep.iteration = iteration;
      newmark_kinematics_of(plant, dt, mass_weight);
      // The synchronous path decides the touching pairs at the predictor.
      if (iteration == 1 && !within_clearance()) return false;
      progress.corrections[p] = Correction{};
      factorized += newton_iteration(p, sweep, progress, scratch) ? 1 : 0;
      const Correction& correction = progress.corrections[p];
      if (correction.singular || !std::isfinite(correction.largest)) return false;
      if (progress.converged[p]) break;
    }
    most_iterations = std::max(most_iterations, iteration);
    newmark_kinematics_of(plant, dt, mass_weight);  // state consistent with the final position
    for (int k = first; k <= last; ++k) impulse[k] += half * previous_drag_[k];
    for (int k = first; k <= last; ++k) impulse[k] += half * drag_[k];
    if (!state_problem(p, ambient).empty()) return false;
  }
  int seen = window.iterations->load(std::memory_order_relaxed);
  while (seen < most_iterations && !window.iterations->compare_exchange_weak(seen, most_iterations))
    ;
  window.factorizations->fetch_add(factorized, std::memory_order_relaxed);
  return true;
}

void PlantField::settle_contact_state(int substeps) {
  const std::size_t n = positions_.size();
  update_contact_candidates(start_positions_);
  for (int step = 2; step <= substeps; ++step) {
    update_contact_candidates(std::span<const Eigen::Vector3d>(
        substep_starts_.data() + static_cast<std::size_t>(step - 2) * n, n));
  }
  clear_contact_state();
}

}  // namespace cosim::vegetation

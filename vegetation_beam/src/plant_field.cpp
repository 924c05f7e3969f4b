// Construction, forces, stability limits and state checks of the plant field (the sub-cycled
// implicit Newmark step: plant_field_newmark.cpp).
#include "cosim/vegetation_beam/plant_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "beam_elements.hpp"
#include "cosim/vegetation_beam/banded_matrix.hpp"
#include "newmark_constants.hpp"
#include "plant_messages.hpp"

namespace cosim::vegetation {
namespace {

bool finite(const Eigen::Vector3d& v) {
  return v.allFinite();
}

}  // namespace

PlantField::PlantField(std::vector<PlantSpec> plants, BeamParameters parameters)
    : specs_(std::move(plants)), parameters_(std::move(parameters)) {
  const BeamParameters& p = parameters_;
  check_beam_parameters(p);  // the declared ranges (plant_field.hpp)
  double min_node_mass = 0, min_axial_spring = 0;
  for (std::size_t index = 0; index < specs_.size(); ++index) {
    PlantSpec& spec = specs_[index];
    check_plant(spec, static_cast<int>(index));
    spec.direction.normalize();
    const double area = spec.width * spec.thickness;
    if (spec.bending_stiffness <= 0)
      spec.bending_stiffness = spec.youngs_modulus * spec.width * std::pow(spec.thickness, 3) / 12;
    if (spec.axial_stiffness <= 0) spec.axial_stiffness = spec.youngs_modulus * area;

    Plant plant;
    plant.first = static_cast<int>(positions_.size());
    plant.links = spec.links;
    const double l0 = spec.length / spec.links;
    plant.link_length = l0;
    // Eq. 8: the node accelerates its own mass plus C_M times the displaced fluid.
    const double mass_density = spec.density + p.added_mass_coefficient * p.fluid_density;
    const double link_mass = mass_density * area * l0;  // M_p of eq. 14-15
    plant.axial_spring = spec.axial_stiffness / l0;     // eq. 12
    plant.axial_damper = p.axial_damping_ratio * 2 * std::sqrt(link_mass * plant.axial_spring);
    // Eq. 13 gives a force k_m = EI / l0^2 at lever l0: a joint moment EI / l0 per angle.
    plant.bending_spring = spec.bending_stiffness / l0;
    // Eq. 15 transferred to rotation: inertia M_p l0^2 about the joint.
    plant.bending_damper =
        p.bending_damping_ratio * 2 * l0 * std::sqrt(link_mass * plant.bending_spring);
    plant.drag_factor = 0.5 * p.fluid_density * p.drag_coefficient * spec.width;
    plant.contact_radius = 0.5 * spec.width;
    plant.ghost = spec.base - l0 * spec.direction;
    const double wave_speed = std::sqrt(spec.axial_stiffness / (mass_density * area));
    plant.speed_limit = wave_speed + 10 * std::sqrt(p.gravity.norm() * spec.length);
    plant.reach_limit = 1.5 * spec.length;
    setup_bed_contact(plant, spec, link_mass);
    plants_.push_back(plant);

    for (int i = 0; i <= spec.links; ++i) {
      const double share = (i == 0 || i == spec.links) ? 0.5 * l0 : l0;  // lumped length ds
      const double volume = area * share;
      positions_.push_back(spec.base + i * l0 * spec.direction);
      node_mass_.push_back(mass_density * volume);
      body_forces_.push_back((spec.density - p.fluid_density) * volume * p.gravity);
      plant_weight_.push_back(spec.density * volume * p.gravity);
      displaced_weight_.push_back(p.fluid_density * volume * p.gravity);
      contact_radius_.push_back(plant.contact_radius);
      node_plant_.push_back(static_cast<int>(index));
    }
    min_node_mass = index == 0 ? link_mass : std::min(min_node_mass, link_mass);
    min_axial_spring =
        index == 0 ? plant.axial_spring : std::min(min_axial_spring, plant.axial_spring);
  }
  const std::size_t n = positions_.size();
  initial_positions_ = positions_;
  velocities_.assign(n, Eigen::Vector3d::Zero());
  accelerations_.assign(n, Eigen::Vector3d::Zero());
  external_forces_.assign(n, Eigen::Vector3d::Zero());
  window_mean_drag_.assign(n, Eigen::Vector3d::Zero());
  water_fraction_.assign(n, 1.0);
  forces_.assign(n, Eigen::Vector3d::Zero());
  drag_.assign(n, Eigen::Vector3d::Zero());
  residual_.assign(n, Eigen::Vector3d::Zero());
  contact_forces_.assign(n, Eigen::Vector3d::Zero());
  contact_stiffness_blocks_.assign(n, Eigen::Matrix3d::Zero());
  contact_damping_blocks_.assign(n, Eigen::Matrix3d::Zero());
  plant_in_contact_.assign(plants_.size(), 0);
  contact_stiffness_ = p.contact_stiffness > 0 ? p.contact_stiffness : min_axial_spring;
  // A node pair: reduced mass m/2, critical damping 2 sqrt(k m / 2).
  contact_damping_ =
      p.contact_damping_ratio * 2 * std::sqrt(contact_stiffness_ * 0.5 * min_node_mass);
  double max_radius = 0;
  for (const Plant& plant : plants_) max_radius = std::max(max_radius, plant.contact_radius);
  contact_margin_ = max_radius;
  // A pair closer than reach + 4 radii at the last clearance check keeps the plants' windows
  // synchronous; the others may drift 2 radii each within a window and a quarter of that
  // between checks.
  clearance_margin_ = 4 * contact_margin_;
}

std::pair<int, int> PlantField::node_range(int plant) const {
  const Plant& p = plants_.at(plant);
  return {p.first, p.first + p.links + 1};
}

std::pair<double, std::string> PlantField::step_limit() const {
  double best = std::numeric_limits<double>::infinity();
  std::string reason = "no plants";
  double min_link_mass = std::numeric_limits<double>::infinity();
  for (int index = 0; index < plant_count(); ++index) {
    const Plant& plant = plants_[index];
    const PlantSpec& spec = specs_[index];
    const double link_mass = node_mass_[plant.first + 1] *
                             (plant.links == 1 ? 2.0 : 1.0);  // tip node carries half a link
    min_link_mass = std::min(min_link_mass, link_mass);
    // Lumped chain: axial dt < sqrt(m / k_nv) = l0 sqrt(rho/E); bending dt < (l0^2/2)
    // sqrt(m'/EI) with m' the mass per length (references/cantilever.md).
    const double axial = std::sqrt(link_mass / plant.axial_spring);
    const double l0 = plant.link_length;
    const double bending = 0.5 * l0 * l0 * std::sqrt(link_mass / l0 / spec.bending_stiffness);
    if (axial < best) {
      best = axial;
      reason = "axial spring-mass period of plant " + std::to_string(index) +
               " (axial_stiffness EA = " + std::to_string(spec.axial_stiffness) +
               " N, link length " + std::to_string(l0) + " m)";
    }
    if (bending < best) {
      best = bending;
      reason = "bending spring-mass period of plant " + std::to_string(index) +
               " (bending_stiffness EI = " + std::to_string(spec.bending_stiffness) +
               " N m^2, link length " + std::to_string(l0) + " m)";
    }
  }
  if (plants_may_touch()) {
    const double contact = std::sqrt(min_link_mass / contact_stiffness_);
    if (contact < best) {
      best = contact;
      reason =
          "contact spring-mass period (contact_stiffness = " + std::to_string(contact_stiffness_) +
          " N/m)";
    }
  }
  best *= parameters_.safety_factor;
  // The bed's spring-mass period is a limit whatever safety_factor (bed_contact.cpp).
  for (int index = 0; index < plant_count(); ++index) {
    const Plant& plant = plants_[index];
    if (plant.bed_spring <= 0) continue;
    const double link_mass = node_mass_[plant.first + 1] * (plant.links == 1 ? 2.0 : 1.0);
    const double bed = std::sqrt(link_mass / plant.bed_spring);
    if (bed < best) {
      best = bed;
      reason = "bed contact spring-mass period of plant " + std::to_string(index) +
               " (bed_stiffness = " + std::to_string(plant.bed_spring) + " N/m)";
    }
  }
  return {best, reason};
}

double PlantField::stable_substep() const {
  return step_limit().first;
}

int PlantField::substeps_for(double window_dt) const {
  if (!(window_dt > 0) || !std::isfinite(window_dt))
    throw std::invalid_argument("vegetation_beam: window_dt must be positive and finite");
  const auto [dt, reason] = step_limit();
  // The relative slack keeps an exact multiple from rounding up to one more sub-step.
  const double needed = std::ceil(window_dt / dt * (1 - 1e-12));
  if (needed > parameters_.max_substeps) {
    std::ostringstream out;
    out << "vegetation_beam: window of " << window_dt << " s needs " << needed << " sub-steps of "
        << dt << " s, above max_substeps = " << parameters_.max_substeps
        << "; the step is limited by the " << reason << " with safety_factor "
        << parameters_.safety_factor;
    throw StabilityError(out.str());
  }
  return std::max(1, static_cast<int>(needed));
}

void PlantField::set_external_forces(std::vector<Eigen::Vector3d> forces) {
  if (forces.size() != positions_.size())
    throw std::invalid_argument("vegetation_beam: external forces need one entry per node");
  external_forces_ = std::move(forces);
  accelerations_valid_ = false;
}

void PlantField::set_state(std::vector<Eigen::Vector3d> positions,
                           std::vector<Eigen::Vector3d> velocities) {
  if (positions.size() != positions_.size() || velocities.size() != positions_.size())
    throw std::invalid_argument("vegetation_beam: set_state needs one entry per node");
  positions_ = std::move(positions);
  velocities_ = std::move(velocities);
  for (const Plant& plant : plants_) {  // the base stays clamped
    positions_[plant.first] = initial_positions_[plant.first];
    velocities_[plant.first].setZero();
  }
  accelerations_valid_ = false;
  candidates_valid_ = false;
  clearance_valid_ = false;
}

void PlantField::compute_forces(int plant_index, const std::vector<Eigen::Vector3d>& x,
                                const std::vector<Eigen::Vector3d>& v,
                                const std::vector<Eigen::Vector3d>& ambient, bool include_contact,
                                std::vector<Eigen::Vector3d>& force,
                                std::vector<Eigen::Vector3d>& drag, BandedMatrix* jacobian,
                                double stiffness_weight, double damping_weight,
                                bool drag_stiffness) const {
  const Plant& plant = plants_[plant_index];
  const int first = plant.first, links = plant.links;
  const double l0 = plant.link_length;
  // Free node global index first + i has local block index i - 1; the base (i = 0) has none.
  auto add = [&](int i, int j, const Eigen::Matrix3d& block, double weight) {
    if (jacobian != nullptr && i > 0 && j > 0) jacobian->add_block(i - 1, j - 1, block, weight);
  };
  auto add_both = [&](int i, int j, const Eigen::Matrix3d& stiffness,
                      const Eigen::Matrix3d& damping, double sign) {
    if (jacobian != nullptr && i > 0 && j > 0)
      jacobian->add_blocks(i - 1, j - 1, stiffness, sign * stiffness_weight, damping,
                           sign * damping_weight);
  };
  for (int i = 0; i <= links; ++i) {
    force[first + i] = body_forces_[first + i] + external_forces_[first + i];
  }

  // Axial links (eq. 9).
  for (int i = 1; i <= links; ++i) {
    const AxialLink link =
        axial_link(x[first + i - 1], x[first + i], v[first + i - 1], v[first + i],
                   plant.axial_spring, plant.axial_damper, l0, jacobian != nullptr);
    force[first + i] += link.force_on_b;
    force[first + i - 1] -= link.force_on_b;
    for (const auto& [a, b, sign] : {std::tuple{i, i, 1.0}, std::tuple{i - 1, i - 1, 1.0},
                                     std::tuple{i, i - 1, -1.0}, std::tuple{i - 1, i, -1.0}})
      add_both(a, b, link.stiffness, link.damping, sign);
  }

  // Bending joints (eq. 10-11). Joint 0 uses the ghost node below the base; it carries the
  // curvature of only half a link (the other half is inside the clamp), hence 2 EI / l0, which
  // makes the clamp second-order accurate (references/cantilever.md).
  BendingJoint joint;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (int j = 0; j < links; ++j) {
    const Eigen::Vector3d nodes[3] = {j == 0 ? plant.ghost : x[first + j - 1], x[first + j],
                                      x[first + j + 1]};
    const Eigen::Vector3d rates[3] = {j == 0 ? zero : v[first + j - 1], v[first + j],
                                      v[first + j + 1]};
    const double scale = j == 0 ? 2.0 : 1.0;
    bending_joint(nodes, rates, scale * plant.bending_spring,
                  std::sqrt(scale) * plant.bending_damper, jacobian != nullptr, joint);
    for (int n = 0; n < 3; ++n) {
      const int node = j - 1 + n;  // -1 is the ghost
      if (node >= 0) force[first + node] += joint.force[n];
    }
    if (jacobian == nullptr) continue;
    for (int n = 0; n < 3; ++n) {
      for (int m = 0; m < 3; ++m)
        add_both(j - 1 + n, j - 1 + m, joint.stiffness[n][m], joint.damping[n][m], 1.0);
    }
  }

  // Drag on the normal relative velocity (eq. 16), per node with its lumped length ds. The
  // position dependence through the tangent is left out of the Jacobian unless asked
  // (quasi-Newton: enough while a sub-step turns the tangent little).
  if (plant.drag_factor > 0) {
    for (int i = 0; i <= links; ++i) {
      const int lo = std::max(i - 1, 0), hi = std::min(i + 1, links);
      const Eigen::Vector3d chord = x[first + hi] - x[first + lo];
      const Eigen::Vector3d tangent = chord.normalized();
      const double share = (i == 0 || i == links) ? 0.5 * l0 : l0;
      // Nodes out of the water (fraction 0) feel no drag.
      const bool tangent_terms = drag_stiffness && jacobian != nullptr;
      const NodeDrag d = node_drag(tangent, ambient[first + i], v[first + i],
                                   plant.drag_factor * share * water_fraction_[first + i],
                                   tangent_terms, jacobian != nullptr);
      drag[first + i] = d.force;
      force[first + i] += d.force;
      add(i, i, d.damping, damping_weight);
      if (tangent_terms) {  // t = chord / |chord|: d t / d x_hi = (I - t t^T) / |chord|
        const Eigen::Matrix3d by_hi =
            d.tangent_stiffness * (Eigen::Matrix3d::Identity() - tangent * tangent.transpose()) /
            chord.norm();
        add(i, hi, by_hi, stiffness_weight);
        add(i, lo, by_hi, -stiffness_weight);
      }
    }
  } else {
    for (int i = 0; i <= links; ++i) drag[first + i].setZero();
  }

  add_bed_contact(plant, x, v, force, jacobian, stiffness_weight, damping_weight);

  if (include_contact && plant_in_contact_[plant_index]) {
    for (int i = 1; i <= links; ++i) {
      force[first + i] += contact_forces_[first + i];
      add_both(i, i, contact_stiffness_blocks_[first + i], contact_damping_blocks_[first + i], 1.0);
    }
  }
}

void PlantField::check_state(const std::vector<Eigen::Vector3d>& ambient) const {
  for (int p = 0; p < plant_count(); ++p) {
    if (std::string problem = state_problem(p, ambient); !problem.empty())
      throw StabilityError(std::move(problem));
  }
}

std::string PlantField::state_problem(int p, const std::vector<Eigen::Vector3d>& ambient) const {
  const Plant& plant = plants_[p];
  double ambient_speed = 0;
  for (int i = 0; i <= plant.links; ++i)
    ambient_speed = std::max(ambient_speed, ambient[plant.first + i].norm());
  const double speed_limit = plant.speed_limit + 10 * ambient_speed;
  const auto when = [this] { return " at t = " + std::to_string(time_) + " s"; };
  for (int i = 1; i <= plant.links; ++i) {
    const int k = plant.first + i;
    if (!finite(positions_[k]) || !finite(velocities_[k]))
      return plant_message(p, i, "position or velocity is NaN/inf" + when());
    const double speed = velocities_[k].norm();
    if (speed > speed_limit) {
      std::ostringstream what;
      what << "runaway kinetic energy: speed " << speed << " m/s exceeds " << speed_limit
           << " m/s (axial wave speed + 10 sqrt(g L) + 10 |ambient|)" << when();
      return plant_message(p, i, what.str());
    }
    const double reach = (positions_[k] - positions_[plant.first]).norm();
    if (reach > plant.reach_limit) {
      std::ostringstream what;
      what << "node escaped: distance from base " << reach
           << " m exceeds 1.5 length = " << plant.reach_limit << " m" << when();
      return plant_message(p, i, what.str());
    }
  }
  return {};
}

WindowReport PlantField::advance(double window_dt,
                                 const std::vector<Eigen::Vector3d>& ambient_begin,
                                 const std::vector<Eigen::Vector3d>& ambient_end) {
  const std::size_t n = positions_.size();
  if (ambient_begin.size() != n || ambient_end.size() != n)
    throw std::invalid_argument("vegetation_beam: ambient velocities need one entry per node");
  for (std::size_t k = 0; k < n; ++k) {
    if (!finite(ambient_begin[k]) || !finite(ambient_end[k])) {
      const int p = node_plant_[k];
      throw StabilityError(plant_message(p, static_cast<int>(k) - plants_[p].first,
                                         "ambient fluid velocity is NaN/inf"));
    }
  }
  WindowReport report;
  report.substeps = substeps_for(window_dt);
  report.substep = window_dt / report.substeps;
  if (!accelerations_valid_) initialise_accelerations(ambient_begin);

  std::vector<Eigen::Vector3d> impulse(n, Eigen::Vector3d::Zero());
  const double start = time_;
  robust_first_ = false;
  // Plant by plant when no two can touch (plant_field_apart.cpp), but not right after a window
  // that needed the robust attempt (this one likely does too, and would be solved twice), and
  // not when the sub-steps' start positions it keeps would exceed kApartMostKeptPositions.
  const bool contact = plants_may_touch();
  const long long kept_positions =
      contact ? static_cast<long long>(report.substeps - 1) * static_cast<long long>(n) : 0;
  if (parameters_.plants_apart_windows && !parameters_.rigid && !last_window_robust_ &&
      kept_positions <= kApartMostKeptPositions && plants_clear() &&
      advance_plants_apart(ambient_begin, ambient_end, impulse, report)) {
    time_ = start + window_dt;
  } else {
    // Each window starts from fresh Jacobians, so a run restarted at a window boundary (or a
    // window repeated by an implicit scheme) takes the same steps as the straight run.
    std::fill(jacobian_dt_.begin(), jacobian_dt_.end(), 0.0);
    std::vector<Eigen::Vector3d> ambient(ambient_begin), previous_ambient(n);
    for (int step = 1; step <= report.substeps; ++step) {
      const double s = static_cast<double>(step) / report.substeps;
      std::swap(ambient, previous_ambient);
      for (std::size_t k = 0; k < n; ++k)
        ambient[k] = (1 - s) * ambient_begin[k] + s * ambient_end[k];
      substep(time_, report.substep, previous_ambient, ambient, 0, impulse, report);
      time_ = start + s * window_dt;
      check_state(ambient);
    }
    last_window_robust_ = robust_first_;
  }
  for (std::size_t k = 0; k < n; ++k) window_mean_drag_[k] = impulse[k] / window_dt;
  return report;
}

void PlantField::set_water_fraction(const std::vector<double>& fraction) {
  if (fraction.size() != water_fraction_.size()) {
    throw std::invalid_argument("vegetation_beam: water fraction needs one value per node (" +
                                std::to_string(water_fraction_.size()) + "), got " +
                                std::to_string(fraction.size()));
  }
  for (std::size_t k = 0; k < fraction.size(); ++k) {
    const double wet = std::clamp(fraction[k], 0.0, 1.0);
    water_fraction_[k] = wet;
    // Buoyancy acts on the submerged share only.
    body_forces_[k] = plant_weight_[k] - wet * displaced_weight_[k];
  }
  accelerations_valid_ = false;
}

}  // namespace cosim::vegetation

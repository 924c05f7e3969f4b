// Fluid forces on the moving elements and the window loop that applies them. Seed 004 (eq.
// 47-49): constant-C_D drag and buoyancy on the submerged share, no fluid torque. The unresolved
// CFD-DEM set (Zhou, Kuang, Chu & Yu, J. Fluid Mech. 661 (2010) 482-510; the fluid's viscous
// stress on the element is left out): Reynolds-number dependent drag with the Di Felice voidage
// correction, the pressure-gradient force -V_sub grad p with grad p = rho_f (g - Du/Dt), and
// added mass, integrated implicitly. Still no fluid torque (eq. 47).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/fluid_forces.hpp"

namespace cosim::dem {

void DemWorld::check_fluid(const FluidAtElements& fluid) const {
  if (fluid.velocity.empty()) return;
  const std::size_t n = moving_.size();
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument("advance: " + what + " (" + std::to_string(n) +
                                " moving elements)");
  };
  if (fluid.velocity.size() != n) fail("need one fluid velocity per moving element");
  if (!fluid.acceleration.empty() && fluid.acceleration.size() != n) {
    fail("fluid acceleration: give one per moving element or none");
  }
  if (!fluid.surface_elevation.empty() && fluid.surface_elevation.size() != n) {
    fail("surface elevation: give one per moving element or none");
  }
  if (fluid.water_fraction.size() != n) {
    const bool every_surface_known =
        fluid.surface_elevation.size() == n &&
        std::none_of(fluid.surface_elevation.begin(), fluid.surface_elevation.end(),
                     [](double z) { return std::isnan(z); });
    if (!every_surface_known) fail("need a water fraction wherever the surface is unknown");
  }
  const DemParameters& p = parameters_;
  if (p.drag_law == DragLaw::kSchillerNaumann && !(p.fluid_viscosity > 0.0)) {
    fail("the Schiller-Naumann drag needs fluid_viscosity > 0");
  }
  if (p.voidage_correction &&
      (p.drag_law != DragLaw::kSchillerNaumann || !(p.voidage_radius > 0.0))) {
    fail("the voidage correction needs the Schiller-Naumann drag and voidage_radius > 0");
  }
}

void DemWorld::update_voidage() {
  std::vector<double> volumes;
  volumes.reserve(moving_.size());
  for (const int i : moving_) volumes.push_back(volume(i));
  voidage_ = local_voidage(element_centers(), volumes, parameters_.voidage_radius);
}

double DemWorld::element_submerged_fraction(int k, const FluidAtElements& fluid) const {
  if (!fluid.surface_elevation.empty() && !std::isnan(fluid.surface_elevation[k])) {
    const int i = moving_[k];
    const Element& e = elements_[i];
    const double surface = fluid.surface_elevation[k];
    if (e.kind == ElementKind::kSphere) {
      return sphere_submerged_fraction(position(i).z(), e.radius, surface);
    }
    return cylinder_submerged_fraction(position(i), e.axis, e.radius, 2.0 * e.half_length, surface);
  }
  return std::clamp(fluid.water_fraction[k], 0.0, 1.0);
}

Eigen::Vector3d DemWorld::drag_force(int k, const Eigen::Vector3d& relative) const {
  const Element& e = elements_[moving_[k]];
  const double rho = parameters_.fluid_density;
  const double speed = relative.norm();
  if (parameters_.drag_law == DragLaw::kSeed004) {
    // Eq. (48): 0.5 C_D rho A |U - v| (U - v) on the projected area normal to the relative flow.
    double area = std::numbers::pi * e.radius * e.radius;
    double drag_coefficient = parameters_.drag_coefficient_sphere;
    if (e.kind == ElementKind::kCylinder) {
      const double cosine = speed > 0.0 ? std::abs(e.axis.dot(relative) / speed) : 1.0;
      const double sine = std::sqrt(std::max(0.0, 1.0 - cosine * cosine));
      area = area * cosine + 4.0 * e.radius * e.half_length * sine;
      drag_coefficient = parameters_.drag_coefficient_cylinder;
    }
    return 0.5 * drag_coefficient * rho * area * speed * relative;
  }
  if (!(speed > 0.0)) return Eigen::Vector3d::Zero();
  // Di Felice (1994): F = F_0(eps |w|) eps^(-chi), F_0 the single-particle drag at the
  // superficial slip eps w, i.e. 0.5 C_D(Re_eps) rho A eps^2 |w| w eps^(-chi), Re on eps |w|.
  const double eps = parameters_.voidage_correction ? voidage_[k] : 1.0;
  const double diameter = 2.0 * e.radius;
  const double reynolds_per_speed = rho * eps * diameter / parameters_.fluid_viscosity;
  const double hindrance = parameters_.voidage_correction
                               ? std::pow(eps, 2.0 - di_felice_exponent(reynolds_per_speed * speed))
                               : 1.0;
  if (e.kind == ElementKind::kSphere) {
    const double c_d = schiller_naumann_drag_coefficient(reynolds_per_speed * speed);
    const double area = std::numbers::pi * e.radius * e.radius;
    return (0.5 * c_d * rho * area * speed * hindrance) * relative;
  }
  // Crossflow principle: normal and axial parts of the slip each with their own Re (the
  // hindrance uses the whole slip, as the voidage function was fitted for spheres).
  const Eigen::Vector3d axial = e.axis.dot(relative) * e.axis;
  const Eigen::Vector3d normal = relative - axial;
  const double normal_speed = normal.norm();
  const double axial_speed = axial.norm();
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  if (normal_speed > 0.0) {
    const double c_d = cylinder_crossflow_drag_coefficient(reynolds_per_speed * normal_speed);
    force += (0.5 * c_d * rho * diameter * 2.0 * e.half_length * normal_speed) * normal;
  }
  if (axial_speed > 0.0) {
    const double c_d = schiller_naumann_drag_coefficient(reynolds_per_speed * axial_speed);
    force += (0.5 * c_d * rho * std::numbers::pi * e.radius * e.radius * axial_speed) * axial;
  }
  return hindrance * force;
}

void DemWorld::apply_fluid(const FluidAtElements& fluid) {
  if (fluid.velocity.empty()) return;
  const DemParameters& p = parameters_;
  const double rho = p.fluid_density;
  const int count = static_cast<int>(moving_.size());
  for (int k = 0; k < count; ++k) {
    const Element& e = elements_[moving_[k]];
    const double fraction = element_submerged_fraction(k, fluid);
    submerged_fraction_[k] = fraction;
    added_mass_normal_[k] = 0.0;
    added_mass_axial_[k] = 0.0;
    fluid_acceleration_[k] =
        fluid.acceleration.empty() ? Eigen::Vector3d::Zero() : fluid.acceleration[k];
    if (fraction <= 0.0) continue;
    // Drag and buoyancy scale with the submerged share (seed 004: no fluid force above the
    // water depth); buoyancy is the hydrostatic part of -V_sub grad p.
    const Eigen::Vector3d relative = fluid.velocity[k] - e.velocity;
    const double volume = e.mass / materials_[e.material].density;
    const Eigen::Vector3d drag = fraction * drag_force(k, relative);
    Eigen::Vector3d fluid_force = drag - fraction * rho * volume * p.gravity;
    const double submerged_volume = fraction * volume;
    if (p.fluid_acceleration_force) {
      fluid_force += rho * submerged_volume * fluid_acceleration_[k];
    }
    if (p.added_mass) {
      const bool sphere = e.kind == ElementKind::kSphere;
      added_mass_normal_[k] =
          rho * submerged_volume * (sphere ? p.added_mass_sphere : p.added_mass_cylinder_normal);
      added_mass_axial_[k] =
          rho * submerged_volume * (sphere ? p.added_mass_sphere : p.added_mass_cylinder_axial);
    }
    force_[moving_[k]] += fluid_force;
    mean_fluid_force_[k] += fluid_force;
    mean_interaction_force_[k] += drag;
  }
}

Eigen::Vector3d DemWorld::added_mass_acceleration(int k) {
  // m dv/dt = F + M_a (Du/Dt - dv/dt)  =>  (m I + M_a) dv/dt = F + M_a Du/Dt, with
  // M_a = m_n (I - a a^T) + m_t a a^T: the 3x3 system splits exactly along and across the axis
  // (a sphere has m_n = m_t). Solved for dv/dt, the added-mass force M_a (Du/Dt - dv/dt) is the
  // one this sub-step really applied, so it enters the window's fluid force.
  const Element& e = elements_[moving_[k]];
  const Eigen::Vector3d& fluid_acceleration = fluid_acceleration_[k];
  const double normal_mass = added_mass_normal_[k];
  const double axial_mass = added_mass_axial_[k];
  const Eigen::Vector3d& axis = e.axis;
  const auto split = [&](const Eigen::Vector3d& v) {
    const Eigen::Vector3d along = axis.dot(v) * axis;
    return std::pair<Eigen::Vector3d, Eigen::Vector3d>(along, v - along);
  };
  const auto [fluid_along, fluid_across] = split(fluid_acceleration);
  const Eigen::Vector3d total =
      force_[moving_[k]] + axial_mass * fluid_along + normal_mass * fluid_across;
  const auto [total_along, total_across] = split(total);
  const Eigen::Vector3d acceleration =
      total_along / (e.mass + axial_mass) + total_across / (e.mass + normal_mass);
  const auto [slip_along, slip_across] = split(fluid_acceleration - acceleration);
  const Eigen::Vector3d added_mass_force = axial_mass * slip_along + normal_mass * slip_across;
  mean_fluid_force_[k] += added_mass_force;
  mean_interaction_force_[k] += added_mass_force;
  return acceleration;
}

WindowReport DemWorld::advance(double window_dt, const FluidAtElements& fluid) {
  if (!(window_dt > 0.0)) throw std::invalid_argument("advance: window_dt must be positive");
  check_fluid(fluid);
  const bool with_fluid = !fluid.velocity.empty();
  const double target = parameters_.user_dt > 0.0 ? parameters_.user_dt : stable_dt();
  const int substeps = std::max(1, static_cast<int>(std::ceil(window_dt / target - 1e-9)));
  const double dt = window_dt / substeps;
  for (auto& f : mean_fluid_force_) f.setZero();
  for (auto& f : mean_interaction_force_) f.setZero();
  if (!with_fluid) std::fill(submerged_fraction_.begin(), submerged_fraction_.end(), 0.0);
  if (with_fluid && parameters_.voidage_correction) update_voidage();
  window_max_overlap_ = 0.0;
  for (int s = 0; s < substeps; ++s) {
    update_list_if_needed(dt);
    compute_forces(dt);
    apply_fluid(fluid);
    const bool suspect = integrate(dt, with_fluid);
    time_ += dt;
    ++step_count_;
    if (suspect) check_stability();
  }
  for (auto& f : mean_fluid_force_) f /= substeps;
  for (auto& f : mean_interaction_force_) f /= substeps;
  WindowReport report;
  report.substeps = substeps;
  report.substep = dt;
  report.contacts = contact_count();
  report.max_overlap_ratio = window_max_overlap_;
  return report;
}

WindowReport DemWorld::advance(double window_dt,
                               const std::vector<Eigen::Vector3d>& ambient_velocity,
                               const std::vector<double>& water_fraction) {
  FluidAtElements fluid;
  fluid.velocity = ambient_velocity;
  fluid.water_fraction = water_fraction;
  return advance(window_dt, fluid);
}

}  // namespace cosim::dem

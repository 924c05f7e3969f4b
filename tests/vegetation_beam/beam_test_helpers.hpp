// Shared set-ups of the vegetation_beam tests.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

#include "cosim/vegetation_beam/plant_field.hpp"

namespace cosim::vegetation::testing {

// Square-ish strip of length 1 m in vacuum without gravity: a textbook cantilever.
inline PlantSpec textbook_strip(int links) {
  PlantSpec spec;
  spec.length = 1.0;
  spec.links = links;
  spec.width = 0.01;
  spec.thickness = 0.01;
  spec.youngs_modulus = 1e9;
  spec.density = 1000;
  return spec;
}

// The single-blade scene's PET strip (seed 000 section 3(2)), z up, leaning `tilt_degrees`
// towards +x.
inline PlantSpec pet_strip(double density, double tilt_degrees,
                           const Eigen::Vector3d& base = Eigen::Vector3d::Zero()) {
  PlantSpec blade;
  const double tilt = tilt_degrees * std::numbers::pi / 180;
  blade.base = base;
  blade.direction = Eigen::Vector3d(std::sin(tilt), 0, std::cos(tilt));
  blade.length = 0.045;
  blade.links = 16;
  blade.width = 0.002;
  blade.thickness = 1.2e-4;
  blade.bending_stiffness = 8.67e-7;
  blade.youngs_modulus = 3.0e9;
  blade.density = density;
  return blade;
}

// Water with the single-blade scene's drag and damping (z up).
inline BeamParameters pet_strip_water(double safety_factor) {
  BeamParameters parameters;
  parameters.gravity = Eigen::Vector3d(0, 0, -9.81);
  parameters.drag_coefficient = 1.95;
  parameters.bending_damping_ratio = 0.5;
  parameters.axial_damping_ratio = 0.5;
  parameters.safety_factor = safety_factor;
  return parameters;
}

inline BeamParameters vacuum_parameters() {
  BeamParameters parameters;
  parameters.fluid_density = 0;
  parameters.gravity.setZero();
  parameters.axial_damping_ratio = 0;
  parameters.bending_damping_ratio = 0;
  return parameters;
}

inline std::vector<Eigen::Vector3d> uniform(const PlantField& field, const Eigen::Vector3d& u) {
  return std::vector<Eigen::Vector3d>(field.node_count(), u);
}

// Clamped-free Euler-Bernoulli frequency (Hz) of mode n (1-based), references/cantilever.md.
inline double cantilever_frequency(int mode, double bending_stiffness, double mass_per_length,
                                   double length) {
  constexpr double beta_l_squared[] = {3.516015, 22.034492, 61.697214, 120.901916};
  return beta_l_squared[mode - 1] *
         std::sqrt(bending_stiffness / (mass_per_length * std::pow(length, 4))) /
         (2 * std::numbers::pi);
}

// A reed of scenarios/honami_field (seed 000 section 4): 1 m tall, 10 links, d = 0.01 m,
// EI = 0.847 N m^2, EA of E = 1.73e9 Pa, specific gravity 0.5, upright (z) at x = `x`.
inline PlantSpec honami_reed(double x) {
  PlantSpec reed;
  reed.base = Eigen::Vector3d(x, 0, 0);
  reed.direction = Eigen::Vector3d::UnitZ();
  reed.length = 1.0;
  reed.links = 10;
  reed.width = 0.01;
  reed.thickness = 0.007854;  // pi d / 4: width x thickness = the round stem's area
  reed.bending_stiffness = 0.847;
  reed.axial_stiffness = 1.3552e5;
  reed.density = 500;
  return reed;
}

}  // namespace cosim::vegetation::testing

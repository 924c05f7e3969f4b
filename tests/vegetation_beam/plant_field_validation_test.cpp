// Validation against references/cantilever.md: static deflections, natural frequencies, and the
// energy behaviour of the undamped Newmark scheme.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "beam_test_helpers.hpp"

namespace cosim::vegetation {
namespace {

using testing::cantilever_frequency;
using testing::textbook_strip;
using testing::uniform;
using testing::vacuum_parameters;

// Tip deflection of the strip (along x) under a tip load giving 1e-4 L (small deflection).
double tip_load_error(int links) {
  PlantField field({textbook_strip(links)}, vacuum_parameters());
  const double ei = field.specs()[0].bending_stiffness;
  const double load = 3 * ei * 1e-4;  // P = 3 EI delta / L^3 with L = 1
  std::vector<Eigen::Vector3d> loads(field.node_count(), Eigen::Vector3d::Zero());
  loads.back() = Eigen::Vector3d(load, 0, 0);
  field.set_external_forces(loads);
  field.solve_static();
  const double reference = load / (3 * ei);  // P L^3 / (3 EI)
  return field.tip_displacement(0).x() / reference - 1;
}

double uniform_load_error(int links) {
  PlantField field({textbook_strip(links)}, vacuum_parameters());
  const double ei = field.specs()[0].bending_stiffness;
  const double q = 8 * ei * 1e-4;  // q L^4 / (8 EI) = 1e-4
  const double l0 = 1.0 / links;
  std::vector<Eigen::Vector3d> loads(field.node_count(), Eigen::Vector3d(q * l0, 0, 0));
  loads.back() *= 0.5;  // lumped: the tip carries half a link
  field.set_external_forces(loads);
  field.solve_static();
  return field.tip_displacement(0).x() / (q / (8 * ei)) - 1;
}

TEST(CantileverStatics, TipLoadWithinHalfPercentAndSecondOrder) {
  const double e8 = tip_load_error(8), e16 = tip_load_error(16), e32 = tip_load_error(32);
  std::printf("tip load relative error: 8 links %.3e, 16 links %.3e, 32 links %.3e\n", e8, e16,
              e32);
  EXPECT_LT(std::abs(e32), 0.005);
  EXPECT_GT(std::abs(e8) / std::abs(e32), 10) << "ghost-node clamp should converge at order 2";
  EXPECT_LT(std::abs(e16), std::abs(e8));
}

TEST(CantileverStatics, UniformLoadWithinHalfPercentAndConverging) {
  const double e8 = uniform_load_error(8), e16 = uniform_load_error(16),
               e32 = uniform_load_error(32);
  std::printf("uniform load relative error: 8 links %.3e, 16 links %.3e, 32 links %.3e\n", e8, e16,
              e32);
  EXPECT_LT(std::abs(e32), 0.005);
  EXPECT_LT(std::abs(e32), std::abs(e16));
  EXPECT_LT(std::abs(e16), std::abs(e8));
}

// First three clamped-free bending frequencies, in vacuum and in water (added mass C_M rho A).
TEST(CantileverFrequencies, FirstThreeModesWithinOnePercentAt32Links) {
  for (const double fluid_density : {0.0, 1000.0}) {
    BeamParameters parameters = vacuum_parameters();
    parameters.fluid_density = fluid_density;
    const PlantField field({textbook_strip(32)}, parameters);
    const PlantSpec& spec = field.specs()[0];
    const double mass_per_length = (spec.density + fluid_density) * spec.width * spec.thickness;
    const std::vector<double> frequencies = field.linear_natural_frequencies(0, 3);
    ASSERT_EQ(frequencies.size(), 3u);
    for (int mode = 1; mode <= 3; ++mode) {
      const double reference =
          cantilever_frequency(mode, spec.bending_stiffness, mass_per_length, spec.length);
      const double error = frequencies[mode - 1] / reference - 1;
      std::printf("rho %.0f mode %d: %.5f Hz vs %.5f Hz (error %.3e)\n", fluid_density, mode,
                  frequencies[mode - 1], reference, error);
      EXPECT_LT(std::abs(error), 0.01) << "mode " << mode;
    }
  }
}

TEST(CantileverFrequencies, ConvergeWithLinkCount) {
  const PlantSpec spec = textbook_strip(8);
  const double reference =
      cantilever_frequency(2, 1e9 * 1e-8 / 12, spec.density * 1e-4, spec.length);
  double previous = 1;
  for (int links : {8, 16, 32}) {
    const PlantField field({textbook_strip(links)}, vacuum_parameters());
    const double error = std::abs(field.linear_natural_frequencies(0, 2)[1] / reference - 1);
    EXPECT_LT(error, previous) << links << " links";
    previous = error;
  }
}

// Undamped, no fluid, no gravity: release a small static deflection. Newmark average
// acceleration keeps the total energy (no numerical damping) and the free vibration runs at
// the first natural frequency.
TEST(NewmarkDynamics, UndampedFreeVibrationConservesEnergyAndHasModeOnePeriod) {
  PlantSpec spec;
  spec.length = 0.1;
  spec.links = 16;
  spec.width = 0.01;
  spec.thickness = 0.005;
  spec.youngs_modulus = 1e9;
  spec.density = 1000;
  BeamParameters parameters = vacuum_parameters();
  PlantField field({spec}, parameters);
  const double ei = field.specs()[0].bending_stiffness;
  std::vector<Eigen::Vector3d> loads(field.node_count(), Eigen::Vector3d::Zero());
  loads.back() = Eigen::Vector3d(3 * ei * 1e-3 * spec.length / std::pow(spec.length, 3), 0, 0);
  field.set_external_forces(loads);
  field.solve_static();  // tip deflection 1e-3 L
  field.set_external_forces(
      std::vector<Eigen::Vector3d>(field.node_count(), Eigen::Vector3d::Zero()));
  const double energy0 = field.kinetic_energy() + field.elastic_energy() + field.potential_energy();
  ASSERT_GT(energy0, 0);

  const double f1 = field.linear_natural_frequencies(0, 1)[0];
  const double periods = 20;
  const double window = 1.0 / f1 / 50;
  const auto still = uniform(field, Eigen::Vector3d::Zero());
  double worst_drift = 0;
  int crossings = 0;
  double first_crossing = 0, last_crossing = 0;
  double previous_x = field.tip_displacement(0).x();
  for (int w = 0; w < 50 * periods; ++w) {
    field.advance(window, still, still);
    const double energy =
        field.kinetic_energy() + field.elastic_energy() + field.potential_energy();
    worst_drift = std::max(worst_drift, std::abs(energy / energy0 - 1));
    const double x = field.tip_displacement(0).x();
    if ((previous_x > 0) != (x > 0)) {
      // Linear interpolation of the zero crossing inside the window.
      const double t = field.time() - window * x / (x - previous_x);
      if (crossings == 0) first_crossing = t;
      last_crossing = t;
      ++crossings;
    }
    previous_x = x;
  }
  const double measured = 0.5 * (crossings - 1) / (last_crossing - first_crossing);
  std::printf("energy drift %.3e over %.0f periods; tip frequency %.4f Hz vs eigen %.4f Hz\n",
              worst_drift, periods, measured, f1);
  EXPECT_LT(worst_drift, 1e-4);
  EXPECT_NEAR(measured / f1, 1.0, 0.005);
  // Against the continuum beam too (16 links).
  const double reference =
      cantilever_frequency(1, ei, spec.density * spec.width * spec.thickness, spec.length);
  EXPECT_NEAR(measured / reference, 1.0, 0.01);
}

}  // namespace
}  // namespace cosim::vegetation

namespace cosim::vegetation {
namespace {

// Dynamic relaxation: a damped plant in still water under a large tip load (tip deflection about
// 0.3 L, geometrically non-linear) settles where the static Newton solve puts it, so the dynamic
// force path and the static one agree.
TEST(NewmarkDynamics, DampedMotionSettlesAtTheStaticSolution) {
  PlantSpec spec;
  spec.length = 0.1;
  spec.links = 10;
  spec.width = 0.01;
  spec.thickness = 0.002;
  spec.youngs_modulus = 1e9;
  spec.density = 1000;
  BeamParameters parameters;
  parameters.gravity.setZero();
  parameters.bending_damping_ratio = 2.0;
  parameters.axial_damping_ratio = 1.0;
  PlantField dynamic({spec}, parameters);
  const double ei = dynamic.specs()[0].bending_stiffness;
  std::vector<Eigen::Vector3d> loads(dynamic.node_count(), Eigen::Vector3d::Zero());
  loads.back() = Eigen::Vector3d(ei / (spec.length * spec.length), 0, 0);  // P L^2 / EI = 1
  dynamic.set_external_forces(loads);
  PlantField statics({spec}, parameters);
  statics.set_external_forces(loads);
  const StaticReport report = statics.solve_static();
  const Eigen::Vector3d target = statics.tip_displacement(0);
  const auto still = uniform(dynamic, Eigen::Vector3d::Zero());
  int windows = 0;
  while (windows < 4000) {
    dynamic.advance(1e-3, still, still);
    ++windows;
    if ((dynamic.tip_displacement(0) - target).norm() < 1e-6 * target.norm() &&
        dynamic.velocities().back().norm() < 1e-6)
      break;
  }
  std::printf(
      "static Newton %d iterations, tip (%.6f, %.6f) m; dynamic after %.3f s: (%.6f, "
      "%.6f) m\n",
      report.iterations, target.x(), target.y(), dynamic.time(), dynamic.tip_displacement(0).x(),
      dynamic.tip_displacement(0).y());
  // Large-deflection elastica at P L^2 / EI = 1 (Bisshopp and Drucker 1945): transverse tip
  // deflection 0.3017 L, shortening 0.0566 L (linear theory: L/3). 10 links: within 1 %.
  EXPECT_NEAR(target.x() / spec.length, 0.3017, 0.01 * 0.3017);
  EXPECT_NEAR(-target.y() / spec.length, 0.0566, 0.01 * 0.0566);
  EXPECT_LT((dynamic.tip_displacement(0) - target).norm(), 1e-5 * target.norm());
}

// honami_field's reeds (seed 000 section 4; 10 links, EI = 0.847 N m^2, s.g. 0.5, C_D = 0.9) in
// a stream that pulses and varies with height, in the scene's 2 ms windows, with the water
// fraction set at every window as the coupled process sets it. The scene takes one sub-step a
// window (safety_factor 25); the implicit step must give the motion of five sub-steps
// (safety_factor 5) to 1e-4 of the tips' displacement, far below the honami's fluctuations
// (about 1 % of it; docs/validation.md, honami_field).
std::vector<Eigen::Vector3d> honami_reed_tips(double safety_factor) {
  std::vector<PlantSpec> reeds;
  for (int i = 0; i < 4; ++i) reeds.push_back(testing::honami_reed(0.05 * i));
  BeamParameters parameters;
  parameters.gravity = Eigen::Vector3d(0, 0, -9.81);
  parameters.drag_coefficient = 0.9;
  parameters.safety_factor = safety_factor;
  PlantField field(reeds, parameters);
  const double window = 2e-3;
  // u = r(t) (1.5 + 0.5 sin(2 pi 1.5 t)) (0.5 + z) m/s along x, z the height of the node, with
  // the scene's soft start r(t) = min(1, t / 0.25 s): an impulsive start is a transient of the
  // links' own periods, which no sub-step of 2 ms follows (the scene ramps its inflow too).
  const auto stream = [&](double t) {
    std::vector<Eigen::Vector3d> flow(field.node_count());
    const double speed =
        std::min(1.0, t / 0.25) * (1.5 + 0.5 * std::sin(2 * std::numbers::pi * 1.5 * t));
    for (std::size_t k = 0; k < flow.size(); ++k)
      flow[k] = Eigen::Vector3d(speed * (0.5 + field.positions()[k].z()), 0, 0);
    return flow;
  };
  std::vector<Eigen::Vector3d> tips;
  for (int w = 0; w < 750; ++w) {
    field.set_water_fraction(std::vector<double>(field.node_count(), 1.0));
    field.advance(window, stream(w * window), stream((w + 1) * window));
    for (int p = 0; p < field.plant_count(); ++p) tips.push_back(field.tip_displacement(p));
  }
  return tips;
}

TEST(NewmarkDynamics, HonamiReedsTakeOneSubstepAWindowAsFive) {
  const auto five = honami_reed_tips(5);
  const auto one = honami_reed_tips(25);
  ASSERT_EQ(five.size(), one.size());
  double largest_five = 0, difference = 0;
  for (std::size_t k = 0; k < five.size(); ++k) {
    largest_five = std::max(largest_five, five[k].norm());
    difference = std::max(difference, (five[k] - one[k]).norm());
  }
  std::printf("tips over 1.5 s: largest displacement %.4f m, largest difference %.3e m\n",
              largest_five, difference);
  EXPECT_GT(largest_five, 0.1);  // the reeds do bend
  EXPECT_LT(difference, 1e-4 * largest_five);
}

}  // namespace
}  // namespace cosim::vegetation

// Still water tank 0.2 m x 0.2 m, l0 = 0.01 m: time-averaged pressure within 2 % of rho g depth,
// and the water stays at rest.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"
#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

TEST(MpsStillWater, HydrostaticPressureAndRest) {
  const double width = 0.2, depth = 0.2, l0 = 0.01;
  // Seed 001's findings: a collision distance of 1.0 l0 steadies the free surface, and a wider
  // gradient radius (4.0 l0 here, 8.0 l0 in its fishway) gives a quieter pressure field.
  MpsParameters p = quiet_parameters(l0);
  FluidSystem system(p, still_water_tank(p, width, depth, 1.5 * depth));
  const double g = 9.81, rho = p.density;
  const auto start = std::chrono::steady_clock::now();
  // Settle for 1 s, then average over 1 s.
  while (system.time() < 1.0) system.step(system.stable_dt());
  const std::vector<double> depths{0.05, 0.1, 0.15};
  std::vector<double> sums(depths.size(), 0.0);
  int samples = 0;
  double max_speed = 0.0, max_height = 0.0;
  while (system.time() < 2.0) {
    const StepReport report = system.step(system.stable_dt());
    max_speed = std::max(max_speed, report.max_speed);
    for (std::size_t k = 0; k < depths.size(); ++k) {
      const Eigen::Vector3d point(0.5 * width, depth - depths[k], 0.0);
      sums[k] += mean_pressure_at(system, point, 1.5 * l0);
    }
    ++samples;
  }
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] == ParticleKind::fluid) {
      max_height = std::max(max_height, system.positions()[i].y());
    }
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "[still water] particles=" << system.particle_count()
            << " steps=" << system.step_count() << " wall=" << wall << " s max_speed=" << max_speed
            << " m/s top particle y=" << max_height << " m\n";
  for (std::size_t k = 0; k < depths.size(); ++k) {
    const double mean = sums[k] / samples;
    const double expected = rho * g * depths[k];
    std::cout << "  depth " << depths[k] << " m: p_mean=" << mean << " Pa, rho g h=" << expected
              << " Pa, error=" << 100.0 * (mean - expected) / expected << " %\n";
    EXPECT_NEAR(mean, expected, 0.02 * expected) << "depth " << depths[k];
  }
  // At rest: spurious speeds well below sqrt(g depth) = 1.4 m/s and no particle leaves the
  // surface (the top layer's centres start at depth - l0/2).
  EXPECT_LT(max_speed, 0.1);
  EXPECT_LT(max_height, depth + 0.5 * l0);
}

// The hydrostatic probe reads a hydrostatic field exactly wherever its sample's centroid lies;
// the plain mean reads rho g times the centroid's offset from the probe. A probe 0.3 l0 above a
// lattice row takes in one row more below than above it.
TEST(MpsStillWater, HydrostaticProbeIsExactOnAHydrostaticField) {
  const double l0 = 0.01, depth = 0.1;
  MpsParameters p = quiet_parameters(l0);
  FluidSystem settled(p, still_water_tank(p, 0.1, depth, 0.15));
  MpsState state = settled.save_state();
  const double rho_g = p.density * -p.gravity.y();
  for (std::size_t i = 0; i < state.positions.size(); ++i) {
    state.pressures[i] = rho_g * (depth - state.positions[i].y());
  }
  const FluidSystem system(p, state);
  const Eigen::Vector3d probe(0.05, 0.053, 0.0);  // 0.3 l0 above the row at 0.05 m
  const double exact = rho_g * (depth - probe.y());
  EXPECT_NEAR(hydrostatic_pressure_at(system, probe, 1.5 * l0), exact, 1e-9 * exact);
  const double plain = mean_pressure_at(system, probe, 1.5 * l0);
  EXPECT_GT(std::abs(plain - exact), 0.02 * exact) << "the sample's centroid is below the probe";
  EXPECT_EQ(hydrostatic_pressure_at(system, Eigen::Vector3d(0.05, 0.5, 0.0), 1.5 * l0), 0.0);
}

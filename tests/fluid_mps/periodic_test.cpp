// Periodic boundary in x (seed 001 section 2.2(4), seed 000 section 3.1): seam-free neighbour
// search, hydrostatic still water across the seam, driven channel acceleration and momentum
// balance at steady state.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/observers.hpp"

using namespace cosim::mps;

namespace {

int count_kind(const FluidSystem& system, ParticleKind kind) {
  int count = 0;
  for (auto k : system.kinds()) count += k == kind ? 1 : 0;
  return count;
}

// Mean pressure of fluid particles within `radius` of `point`, minimum-image distance.
double periodic_mean_pressure(const FluidSystem& system, const Eigen::Vector3d& point,
                              double radius) {
  const PeriodicBoundary& periodic = system.parameters().periodic;
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    if (periodic.wrap(system.positions()[i] - point).norm() < radius) {
      sum += system.pressures()[i];
      ++count;
    }
  }
  return count > 0 ? sum / count : 0.0;
}

MpsParameters quiet_parameters(double l0) {
  MpsParameters p;
  p.particle_spacing = l0;
  p.max_dt = 1e-3;
  p.collision_distance_ratio = 1.0;  // as the still-water test (seed 001's findings)
  p.collision_restitution = 0.2;
  p.radius_gradient_over_l0 = 4.0;
  return p;
}

}  // namespace

TEST(MpsPeriodic, FoldAndWrap) {
  PeriodicBoundary b;
  b.enabled = true;
  b.x_min = -0.1;
  b.x_max = 0.3;
  EXPECT_NEAR(b.fold(0.35), -0.05, 1e-15);
  EXPECT_NEAR(b.fold(-0.15), 0.25, 1e-15);
  EXPECT_NEAR(b.wrap(Eigen::Vector3d(0.39, 1.0, 0.0)).x(), -0.01, 1e-15);
  EXPECT_NEAR(b.wrap(Eigen::Vector3d(-0.3, 1.0, 0.0)).x(), 0.1, 1e-15);
}

TEST(MpsPeriodic, NumberDensityHasNoSeam) {
  MpsParameters p = quiet_parameters(0.01);
  FluidSystem system(p, periodic_channel(p, 0.2, 0.1));
  ASSERT_TRUE(system.parameters().periodic.enabled);
  // Interior fluid particles (>= 3 l0 from bed and surface): n = n0 of the full lattice,
  // whether at the seam or in the middle.
  const double l0 = p.particle_spacing;
  double worst = 0.0;
  int seam_particles = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    const Eigen::Vector3d& x = system.positions()[i];
    if (system.kinds()[i] != ParticleKind::fluid || x.y() < 3 * l0 || x.y() > 0.1 - 3 * l0) {
      continue;
    }
    if (x.x() < 2 * l0 || x.x() > 0.2 - 2 * l0) ++seam_particles;
    worst = std::max(worst, std::abs(system.number_densities()[i] - system.n0_density()));
  }
  EXPECT_GT(seam_particles, 0);
  EXPECT_LT(worst, 1e-9 * system.n0_density());
}

TEST(MpsPeriodic, StillWaterHydrostaticAcrossSeam) {
  const double length = 0.2, depth = 0.1, l0 = 0.01;
  MpsParameters p = quiet_parameters(l0);
  FluidSystem system(p, periodic_channel(p, length, depth));
  const int fluid = count_kind(system, ParticleKind::fluid);
  const double rho_g = p.density * 9.81;
  while (system.time() < 0.8) system.step(system.stable_dt());
  const std::vector<double> depths{0.025, 0.05, 0.075};
  const std::vector<double> xs{0.0, 0.5 * length};  // the seam and the middle
  std::vector<std::vector<double>> sums(xs.size(), std::vector<double>(depths.size(), 0.0));
  int samples = 0;
  double max_speed = 0.0;
  while (system.time() < 1.6) {
    max_speed = std::max(max_speed, system.step(system.stable_dt()).max_speed);
    for (std::size_t a = 0; a < xs.size(); ++a)
      for (std::size_t k = 0; k < depths.size(); ++k)
        sums[a][k] += periodic_mean_pressure(system, Eigen::Vector3d(xs[a], depth - depths[k], 0.0),
                                             1.5 * l0);
    ++samples;
  }
  EXPECT_EQ(count_kind(system, ParticleKind::fluid), fluid);
  for (int i = 0; i < system.particle_count(); ++i) {
    EXPECT_GE(system.positions()[i].x(), 0.0);
    EXPECT_LT(system.positions()[i].x(), length);
  }
  for (std::size_t a = 0; a < xs.size(); ++a)
    for (std::size_t k = 0; k < depths.size(); ++k) {
      const double mean = sums[a][k] / samples, expected = rho_g * depths[k];
      std::cout << "[periodic still water] x=" << xs[a] << " depth=" << depths[k] << " p=" << mean
                << " Pa rho g h=" << expected << " error=" << 100.0 * (mean - expected) / expected
                << " %\n";
      EXPECT_NEAR(mean, expected, 0.02 * expected) << "x " << xs[a] << " depth " << depths[k];
    }
  std::cout << "[periodic still water] max speed " << max_speed << " m/s\n";
  EXPECT_LT(max_speed, 0.1);
}

TEST(MpsPeriodic, DrivenChannelInitialAcceleration) {
  const double length = 0.2, depth = 0.1;
  MpsParameters p = quiet_parameters(0.01);
  p.periodic.driving_pressure_drop = 10.0;  // [Pa] over the period: a = dp / (rho L)
  FluidSystem system(p, periodic_channel(p, length, depth));
  const double a = 10.0 / (p.density * length);
  const double fluid_mass = count_kind(system, ParticleKind::fluid) * system.particle_mass();
  while (system.time() < 0.1 - 1e-12) system.step(5e-4);
  const double mean_u = system.total_fluid_momentum().x() / fluid_mass;
  std::cout << "[driven channel] t=" << system.time() << " mean u=" << mean_u
            << " expected a t=" << a * system.time() << "\n";
  EXPECT_NEAR(mean_u, a * system.time(), 0.01 * a * system.time());

  // The same with the slope as a gravity tilt (seed 000: slope 0.00304).
  MpsParameters q = quiet_parameters(0.01);
  FluidSystem sloped(q, periodic_channel(q, length, depth, 0.00304));
  while (sloped.time() < 0.1 - 1e-12) sloped.step(5e-4);
  const double sloped_u = sloped.total_fluid_momentum().x() / fluid_mass;
  EXPECT_NEAR(sloped_u, 9.81 * 0.00304 * sloped.time(), 0.01 * 9.81 * 0.00304 * sloped.time());
}

// Laminar periodic channel: at steady state the bed shear (viscous force of the wall particles)
// balances the driving force rho a H L; the mean velocity approaches a H^2 / (3 nu).
TEST(MpsPeriodic, SteadyChannelBedShearBalancesDrivingForce) {
  const double length = 0.1, depth = 0.05, l0 = 0.005, nu = 2e-3, a = 0.08;
  MpsParameters p = quiet_parameters(l0);
  p.kinematic_viscosity = nu;
  p.periodic.driving_pressure_drop = p.density * a * length;
  FluidSystem system(p, periodic_channel(p, length, depth));
  const double fluid_mass = count_kind(system, ParticleKind::fluid) * system.particle_mass();
  const double driving = fluid_mass * a;  // [N/m]
  Eigen::Vector3d shear = Eigen::Vector3d::Zero();
  double mean_u = 0.0;
  int samples = 0;
  ObservationPoints probe({{0.05, 0.5 * depth, 0.0}, {0.0, 0.5 * depth, 0.0}}, 1.5 * l0);
  while (system.time() < 3.0) {
    const StepReport report = system.step(system.stable_dt());
    if (system.time() > 2.5) {
      shear += report.wall_viscous_force;
      mean_u += system.total_fluid_momentum().x() / fluid_mass;
      probe.record(system);
      ++samples;
    }
  }
  shear /= samples;
  mean_u /= samples;
  const double poiseuille = a * depth * depth / (3.0 * nu);
  std::cout << "[steady channel] driving " << driving << " N/m, bed shear " << shear.x() << " N/m ("
            << 100.0 * (-shear.x() - driving) / driving << " %), mean u " << mean_u
            << " m/s, Poiseuille " << poiseuille << " m/s, probe mid-depth u "
            << probe.mean_velocity(0).x() << " / " << probe.mean_velocity(1).x() << " (seam)\n";
  EXPECT_NEAR(-shear.x(), driving, 0.05 * driving);
  EXPECT_NEAR(mean_u, poiseuille, 0.15 * poiseuille);
  // Same velocity at the seam as in the middle.
  EXPECT_NEAR(probe.mean_velocity(1).x(), probe.mean_velocity(0).x(),
              0.05 * probe.mean_velocity(0).x());
}

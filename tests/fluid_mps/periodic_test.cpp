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

#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

namespace {

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

// Still water in a periodic channel 0.2 m long and 0.2 m deep (l0 = 1 cm), sampled over
// 0.8-1.6 s: the mean pressure 0.15 m down, the largest speed and the mean kinetic energy.
struct StillWaterSample {
  double pressure = 0.0, max_speed = 0.0, kinetic_energy = 0.0;
};
StillWaterSample still_water_sample(const MpsParameters& p) {
  const double length = 0.2, depth = 0.2;
  MpsParameters q = p;
  FluidSystem system(q, periodic_channel(q, length, depth));
  const int fluid = count_kind(system, ParticleKind::fluid);
  StillWaterSample sample;
  int samples = 0;
  while (system.time() < 1.6) {
    const StepReport report = system.step(system.stable_dt());
    if (system.time() < 0.8) continue;
    sample.max_speed = std::max(sample.max_speed, report.max_speed);
    sample.pressure += periodic_mean_pressure(system, Eigen::Vector3d(0.1, depth - 0.15, 0.0),
                                              1.5 * p.particle_spacing);
    for (int i = 0; i < system.particle_count(); ++i) {
      if (system.kinds()[i] == ParticleKind::fluid)
        sample.kinetic_energy += 0.5 * system.velocities()[i].squaredNorm() / fluid;
    }
    ++samples;
  }
  sample.pressure /= samples;
  sample.kinetic_energy /= samples;
  return sample;
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
  // With a drop the downstream copy lies lower: leaving at x_max re-enters at x_min higher.
  b.drop = 0.05;
  const Eigen::Vector3d upstream = b.wrap(Eigen::Vector3d(0.39, 1.0, 0.0));
  EXPECT_NEAR(upstream.x(), -0.01, 1e-15);
  EXPECT_NEAR(upstream.y(), 1.05, 1e-15);
  const Eigen::Vector3d downstream = b.wrap(Eigen::Vector3d(-0.39, 1.0, 0.0));
  EXPECT_NEAR(downstream.x(), 0.01, 1e-15);
  EXPECT_NEAR(downstream.y(), 0.95, 1e-15);
  const Eigen::Vector3d reentered = b.fold(Eigen::Vector3d(0.31, 0.2, 0.0));
  EXPECT_NEAR(reentered.x(), -0.09, 1e-15);
  EXPECT_NEAR(reentered.y(), 0.25, 1e-15);
  const Eigen::Vector3d twice_back = b.fold(Eigen::Vector3d(-0.55, 0.2, 0.0));
  EXPECT_NEAR(twice_back.x(), 0.25, 1e-15);
  EXPECT_NEAR(twice_back.y(), 0.1, 1e-15);
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
  const double length = 0.2, depth = 0.2, l0 = 0.01;
  MpsParameters p = quiet_parameters(l0);
  FluidSystem system(p, periodic_channel(p, length, depth));
  const int fluid = count_kind(system, ParticleKind::fluid);
  const double rho_g = p.density * 9.81;
  while (system.time() < 0.8) system.step(system.stable_dt());
  const std::vector<double> depths{0.05, 0.1, 0.15};  // as MpsStillWater
  const std::vector<double> xs{0.0, 0.5 * length};    // the seam and the middle
  std::vector<std::vector<double>> sums(xs.size(), std::vector<double>(depths.size(), 0.0));
  int samples = 0;
  double max_speed = 0.0, level_sum = 0.0;
  while (system.time() < 1.6) {
    max_speed = std::max(max_speed, system.step(system.stable_dt()).max_speed);
    for (std::size_t a = 0; a < xs.size(); ++a)
      for (std::size_t k = 0; k < depths.size(); ++k)
        sums[a][k] += periodic_mean_pressure(system, Eigen::Vector3d(xs[a], depth - depths[k], 0.0),
                                             1.5 * l0);
    // Free-surface level: mean height of the top particles plus l0/2.
    double top_sum = 0.0;
    int top_count = 0;
    for (int i = 0; i < system.particle_count(); ++i) {
      const double y = system.positions()[i].y();
      if (system.kinds()[i] == ParticleKind::fluid && y > depth - l0) {
        top_sum += y;
        ++top_count;
      }
    }
    level_sum += top_sum / top_count + 0.5 * l0;
    ++samples;
  }
  std::cout << "[periodic still water] mean surface level " << level_sum / samples << " m\n";
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
      // A perfect lattice column is 2-3 % high one fifth below the surface whatever the
      // collision and gradient settings (tank walls perturb it less): 3 % there, 2 % below.
      const double tolerance = depths[k] < 0.075 ? 0.03 : 0.02;
      EXPECT_NEAR(mean, expected, tolerance * expected) << "x " << xs[a] << " depth " << depths[k];
      if (a > 0) {  // no seam: the same pressure at the seam as mid-channel
        EXPECT_NEAR(sums[0][k] / samples, mean, 0.005 * expected);
      }
    }
  std::cout << "[periodic still water] max speed " << max_speed << " m/s\n";
  EXPECT_LT(max_speed, 0.1);
}

// Mean x velocity of the fluid particles with y >= y_min.
double mean_u_above(const FluidSystem& system, double y_min) {
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid || system.positions()[i].y() < y_min) continue;
    sum += system.velocities()[i].x();
    ++count;
  }
  return sum / count;
}

// From rest, the driving pressure difference accelerates the water at a = dp / (rho L). Without
// gravity there is no pressure and the whole water follows a t exactly; with gravity the fluid
// beyond the Laplacian radius of the bed does (the lowest rows slide over the particle bed).
TEST(MpsPeriodic, DrivenChannelInitialAcceleration) {
  const double length = 0.2, depth = 0.1, l0 = 0.01;
  MpsParameters p = quiet_parameters(l0);
  p.periodic.driving_pressure_drop = 10.0;  // [Pa] over the period
  const double a = 10.0 / (p.density * length);
  MpsParameters weightless = p;
  weightless.gravity.setZero();
  FluidSystem free(weightless, periodic_channel(weightless, length, depth));
  const double fluid_mass = count_kind(free, ParticleKind::fluid) * free.particle_mass();
  while (free.time() < 0.1 - 1e-12) free.step(5e-4);
  const double free_u = free.total_fluid_momentum().x() / fluid_mass;
  EXPECT_NEAR(free_u, a * free.time(), 1e-3 * a * free.time());

  FluidSystem system(p, periodic_channel(p, length, depth));
  while (system.time() < 0.1 - 1e-12) system.step(5e-4);
  const double interior_u = mean_u_above(system, 4.0 * l0);
  std::cout << "[driven channel] t=" << system.time() << " a t=" << a * system.time()
            << " mean u (no gravity)=" << free_u << " interior mean u=" << interior_u
            << " whole-water mean u=" << system.total_fluid_momentum().x() / fluid_mass << "\n";
  EXPECT_NEAR(interior_u, a * system.time(), 0.01 * a * system.time());

  // The same with the slope as a gravity tilt (seed 000 section 3.1: slope 0.00304).
  MpsParameters q = quiet_parameters(l0);
  FluidSystem sloped(q, periodic_channel(q, length, depth, 0.00304));
  EXPECT_NEAR(sloped.parameters().gravity.x(), 9.81 * 0.00304, 1e-12);
  while (sloped.time() < 0.1 - 1e-12) sloped.step(5e-4);
  const double expected = 9.81 * 0.00304 * sloped.time();
  EXPECT_NEAR(mean_u_above(sloped, 4.0 * l0), expected, 0.01 * expected);
}

// Laminar periodic channel: at steady state the bed shear (viscous force of the wall particles)
// balances the driving force rho a H L; the mean velocity approaches a H^2 / (3 nu).
TEST(MpsPeriodic, SteadyChannelBedShearBalancesDrivingForce) {
  const double length = 0.1, depth = 0.05, l0 = 0.005, nu = 0.02, a = 1.0;
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
  // Slowest viscous mode decays as exp(-pi^2 nu t / (4 H^2)) = exp(-20 t): steady after 0.5 s.
  while (system.time() < 1.0) {
    const StepReport report = system.step(system.stable_dt());
    if (system.time() > 0.5) {
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
  EXPECT_NEAR(-shear.x(), driving, 0.03 * driving);
  // MPS walls slip (the Laplacian sees the wall layers within 4 l0): about +27 % at 10 layers.
  EXPECT_GT(mean_u, 0.9 * poiseuille);
  EXPECT_LT(mean_u, 1.4 * poiseuille);
  // Same velocity at the seam as in the middle.
  EXPECT_NEAR(probe.mean_velocity(1).x(), probe.mean_velocity(0).x(),
              0.05 * probe.mean_velocity(0).x());
}

// A water hump moving through the seam: shifting the whole scene by half a period gives the same
// motion (up to solver round-off), so the seam is invisible to every operator.
TEST(MpsPeriodic, SeamPlacementDoesNotMatter) {
  const double length = 0.2, depth = 0.06, l0 = 0.01;
  MpsParameters p = quiet_parameters(l0);
  p.periodic.driving_pressure_drop = 200.0;  // pushes the hump across the seam
  ParticleSet set = periodic_channel(p, length, depth);
  for (int iy = 0; iy < 4; ++iy)
    for (int ix = 0; ix < 5; ++ix)
      set.add(Eigen::Vector3d(0.145 + (ix + 0.5) * l0, depth + (iy + 0.5) * l0, 0.0),
              ParticleKind::fluid);
  ParticleSet shifted = set;
  for (auto& x : shifted.positions) x.x() = p.periodic.fold(x.x() + 0.5 * length);
  FluidSystem a(p, set), b(p, shifted);
  double worst = 0.0;
  for (int k = 0; k < 300; ++k) {
    a.step(5e-4);
    b.step(5e-4);
  }
  for (int i = 0; i < a.particle_count(); ++i) {
    const Eigen::Vector3d back(p.periodic.fold(b.positions()[i].x() - 0.5 * length),
                               b.positions()[i].y(), 0.0);
    worst = std::max(worst, p.periodic.wrap(back - a.positions()[i]).norm());
  }
  double top_x = 0.0, top_y = 0.0;
  for (int i = 0; i < a.particle_count(); ++i) {
    if (a.kinds()[i] == ParticleKind::fluid && a.positions()[i].y() > top_y) {
      top_y = a.positions()[i].y();
      top_x = a.positions()[i].x();
    }
  }
  std::cout << "[seam placement] max position difference " << worst << " m after " << a.time()
            << " s; highest particle at x=" << top_x << "\n";
  EXPECT_LT(worst, 1e-3 * l0);
}

// Seed 000 section 3.1 geometry: depth 0.084 m, slope 0.00304 (l0 = 2 mm as in seed 000).
TEST(MpsPeriodic, Seed000ChannelGeometry) {
  MpsParameters p;
  p.particle_spacing = 0.002;
  const ParticleSet set = periodic_channel(p, 0.1, 0.084, 0.00304);
  int fluid = 0, wall = 0, dummy = 0;
  double top = 0.0;
  for (std::size_t i = 0; i < set.size(); ++i) {
    fluid += set.kinds[i] == ParticleKind::fluid;
    wall += set.kinds[i] == ParticleKind::wall;
    dummy += set.kinds[i] == ParticleKind::dummy;
    if (set.kinds[i] == ParticleKind::fluid) top = std::max(top, set.positions[i].y());
  }
  EXPECT_EQ(fluid, 50 * 42);
  EXPECT_EQ(wall, 2 * 50);
  EXPECT_EQ(dummy, 2 * 50);
  EXPECT_NEAR(top + 0.001, 0.084, 1e-12);
  EXPECT_NEAR(p.gravity.x(), 9.81 * 0.00304, 1e-12);
  EXPECT_NEAR(p.gravity.norm(), 9.81, 1e-12);
  EXPECT_TRUE(p.periodic.enabled);
  EXPECT_NEAR(p.periodic.length(), 0.1, 1e-12);
  FluidSystem system(p, set);  // valid: period 0.1 m > 3 x 4 l0
  EXPECT_EQ(system.particle_count(), static_cast<int>(set.size()));
}

// The fluid's own pressure forces: with the symmetric (CMPS) gradient every fluid-fluid pair
// force is equal and opposite, so the pressure impulse the fluid receives is the walls' share
// alone; the Koshizuka-Oka minimum form creates momentum of its own. A hump of water falling
// into a driven channel gives strong, uneven pressure.
TEST(MpsPeriodic, SymmetricGradientConservesFluidMomentum) {
  const double length = 0.2, depth = 0.06, l0 = 0.01;
  auto run = [&](MpsParameters::GradientForm form) {
    MpsParameters p = quiet_parameters(l0);
    p.gradient_form = form;
    p.periodic.driving_pressure_drop = 50.0;
    ParticleSet set = periodic_channel(p, length, depth);
    for (int iy = 0; iy < 4; ++iy)
      for (int ix = 0; ix < 5; ++ix)
        set.add(Eigen::Vector3d(0.1 + (ix + 0.5) * l0, depth + (iy + 0.5) * l0, 0.0),
                ParticleKind::fluid);
    FluidSystem system(p, set);
    Eigen::Vector3d fluid_fluid = Eigen::Vector3d::Zero(), total = Eigen::Vector3d::Zero();
    double magnitude = 0.0;
    for (int k = 0; k < 400; ++k) {
      const StepReport report = system.step(5e-4);
      fluid_fluid += report.pressure_impulse - report.wall_pressure_impulse;
      total += report.pressure_impulse;
      magnitude += report.pressure_impulse.norm();
    }
    std::cout << "[gradient form " << static_cast<int>(form) << "] fluid-fluid pressure impulse ("
              << fluid_fluid.x() << ", " << fluid_fluid.y() << ") of total (" << total.x() << ", "
              << total.y() << ") N s/m\n";
    return std::pair{fluid_fluid.norm(), magnitude};
  };
  const auto [symmetric, symmetric_magnitude] = run(MpsParameters::GradientForm::symmetric);
  const auto [minimum, minimum_magnitude] = run(MpsParameters::GradientForm::minimum);
  EXPECT_LT(symmetric, 1e-12 * symmetric_magnitude);
  EXPECT_GT(minimum, 1e-3 * minimum_magnitude);  // the non-conservation the option removes
}

// The symmetric form keeps still water hydrostatic and near rest, though noisier than the
// minimum form (about 17 times the kinetic energy at l0 = 1 cm; the p_i sum pulls particles to
// lattice sites).
TEST(MpsPeriodic, SymmetricGradientKeepsStillWaterHydrostatic) {
  std::vector<double> kinetic_energy;
  for (const auto form :
       {MpsParameters::GradientForm::minimum, MpsParameters::GradientForm::symmetric}) {
    MpsParameters p = quiet_parameters(0.01);
    p.gradient_form = form;
    const StillWaterSample sample = still_water_sample(p);
    const double expected = p.density * 9.81 * 0.15;
    kinetic_energy.push_back(sample.kinetic_energy);
    std::cout << "[still water, gradient form " << static_cast<int>(form) << "] p at 0.15 m depth "
              << sample.pressure << " Pa vs " << expected << " Pa, max speed " << sample.max_speed
              << " m/s, mean kinetic energy " << sample.kinetic_energy << " J/kg\n";
    EXPECT_NEAR(sample.pressure, expected, 0.03 * expected);
    EXPECT_LT(sample.max_speed, 0.2);
  }
  std::cout << "[still water] kinetic energy symmetric / minimum "
            << kinetic_energy[1] / kinetic_energy[0] << "\n";
}

// Still water keeps its hydrostatic pressure with the hydrostatic background and shifting (the
// rigid_canopy bundle's set, issue 16), with q's repulsion and with the whole pressure's (the
// bundle's). With q's it moves less than with the minimum form alone; with the whole pressure's
// it moves about as much (measured 1.18 times here, 0.88 times in scenarios/still_water): in 2D
// that repulsion is not needed to keep water at rest (in 3D it is: fill_lattice_settling_test).
TEST(MpsPeriodic, HydrostaticBackgroundKeepsStillWaterHydrostatic) {
  MpsParameters plain = quiet_parameters(0.01);
  plain.radius_gradient_over_l0 = 4.0;
  const StillWaterSample reference = still_water_sample(plain);
  const double expected = plain.density * 9.81 * 0.15;
  for (const auto repulsion :
       {MpsParameters::BackgroundRepulsion::dynamic, MpsParameters::BackgroundRepulsion::full}) {
    MpsParameters p = plain;
    p.pressure_background = MpsParameters::PressureBackground::hydrostatic;
    p.background_repulsion = repulsion;
    p.shifting_coefficient = 2.0;
    const StillWaterSample sample = still_water_sample(p);
    std::cout << "[still water, hydrostatic background, repulsion " << static_cast<int>(repulsion)
              << "] p at 0.15 m depth " << sample.pressure << " Pa vs " << expected
              << " Pa (minimum form alone " << reference.pressure << "), max speed "
              << sample.max_speed << " m/s, mean kinetic energy " << sample.kinetic_energy
              << " J/kg (minimum form alone " << reference.kinetic_energy << ")\n";
    EXPECT_NEAR(sample.pressure, expected, 0.02 * expected);
    EXPECT_LT(sample.max_speed, 0.2);
    if (repulsion == MpsParameters::BackgroundRepulsion::dynamic) {
      EXPECT_LT(sample.kinetic_energy, reference.kinetic_energy);
    }
  }
}

// Elements in prescribed still fluid against closed forms and references/settling_and_floating.md:
// terminal velocities (ten Cate et al. 2002 case E1 with Schiller-Naumann, a rising s.g. 0.01
// sphere, a log in crossflow), the added-mass start, Di Felice hindered settling in a lattice,
// and hydrostatic floating of a log and a sphere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/fluid_forces.hpp"

namespace cosim::dem {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kG = 9.81;

// Case E1 of ten Cate et al. (2002): nylon sphere in silicone oil.
constexpr double kDiameter = 0.015;
constexpr double kSphereDensity = 1120.0;
constexpr double kOilDensity = 970.0;
constexpr double kOilViscosity = 0.373;

DemParameters still_fluid(double rho_f, double mu) {
  DemParameters p;
  p.fluid_density = rho_f;
  p.fluid_viscosity = mu;
  p.drag_law = DragLaw::kSchillerNaumann;
  p.fluid_acceleration_force = true;
  p.added_mass = true;
  return p;
}

// Still, deep fluid at every moving element.
FluidAtElements submerged(const DemWorld& world) {
  FluidAtElements fluid;
  fluid.velocity.assign(world.moving_elements().size(), Eigen::Vector3d::Zero());
  fluid.water_fraction.assign(world.moving_elements().size(), 1.0);
  return fluid;
}

// Speed v > 0 where drag(v) equals the net weight (bisection; drag increases with v).
double terminal_speed(const std::function<double(double)>& drag, double net_weight) {
  double low = 0.0, high = 1.0;
  while (drag(high) < net_weight) high *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double middle = 0.5 * (low + high);
    (drag(middle) < net_weight ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

double sphere_drag(double v, double d, double rho, double mu) {
  return 0.5 * schiller_naumann_drag_coefficient(rho * v * d / mu) * rho * kPi * d * d / 4 * v * v;
}

TEST(FluidSettling, TenCateE1SphereReachesTheSchillerNaumannTerminalVelocity) {
  DemWorld world(still_fluid(kOilDensity, kOilViscosity));
  Material nylon;
  nylon.density = kSphereDensity;
  const int s = world.add_sphere({0, 0, 0}, 0.5 * kDiameter, nylon);
  const FluidAtElements fluid = submerged(world);
  for (int w = 0; w < 150; ++w) world.advance(0.01, fluid);
  const double volume = kPi * kDiameter * kDiameter * kDiameter / 6;
  const double expected =
      terminal_speed([](double v) { return sphere_drag(v, kDiameter, kOilDensity, kOilViscosity); },
                     (kSphereDensity - kOilDensity) * volume * kG);
  const double measured = -world.velocity(s).z();
  std::printf("E1 sphere after 1.5 s: %.5f m/s (force balance %.5f, Re %.2f; reference 0.0409)\n",
              measured, expected, kOilDensity * measured * kDiameter / kOilViscosity);
  EXPECT_NEAR(measured, 0.0409, 0.005 * 0.0409);
  EXPECT_NEAR(measured, expected, 1e-4 * expected);
  EXPECT_LT(std::abs(world.velocity(s).x()) + std::abs(world.velocity(s).y()), 1e-15);
}

TEST(FluidSettling, AddedMassSlowsTheInitialAcceleration) {
  // Over the first 0.2 ms the E1 sphere reaches 0.2 mm/s: Stokes drag is 0.4 % of the net
  // weight, so the mean acceleration is the inviscid one, (rho_s - rho_f) / (rho_s + C_a rho_f) g.
  for (const bool added : {true, false}) {
    DemParameters p = still_fluid(kOilDensity, kOilViscosity);
    p.added_mass = added;
    p.user_dt = 1e-6;
    DemWorld world(p);
    Material nylon;
    nylon.density = kSphereDensity;
    const int s = world.add_sphere({0, 0, 0}, 0.5 * kDiameter, nylon);
    world.advance(2e-4, submerged(world));
    const double measured = -world.velocity(s).z() / 2e-4;
    const double c_a = added ? 0.5 : 0.0;
    const double expected =
        (kSphereDensity - kOilDensity) / (kSphereDensity + c_a * kOilDensity) * kG;
    std::printf("added mass %s: mean acceleration over 0.2 ms %.5f m/s^2 (inviscid %.5f)\n",
                added ? "on " : "off", measured, expected);
    EXPECT_NEAR(measured, expected, 0.005 * expected);
  }
}

TEST(FluidSettling, LightSphereRisesStablyToItsTerminalVelocity) {
  // s.g. 0.01 in water: the added mass is 50 times the sphere's own, an explicit added-mass
  // force (dv/dt of the previous step) would multiply errors by -50 per step.
  const double d = 0.01;
  const double rho_s = 10.0;
  DemWorld world(still_fluid(1000.0, 1.0e-3));
  Material foam;
  foam.density = rho_s;
  const int s = world.add_sphere({0, 0, 0}, 0.5 * d, foam);
  const FluidAtElements fluid = submerged(world);
  double previous = 0.0;
  bool monotonic = true;
  for (int w = 0; w < 300; ++w) {
    world.advance(1e-3, fluid);
    monotonic = monotonic && world.velocity(s).z() >= previous;
    previous = world.velocity(s).z();
  }
  const double volume = kPi * d * d * d / 6;
  const double expected = terminal_speed([&](double v) { return sphere_drag(v, d, 1000.0, 1e-3); },
                                         (1000.0 - rho_s) * volume * kG);
  std::printf("s.g. 0.01 sphere after 0.3 s: %.5f m/s (force balance %.5f, Re %.0f)\n",
              world.velocity(s).z(), expected, 1000 * expected * d / 1e-3);
  EXPECT_TRUE(monotonic);  // no overshoot or oscillation on the way up
  EXPECT_NEAR(world.velocity(s).z(), expected, 0.005 * expected);
}

TEST(FluidSettling, LogRisesBroadsideAtTheCrossflowTerminalVelocity) {
  // A 10 x 100 mm log of s.g. 0.8 (seed 004) rising broadside in water: buoyancy less weight
  // balances White's crossflow drag 0.5 C_D(Re) rho D L v^2.
  const double d = 0.01, length = 0.1, rho_s = 800.0;
  DemWorld world(still_fluid(1000.0, 1.0e-3));
  Material wood;
  wood.density = rho_s;
  const int log =
      world.add_cylinder({0, 0, 0}, Eigen::Vector3d(1, 1, 0).normalized(), 0.5 * d, length, wood);
  const FluidAtElements fluid = submerged(world);
  for (int w = 0; w < 1000; ++w) world.advance(1e-3, fluid);
  const double expected = terminal_speed(
      [&](double v) {
        return 0.5 * cylinder_crossflow_drag_coefficient(1000.0 * v * d / 1e-3) * 1000.0 * d *
               length * v * v;
      },
      (1000.0 - rho_s) * kPi * d * d / 4 * length * kG);
  std::printf("log rising broadside after 1 s: %.5f m/s (force balance %.5f, Re %.0f)\n",
              world.velocity(log).z(), expected, 1000 * expected * d / 1e-3);
  EXPECT_NEAR(world.velocity(log).z(), expected, 0.005 * expected);
  EXPECT_LT(std::abs(world.axis(log).z()), 1e-12);  // no fluid torque: stays broadside
}

TEST(FluidSettling, VoidageCorrectionHindersSettlingInALattice) {
  // 9 x 9 x 9 E1 spheres, spacing 1.5 D (solid fraction 0.155), all settling; averaging radius
  // 2.5 spacings. The central sphere's neighbourhood (and its neighbours') is a full lattice,
  // so it settles at the Di Felice terminal velocity at its eps:
  // (rho_s - rho_f) V g = 0.5 C_D(Re_eps) rho_f A eps^(2 - chi(Re_eps)) v^2, Re_eps = rho eps v D /
  // mu.
  const double spacing = 1.5 * kDiameter;
  DemParameters p = still_fluid(kOilDensity, kOilViscosity);
  p.voidage_correction = true;
  p.voidage_radius = 2.5 * spacing;
  DemWorld world(p);
  Material nylon;
  nylon.density = kSphereDensity;
  int center = -1;
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j)
      for (int k = -4; k <= 4; ++k) {
        const int id = world.add_sphere(Eigen::Vector3d(i, j, k) * spacing, 0.5 * kDiameter, nylon);
        if (i == 0 && j == 0 && k == 0) center = id;
      }
  const FluidAtElements fluid = submerged(world);
  world.advance(0.01, fluid);
  const int middle = static_cast<int>(world.moving_elements().size()) / 2;
  ASSERT_EQ(world.moving_elements()[middle], center);
  const double eps = world.voidage()[middle];
  for (int w = 1; w < 100; ++w) world.advance(0.01, fluid);
  const double volume = kPi * kDiameter * kDiameter * kDiameter / 6;
  const double net_weight = (kSphereDensity - kOilDensity) * volume * kG;
  const double hindered = terminal_speed(
      [&](double v) {
        const double re = kOilDensity * eps * v * kDiameter / kOilViscosity;
        return sphere_drag(eps * v, kDiameter, kOilDensity, kOilViscosity) *
               std::pow(eps, -di_felice_exponent(re));
      },
      net_weight);
  const double single = terminal_speed(
      [](double v) { return sphere_drag(v, kDiameter, kOilDensity, kOilViscosity); }, net_weight);
  const double measured = -world.velocity(center).z();
  const double phi = volume / (spacing * spacing * spacing);
  std::printf(
      "lattice phi %.4f: eps %.4f (at 1 s %.4f); centre %.5f m/s, Di Felice %.5f, single %.5f "
      "(ratio %.4f; Richardson-Zaki slip eps^(n-1) %.4f)\n",
      phi, eps, world.voidage()[middle], measured, hindered, single, measured / single,
      std::pow(1 - phi,
               4.4 * std::pow(kOilDensity * single * kDiameter / kOilViscosity, -0.1) - 1));
  EXPECT_NEAR(1 - eps, phi, 3e-3 * phi);
  EXPECT_NEAR(world.voidage()[middle], eps, 1e-4);  // the lattice round it is still regular
  EXPECT_NEAR(measured, hindered, 0.005 * hindered);
  EXPECT_LT(measured, 0.9 * single);
}

TEST(FluidFloating, LogAndSphereComeToRestAtTheirHydrostaticDraft) {
  // Released half-submerged in glycerol (rho 1261, mu 1.41 Pa s); the equilibrium does not
  // depend on the fluid's viscosity. The drag falls faster than linearly with speed (the
  // crossflow fit goes as v^(4/3) at low Re), so the last of the log's heave (period 0.5 s)
  // dies out slowly: the draft is averaged over the last 10 s (20 periods), which leaves
  // (amplitude) / (20 pi) of the residual swing.
  const double rho_f = 1261.0;
  DemWorld world(still_fluid(rho_f, 1.41));
  Material wood;
  wood.density = 0.8 * rho_f;
  Material cork;
  cork.density = 0.3 * rho_f;
  const double d = 0.05;
  const int log = world.add_cylinder({0, 0, 0}, Eigen::Vector3d::UnitX(), 0.5 * d, 0.5, wood);
  const int ball = world.add_sphere({0, 1.0, 0}, 0.5 * d, cork);
  FluidAtElements fluid = submerged(world);
  fluid.surface_elevation = {0.0, 0.0};
  double mean_log_z = 0.0;
  double log_z_low = 1.0, log_z_high = -1.0;
  const int windows = 2000;
  for (int w = 0; w < windows; ++w) {
    world.advance(0.01, fluid);
    if (w < windows / 2) continue;
    const double z = world.position(log).z();
    mean_log_z += z / (windows / 2);
    log_z_low = std::min(log_z_low, z);
    log_z_high = std::max(log_z_high, z);
  }
  // Exact drafts: segment share 0.8 (0.746 D in settling_and_floating.md), cap share 0.3.
  const auto draft_for = [&](const std::function<double(double)>& share, double target) {
    double low = 0.0, high = 1.0;
    for (int i = 0; i < 100; ++i) {
      const double middle = 0.5 * (low + high);
      (share(middle) < target ? low : high) = middle;
    }
    return low;
  };
  const double log_draft = draft_for(
      [&](double x) {
        return cylinder_submerged_fraction(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                           0.5 * d, 0.5, -0.5 * d + x * d);
      },
      0.8);
  const double ball_draft = draft_for(
      [&](double x) { return sphere_submerged_fraction(0.0, 0.5 * d, -0.5 * d + x * d); }, 0.3);
  const double measured_log = (0.5 * d - mean_log_z) / d;
  const double measured_ball = (0.5 * d - world.position(ball).z()) / d;
  const double swing = (log_z_high - log_z_low) / d;
  std::printf(
      "10-20 s: log draft %.5f D (exact %.5f, reference 0.746; swing %.1e D), sphere at "
      "20 s %.5f D (exact %.5f, speed %.1e m/s)\n",
      measured_log, log_draft, swing, measured_ball, ball_draft, world.velocity(ball).norm());
  EXPECT_NEAR(measured_log, 0.746, 5e-4);
  EXPECT_NEAR(measured_log, log_draft, 1e-4 + swing / (20 * kPi));
  EXPECT_NEAR(measured_ball, ball_draft, 1e-4);
  EXPECT_NEAR(world.submerged_fraction()[1], 0.3, 1e-4);
}

}  // namespace
}  // namespace cosim::dem

// Fluid forces in DemWorld: momentum bookkeeping of the window-mean fluid force, the implicit
// added mass at the first sub-step, and the input checks of advance().
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/fluid_forces.hpp"

namespace cosim::dem {
namespace {

constexpr double kPi = std::numbers::pi;

DemParameters full_force_set() {
  DemParameters p;
  p.drag_law = DragLaw::kSchillerNaumann;
  p.fluid_viscosity = 1e-3;
  p.fluid_acceleration_force = true;
  p.added_mass = true;
  return p;
}

// Sum over moving elements of m dv over one window, less gravity's impulse: what the fluid (and
// contacts, which cancel between moving elements) gave.
Eigen::Vector3d momentum(const DemWorld& world) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (const int i : world.moving_elements()) p += world.mass(i) * world.velocity(i);
  return p;
}

TEST(FluidWorld, ImpulseFromTheFluidIsTheMeanFluidForceTimesTheWindow) {
  for (const bool seed_law : {false, true}) {
    DemParameters p = seed_law ? DemParameters{} : full_force_set();
    if (!seed_law) {
      p.voidage_correction = true;
      p.voidage_radius = 0.1;
    }
    DemWorld world(p);
    Material stone;
    Material wood;
    wood.density = 800;
    Material foam;
    foam.density = 10;  // s.g. 0.01: added mass 50 times its own
    // A log and a sphere pressed together (their contact forces cancel in the sum), a light
    // sphere across the free surface, a tilted log partly dry.
    world.add_cylinder({0, 0, 0}, Eigen::Vector3d::UnitY(), 0.02, 0.3, wood);
    world.add_sphere({0, 0, 0.0499}, 0.03, stone);
    world.add_sphere({0.5, 0, 0.1}, 0.01, foam);
    world.add_cylinder({-0.5, 0, 0.08}, Eigen::Vector3d(1, 0, 1).normalized(), 0.015, 0.4, wood);
    FluidAtElements fluid;
    fluid.velocity = {{0.3, 0, 0.05}, {0.2, 0.1, 0}, {-0.1, 0, 0.2}, {0.4, 0, 0}};
    fluid.acceleration = {{1.0, 0, -0.5}, {0, 2.0, 0}, {-3.0, 0, 1.0}, {0.5, 0.5, 0.5}};
    const double nan = std::numeric_limits<double>::quiet_NaN();
    fluid.surface_elevation = {nan, 0.06, 0.105, 0.1};
    fluid.water_fraction = {0.7, 1.0, 1.0, 1.0};
    const Eigen::Vector3d g = p.gravity;
    double total_mass = 0.0;
    for (const int i : world.moving_elements()) total_mass += world.mass(i);
    for (int window = 0; window < 5; ++window) {
      const Eigen::Vector3d before = momentum(world);
      std::vector<Eigen::Vector3d> single_before;
      for (const int i : world.moving_elements()) {
        single_before.push_back(world.mass(i) * world.velocity(i));
      }
      const double dt = 2e-3;
      world.advance(dt, fluid);
      if (window == 0) {
        ASSERT_GT(world.contact_count(), 0);
      }
      Eigen::Vector3d fluid_impulse = Eigen::Vector3d::Zero();
      for (const auto& f : world.window_mean_fluid_force()) fluid_impulse += f * dt;
      const Eigen::Vector3d received = momentum(world) - before - total_mass * g * dt;
      const double scale = fluid_impulse.norm() + total_mass * g.norm() * dt;
      EXPECT_LT((received - fluid_impulse).norm(), 1e-13 * scale) << "seed law " << seed_law;
      // The elements without contacts, one by one.
      for (const int k : {2, 3}) {
        const int i = world.moving_elements()[k];
        const Eigen::Vector3d own =
            world.mass(i) * world.velocity(i) - single_before[k] - world.mass(i) * g * dt;
        EXPECT_LT((own - world.window_mean_fluid_force()[k] * dt).norm(), 1e-13 * scale);
      }
    }
    // The light sphere and the tilted log are partly wet, the first log only by water fraction.
    EXPECT_DOUBLE_EQ(world.submerged_fraction()[0], 0.7);
    EXPECT_GT(world.submerged_fraction()[2], 0.0);
    EXPECT_LT(world.submerged_fraction()[2], 1.0);
    EXPECT_LT(world.submerged_fraction()[3], 1.0);
    if (!seed_law) {
      EXPECT_LT(world.voidage()[0], 1.0);
    }
  }
}

// First sub-step from rest in still fluid: drag is zero, so the acceleration is exactly what
// buoyancy, the fluid's acceleration and the added mass make of gravity.
Eigen::Vector3d first_acceleration(DemParameters p, bool sphere, const Eigen::Vector3d& axis,
                                   double density, const Eigen::Vector3d& fluid_acceleration) {
  p.user_dt = 1e-6;
  DemWorld world(p);
  Material m;
  m.density = density;
  const int e = sphere ? world.add_sphere({0, 0, 0}, 0.01, m)
                       : world.add_cylinder({0, 0, 0}, axis, 0.01, 0.2, m);
  FluidAtElements fluid;
  fluid.velocity = {Eigen::Vector3d::Zero()};
  fluid.acceleration = {fluid_acceleration};
  fluid.water_fraction = {1.0};
  world.advance(1e-6, fluid);
  return world.velocity(e) / 1e-6;
}

TEST(FluidWorld, ImplicitAddedMassGivesTheClosedFormStartingAcceleration) {
  const double rho_f = 1000.0;
  const double g = 9.81;
  DemParameters p = full_force_set();
  for (const double rho_s : {10.0, 800.0, 2650.0}) {
    // Sphere: (rho_s - rho_f) / (rho_s + C_a rho_f) g, C_a = 0.5.
    const Eigen::Vector3d a =
        first_acceleration(p, true, Eigen::Vector3d::UnitZ(), rho_s, Eigen::Vector3d::Zero());
    EXPECT_NEAR(a.z(), -(rho_s - rho_f) / (rho_s + 0.5 * rho_f) * g, 1e-12 * g) << rho_s;
    // Log across gravity: C_n = 1; along it: C_t = 0.
    const Eigen::Vector3d across =
        first_acceleration(p, false, Eigen::Vector3d::UnitX(), rho_s, Eigen::Vector3d::Zero());
    EXPECT_NEAR(across.z(), -(rho_s - rho_f) / (rho_s + rho_f) * g, 1e-12 * g) << rho_s;
    const Eigen::Vector3d along =
        first_acceleration(p, false, Eigen::Vector3d::UnitZ(), rho_s, Eigen::Vector3d::Zero());
    EXPECT_NEAR(along.z(), -(rho_s - rho_f) / rho_s * g, 1e-12 * g) << rho_s;
    // Without added mass: (rho_s - rho_f) / rho_s g.
    DemParameters no_added = p;
    no_added.added_mass = false;
    EXPECT_NEAR(
        first_acceleration(no_added, true, Eigen::Vector3d::UnitZ(), rho_s, Eigen::Vector3d::Zero())
            .z(),
        -(rho_s - rho_f) / rho_s * g, 1e-12 * g);
  }
  // A sphere in a fluid accelerating at A, without gravity: pressure gradient plus added mass
  // give a = (1 + C_a) rho_f / (rho_s + C_a rho_f) A (3 A for a massless bubble, A when
  // neutrally buoyant).
  p.gravity.setZero();
  const Eigen::Vector3d fluid_acceleration(2.0, -1.0, 0.5);
  for (const double rho_s : {1.0, 1000.0, 4000.0}) {
    const Eigen::Vector3d a =
        first_acceleration(p, true, Eigen::Vector3d::UnitZ(), rho_s, fluid_acceleration);
    const Eigen::Vector3d expected = 1.5 * rho_f / (rho_s + 0.5 * rho_f) * fluid_acceleration;
    EXPECT_LT((a - expected).norm(), 1e-12 * expected.norm()) << rho_s;
  }
}

TEST(FluidWorld, AdvanceChecksItsFluidInputs) {
  DemParameters p = full_force_set();
  DemWorld world(p);
  Material m;
  world.add_sphere({0, 0, 0}, 0.01, m);
  world.add_sphere({0.1, 0, 0}, 0.01, m);
  FluidAtElements fluid;
  fluid.velocity = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  EXPECT_THROW(world.advance(1e-3, fluid), std::invalid_argument);  // no water fraction
  fluid.surface_elevation = {0.0, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_THROW(world.advance(1e-3, fluid), std::invalid_argument);  // one surface unknown
  fluid.surface_elevation = {0.0, -std::numeric_limits<double>::infinity()};
  EXPECT_NO_THROW(world.advance(1e-3, fluid));  // every surface known: no fraction needed
  EXPECT_NEAR(world.submerged_fraction()[0], 0.5, 1e-2);
  EXPECT_EQ(world.submerged_fraction()[1], 0.0);
  fluid.acceleration = {Eigen::Vector3d::Zero()};
  EXPECT_THROW(world.advance(1e-3, fluid), std::invalid_argument);
  fluid.acceleration.clear();
  world.mutable_parameters().voidage_correction = true;  // radius still 0
  EXPECT_THROW(world.advance(1e-3, fluid), std::invalid_argument);
  world.mutable_parameters().voidage_radius = 0.05;
  world.mutable_parameters().drag_law = DragLaw::kSeed004;
  EXPECT_THROW(world.advance(1e-3, fluid), std::invalid_argument);
}

TEST(FluidWorld, CylinderDragFollowsTheCrossflowPrinciple) {
  // A log held still (one sub-step from rest) in a uniform stream at 30 degrees to its axis:
  // the normal part of the flow drives White's C_D(Re_n) on D L, the axial part the sphere's
  // C_D(Re_t) on pi r^2.
  DemParameters p = full_force_set();
  p.added_mass = false;  // the added-mass force of the first sub-step would be -M_a dv/dt
  p.gravity.setZero();
  p.user_dt = 1e-7;
  const double rho = 1000, mu = 1e-3, r = 0.01, length = 0.2;
  for (const double speed : {1e-4, 1e-2, 0.5}) {
    DemWorld world(p);
    Material m;
    world.add_cylinder({0, 0, 0}, Eigen::Vector3d::UnitX(), r, length, m);
    FluidAtElements fluid;
    const double angle = kPi / 6;
    fluid.velocity = {speed * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0)};
    fluid.water_fraction = {1.0};
    world.advance(1e-7, fluid);
    const Eigen::Vector3d f = world.window_mean_fluid_force()[0];
    const double un = speed * std::sin(angle), ut = speed * std::cos(angle);
    const double fn = 0.5 * cylinder_crossflow_drag_coefficient(rho * un * 2 * r / mu) * rho * 2 *
                      r * length * un * un;
    const double ft = 0.5 * schiller_naumann_drag_coefficient(rho * ut * 2 * r / mu) * rho * kPi *
                      r * r * ut * ut;
    EXPECT_NEAR(f.y(), fn, 1e-12 * fn) << speed;
    EXPECT_NEAR(f.x(), ft, 1e-12 * ft) << speed;
    EXPECT_EQ(f.z(), 0.0);
  }
}

}  // namespace
}  // namespace cosim::dem

// Unit tests of FluidSystem: coupling hooks, collision, restart, determinism, stability checks.
#include <gtest/gtest.h>

#include <omp.h>
#include <limits>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/checkpoint.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/restart.hpp"
#include "cosim/fluid_mps/scenes.hpp"

using namespace cosim::mps;

namespace {

MpsParameters small_parameters() {
  MpsParameters p;
  p.particle_spacing = 0.01;
  p.max_dt = 5e-4;
  return p;
}

// Fluid particles 6 l0 apart: beyond every influence radius, so each one only feels gravity and
// the applied forces (no pressure, viscosity or collision).
ParticleSet isolated_particles(int count, double spacing) {
  ParticleSet set;
  for (int k = 0; k < count; ++k)
    set.add(Eigen::Vector3d(k * spacing, 0.0, 0.0), ParticleKind::fluid);
  return set;
}

MpsParameters dam_parameters(int cells_per_width) {
  MpsParameters p;
  p.particle_spacing = 0.05715 / cells_per_width;
  p.max_dt = 2e-4;
  return p;
}

bool same_bits(const FluidSystem& a, const FluidSystem& b) {
  if (a.particle_count() != b.particle_count() || a.time() != b.time()) return false;
  for (int i = 0; i < a.particle_count(); ++i) {
    if (a.positions()[i] != b.positions()[i] || a.velocities()[i] != b.velocities()[i] ||
        a.pressures()[i] != b.pressures()[i]) {
      return false;
    }
  }
  return true;
}

}  // namespace

TEST(MpsFluidSystem, PointForcesGiveExactlySumOfForcesTimesDt) {
  MpsParameters p = small_parameters();
  p.gravity.setZero();
  const double l0 = p.particle_spacing;
  FluidSystem system(p, isolated_particles(8, 6.0 * l0));
  const std::vector<Eigen::Vector3d> points{{9.0 * l0, 0.0, 0.0}, {30.0 * l0, 0.0, 0.0}};
  const std::vector<Eigen::Vector3d> forces{{1.5, -0.25, 0.0}, {-0.3, 0.7, 0.0}};
  const Eigen::Vector3d before = system.total_fluid_momentum();
  const ForceDelivery delivery = system.set_point_forces(points, forces, 13.0 * l0);
  EXPECT_EQ(delivery.undelivered_points, 0);
  const double dt = 1e-4;
  const StepReport step = system.step(dt);
  const Eigen::Vector3d gained = system.total_fluid_momentum() - before;
  const Eigen::Vector3d expected = (forces[0] + forces[1]) * dt;
  EXPECT_LT((gained - expected).norm(), 1e-12 * expected.norm() + 1e-15);
  EXPECT_LT((step.external_impulse - expected).norm(), 1e-12 * expected.norm());
  // Cleared by an empty set: no more momentum.
  system.set_point_forces({}, {}, 13.0 * l0);
  const Eigen::Vector3d after_first = system.total_fluid_momentum();
  system.step(dt);
  EXPECT_LT((system.total_fluid_momentum() - after_first).norm(), 1e-15);
}

// A coupling window longer than the stable step is split into several fluid steps: the forces
// act in every one of them, so the fluid receives the whole window's impulse (it used to get
// only the first step's share while the full impulse was booked).
TEST(MpsFluidSystem, PointForcesActInEveryStepOfASplitWindow) {
  MpsParameters p = small_parameters();
  p.gravity.setZero();
  const double l0 = p.particle_spacing;
  const std::vector<Eigen::Vector3d> points{{9.0 * l0, 0.0, 0.0}, {30.0 * l0, 0.0, 0.0}};
  const std::vector<Eigen::Vector3d> forces{{1.5, -0.25, 0.0}, {-0.3, 0.7, 0.0}};
  const double window = 3e-4;
  const Eigen::Vector3d window_impulse = (forces[0] + forces[1]) * window;
  for (const int pieces : {2, 3, 4}) {
    FluidSystem system(p, isolated_particles(8, 6.0 * l0));
    const Eigen::Vector3d before = system.total_fluid_momentum();
    system.set_point_forces(points, forces, 13.0 * l0);
    Eigen::Vector3d delivered = Eigen::Vector3d::Zero();
    for (int piece = 0; piece < pieces; ++piece) {
      delivered += system.step(window / pieces).external_impulse;
    }
    const Eigen::Vector3d gained = system.total_fluid_momentum() - before;
    EXPECT_LT((gained - window_impulse).norm(), 1e-12 * window_impulse.norm()) << pieces;
    EXPECT_LT((delivered - window_impulse).norm(), 1e-12 * window_impulse.norm()) << pieces;
  }
}

TEST(MpsFluidSystem, ForcesWithNoFluidNearbyAreReported) {
  MpsParameters p = small_parameters();
  p.gravity.setZero();
  FluidSystem system(p, isolated_particles(3, 0.06));
  const ForceDelivery delivery =
      system.set_point_forces({{0.0, 0.0, 0.0}, {0.0, 0.1, 0.0}}, {{1, 0, 0}, {0, 2, 0}}, 0.02);
  EXPECT_EQ(delivery.undelivered_points, 1);
  EXPECT_EQ(delivery.undelivered_force, Eigen::Vector3d(0, 2, 0));
}

// The free surface over a point: the top of the still-water tank (0.1 m deep) within half a
// particle, -inf beside the tank where there is no water.
TEST(MpsFluidSystem, SampleSurfaceFindsTheWaterLevelAboveEachPoint) {
  MpsParameters p = small_parameters();
  const double l0 = p.particle_spacing;
  FluidSystem system(p, still_water_tank(p, 0.2, 0.1, 0.2));
  std::vector<double> surface;
  system.sample_surface({{0.1, 0.02, 0.0}, {0.1, 0.5, 0.0}, {0.5, 0.0, 0.0}}, 2.0 * l0, surface);
  ASSERT_EQ(surface.size(), 3u);
  EXPECT_NEAR(surface[0], 0.1, 0.5 * l0);
  EXPECT_NEAR(surface[1], 0.1, 0.5 * l0) << "a point above the water sees the same surface";
  EXPECT_EQ(surface[2], -std::numeric_limits<double>::infinity()) << "no water in that column";
}

TEST(MpsFluidSystem, SampleVelocityAveragesFluidAndGivesWaterFraction) {
  MpsParameters p = small_parameters();
  const double l0 = p.particle_spacing;
  ParticleSet set = still_water_tank(p, 0.2, 0.1, 0.2);
  for (std::size_t i = 0; i < set.size(); ++i) {
    if (set.kinds[i] == ParticleKind::fluid) set.velocities[i] = Eigen::Vector3d(0.3, -0.1, 0);
  }
  FluidSystem system(p, set);
  std::vector<double> fraction;
  const auto u = system.sample_velocity(
      {{0.1, 0.05, 0.0}, {0.1, 0.1 - 0.5 * l0, 0.0}, {0.1, 0.5, 0.0}}, 2.0 * l0, &fraction);
  EXPECT_LT((u[0] - Eigen::Vector3d(0.3, -0.1, 0)).norm(), 1e-12);
  EXPECT_NEAR(fraction[0], 1.0, 1e-12);
  EXPECT_GT(fraction[1], 0.3);  // on the free surface: partly water
  EXPECT_LT(fraction[1], 0.95);
  EXPECT_EQ(u[2], Eigen::Vector3d::Zero());  // in the air
  EXPECT_EQ(fraction[2], 0.0);
}

// The particles near a set of points are exactly the fluid particles within the radius (minimum
// image across a periodic seam), in index order: walls, dummies and particles out of the
// points' reach never enter, and a point out of the water finds none.
TEST(MpsFluidSystem, FluidParticlesNearPointsAreTheFluidWithinTheRadius) {
  auto brute_force = [](const FluidSystem& system, const Eigen::Vector3d& point, double radius) {
    std::vector<int> found;
    for (int i = 0; i < system.particle_count(); ++i) {
      const Eigen::Vector3d d = system.parameters().periodic.wrap(system.positions()[i] - point);
      if (system.kinds()[i] == ParticleKind::fluid && d.squaredNorm() < radius * radius) {
        found.push_back(i);
      }
    }
    return found;
  };
  MpsParameters tank = small_parameters();
  const double l0 = tank.particle_spacing;
  const FluidSystem still(tank, still_water_tank(tank, 0.2, 0.1, 0.2));
  // Next to the left wall, on the bed, mid-tank, on the surface, in the air.
  const std::vector<Eigen::Vector3d> points = {{0.5 * l0, 0.05, 0.0},
                                               {0.1, 0.5 * l0, 0.0},
                                               {0.1, 0.05, 0.0},
                                               {0.15, 0.1, 0.0},
                                               {0.1, 0.5, 0.0}};
  const auto groups = still.fluid_particles_near(points, 2.0 * l0);
  ASSERT_EQ(groups.size(), points.size());
  for (std::size_t q = 0; q < points.size(); ++q) {
    EXPECT_EQ(groups[q], brute_force(still, points[q], 2.0 * l0)) << "point " << q;
  }
  EXPECT_FALSE(groups[2].empty());
  EXPECT_TRUE(groups[4].empty());

  MpsParameters channel = small_parameters();
  channel.periodic.driving_pressure_drop = 20.0;
  const FluidSystem periodic(channel, periodic_channel(channel, 0.4, 0.1, 0.00304));
  const double x_min = periodic.parameters().periodic.x_min;
  const double x_max = periodic.parameters().periodic.x_max;
  // On the seam from either side: the group reaches across it.
  const std::vector<Eigen::Vector3d> seam = {{x_min + 0.5 * l0, 0.05, 0.0},
                                             {x_max - 0.5 * l0, 0.05, 0.0}};
  const auto across = periodic.fluid_particles_near(seam, 3.0 * l0);
  for (std::size_t q = 0; q < seam.size(); ++q) {
    EXPECT_EQ(across[q], brute_force(periodic, seam[q], 3.0 * l0)) << "seam point " << q;
    bool wrapped = false;
    for (int i : across[q]) wrapped |= std::abs(periodic.positions()[i].x() - seam[q].x()) > 0.2;
    EXPECT_TRUE(wrapped) << "seam point " << q << " finds particles across the seam";
  }
}

// The coupling hooks keep their grid of the fluid near the points while no particle moves or
// changes kind. After a step, after a particle is moved or made inactive or fluid, and for points
// moved within and beyond the kept reach, the groups are still exactly the fluid within the
// radius (a stale grid misses the moved particle, or keeps the one that left).
TEST(MpsFluidSystem, KeptPointGridFollowsEveryChangeOfTheFluid) {
  MpsParameters tank = small_parameters();
  const double l0 = tank.particle_spacing, radius = 2.0 * l0;
  FluidSystem system(tank, still_water_tank(tank, 0.2, 0.1, 0.2));
  auto brute_force = [&](const Eigen::Vector3d& point) {
    std::vector<int> found;
    for (int i = 0; i < system.particle_count(); ++i) {
      if (system.kinds()[i] == ParticleKind::fluid &&
          (system.positions()[i] - point).squaredNorm() < radius * radius)
        found.push_back(i);
    }
    return found;
  };
  std::vector<Eigen::Vector3d> points = {{0.05, 0.05, 0.0}, {0.1, 0.05, 0.0}};
  auto expect_exact = [&](const char* after) {
    const auto groups = system.fluid_particles_near(points, radius);
    for (std::size_t q = 0; q < points.size(); ++q)
      EXPECT_EQ(groups[q], brute_force(points[q])) << "point " << q << " after " << after;
  };
  expect_exact("the first query");
  // A far fluid particle moved onto the first point.
  int far = -1;
  for (int i = 0; i < system.particle_count() && far < 0; ++i) {
    if (system.kinds()[i] == ParticleKind::fluid && system.positions()[i].x() > 0.18) far = i;
  }
  ASSERT_GE(far, 0);
  system.set_particle(far, ParticleKind::fluid, points[0] + Eigen::Vector3d(0.3 * l0, 0, 0),
                      Eigen::Vector3d::Zero());
  expect_exact("a particle moved in");
  ASSERT_NE(std::find(brute_force(points[0]).begin(), brute_force(points[0]).end(), far),
            brute_force(points[0]).end());
  system.set_particle(far, ParticleKind::inactive, Eigen::Vector3d(0.5, -0.5, 0),
                      Eigen::Vector3d::Zero());
  expect_exact("the particle left the flow");
  system.step(system.stable_dt());
  expect_exact("a step");
  for (auto& point : points) point.x() += 0.5 * radius;  // within the kept reach
  expect_exact("the points moved a little");
  for (auto& point : points) point.x() += 4.0 * radius;  // beyond it
  expect_exact("the points moved far");
}

// Two fluid particles approaching closer than d_c: the collision model keeps momentum and
// leaves them separating at C_c times the approach speed (seed 001 eq. (11)).
TEST(MpsFluidSystem, CollisionConservesMomentumAndAppliesRestitution) {
  MpsParameters p = small_parameters();
  p.gravity.setZero();
  p.kinematic_viscosity = 0.0;
  p.collision_distance_ratio = 1.0;
  p.collision_restitution = 0.2;
  const double l0 = p.particle_spacing;
  ParticleSet set;
  set.add({0.0, 0.0, 0.0}, ParticleKind::fluid, {0.5, 0.0, 0.0});
  set.add({0.9 * l0, 0.0, 0.0}, ParticleKind::fluid, {-0.5, 0.0, 0.0});
  FluidSystem system(p, set);
  const StepReport report = system.step(1e-5);
  EXPECT_EQ(report.collisions, 2);
  EXPECT_LT(system.total_fluid_momentum().norm(), 1e-15);
  const double separation = system.velocities()[1].x() - system.velocities()[0].x();
  EXPECT_NEAR(separation, 0.2 * 1.0, 1e-9);
}

TEST(MpsFluidSystem, StableDtTakesTheSmallestLimit) {
  MpsParameters p = small_parameters();
  p.max_dt = 1e-2;
  p.courant = 0.2;
  ParticleSet set = isolated_particles(2, 0.1);
  set.velocities[1] = Eigen::Vector3d(2.0, 0.0, 0.0);
  FluidSystem system(p, set);
  EXPECT_DOUBLE_EQ(system.stable_dt(), 0.2 * 0.01 / 2.0);
  p.kinematic_viscosity = 1.0;  // viscous limit 0.2 l0^2 / nu = 2e-5
  FluidSystem viscous(p, set);
  EXPECT_DOUBLE_EQ(viscous.stable_dt(), 0.2 * 1e-4 / 1.0);
}

TEST(MpsFluidSystem, EscapedParticleThrowsStabilityErrorNamingIt) {
  MpsParameters p = small_parameters();
  p.gravity.setZero();
  p.domain = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  ParticleSet set = isolated_particles(3, 0.1);
  set.positions[2] = Eigen::Vector3d(0.999, 0.0, 0.0);
  set.velocities[2] = Eigen::Vector3d(10.0, 0.0, 0.0);
  FluidSystem system(p, set);
  try {
    system.step(1e-3);
    FAIL() << "expected a StabilityError";
  } catch (const StabilityError& e) {
    EXPECT_EQ(e.step(), 1);
    EXPECT_EQ(e.particle(), 2);
    EXPECT_EQ(e.quantity(), "position");
    EXPECT_NE(std::string(e.what()).find("particle 2"), std::string::npos);
  }
}

// Enough particles for the parallel check: of two failing particles the lower index is named,
// and one that is both out of the box and too fast is reported as escaped, as a serial scan
// in index order reports it.
TEST(MpsFluidSystem, StabilityErrorNamesTheFirstFailingParticle) {
  MpsParameters p = small_parameters();
  p.gravity.setZero();
  p.domain = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(600, 1, 1));
  FluidSystem system(p, isolated_particles(5000, 0.1));
  // Set after the start's own check; in one step of 0.02 s they leave the box (|y| <= 1 m).
  system.set_velocity(4500, Eigen::Vector3d(0.0, 2.0 * p.runaway_speed, 0.0));
  system.set_velocity(1200, Eigen::Vector3d(0.0, 2.0 * p.runaway_speed, 0.0));
  try {
    system.step(0.02);
    FAIL() << "expected a StabilityError";
  } catch (const StabilityError& e) {
    EXPECT_EQ(e.particle(), 1200);
    EXPECT_EQ(e.quantity(), "position");
    EXPECT_NE(std::string(e.what()).find("escaped the domain box"), std::string::npos) << e.what();
  }
}

TEST(MpsFluidSystem, RunawaySpeedThrowsStabilityError) {
  MpsParameters p = small_parameters();
  p.gravity = Eigen::Vector3d(0.0, -1e6, 0.0);
  p.domain = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -5, -1), Eigen::Vector3d(5, 5, 1));
  FluidSystem system(p, isolated_particles(2, 0.1));
  EXPECT_THROW(system.step(1e-3), StabilityError);
}

// The restarted system searches its pair list afresh and builds a new multigrid hierarchy: the
// sums must not depend on either (partners in index order, one hierarchy per step).
TEST(MpsFluidSystem, RestartFromFileContinuesBitForBit) {
  for (auto preconditioner : {MpsParameters::PressurePreconditioner::automatic,
                              MpsParameters::PressurePreconditioner::amg,
                              MpsParameters::PressurePreconditioner::aggregation}) {
    MpsParameters p = dam_parameters(8);
    p.pressure_preconditioner = preconditioner;
    FluidSystem straight(p, dam_break(p, 0.05715, 2 * 0.05715, 4 * 0.05715, 3 * 0.05715));
    for (int k = 0; k < 40; ++k) straight.step(straight.stable_dt());
    const std::string path =
        (std::filesystem::temp_directory_path() / "cosim_fluid_mps_restart_test.bin").string();
    save_state(straight, path);
    const MpsState loaded = load_state(path);
    std::remove(path.c_str());
    // The aggregation's set-up in reuse travels in the file (restart.hpp, version 2).
    const PressureSetupState saved = straight.save_state().pressure_setup;
    EXPECT_EQ(loaded.pressure_setup.kept, saved.kept);
    EXPECT_EQ(loaded.pressure_setup.age, saved.age);
    EXPECT_EQ(loaded.pressure_setup.aggregate_of_key, saved.aggregate_of_key);
    EXPECT_EQ(loaded.pressure_setup.coarse_row, saved.coarse_row);
    EXPECT_EQ(loaded.pressure_setup.coarse_value, saved.coarse_value);
    if (preconditioner == MpsParameters::PressurePreconditioner::aggregation) {
      EXPECT_TRUE(saved.kept);
    }
    FluidSystem restarted(p, loaded);
    EXPECT_EQ(restarted.step_count(), straight.step_count());
    EXPECT_TRUE(same_bits(straight, restarted));
    int searches = 0;
    for (int k = 0; k < 40; ++k) {
      searches += straight.step(straight.stable_dt()).neighbour_searches;
      restarted.step(restarted.stable_dt());
    }
    EXPECT_TRUE(same_bits(straight, restarted));
    EXPECT_LT(searches, 40);  // the pair list is kept over steps
  }
}

// The aggregation's set-up is reused over steps (pressure_setup_reuse); the state carries it, in
// checkpoints too. A run continued from a checkpoint gives the straight run's bits, and one
// continued without the set-up (a fresh one at its first step) does not: the set-up is what the
// restart must carry.
TEST(MpsFluidSystem, CheckpointCarriesThePressureSetUp) {
  MpsParameters p = dam_parameters(8);
  p.pressure_preconditioner = MpsParameters::PressurePreconditioner::aggregation;
  FluidSystem straight(p, dam_break(p, 0.05715, 2 * 0.05715, 4 * 0.05715, 3 * 0.05715));
  for (int k = 0; k < 23; ++k) straight.step(straight.stable_dt());
  cosim::checkpoint::Writer out("fluid_mps");
  save_checkpoint(straight, out);
  const MpsState state =
      load_checkpoint(cosim::checkpoint::Reader(out.encode(), "memory", "fluid_mps"));
  ASSERT_TRUE(state.pressure_setup.kept);
  EXPECT_GT(state.pressure_setup.age, 0);  // mid-reuse: the next step reuses it
  const PressureSetupState saved = straight.save_state().pressure_setup;
  EXPECT_EQ(state.pressure_setup.aggregate_of_key, saved.aggregate_of_key);
  EXPECT_EQ(state.pressure_setup.coarse_value, saved.coarse_value);
  MpsState without = state;
  without.pressure_setup = PressureSetupState{};
  FluidSystem restarted(p, state), fresh(p, without);
  for (int k = 0; k < 5; ++k) {
    straight.step(straight.stable_dt());
    restarted.step(restarted.stable_dt());
    fresh.step(fresh.stable_dt());
  }
  EXPECT_TRUE(same_bits(straight, restarted));
  EXPECT_FALSE(same_bits(straight, fresh));
}

// A restart file whose set-up section claims more values than the file holds is refused before
// anything is allocated for them, naming the file.
TEST(MpsFluidSystem, RestartFileWithADamagedSetUpIsRefused) {
  MpsParameters p = dam_parameters(8);
  p.pressure_preconditioner = MpsParameters::PressurePreconditioner::aggregation;
  FluidSystem system(p, dam_break(p, 0.05715, 2 * 0.05715, 4 * 0.05715, 3 * 0.05715));
  system.step(system.stable_dt());
  const PressureSetupState setup = system.save_state().pressure_setup;
  ASSERT_TRUE(setup.kept);
  const std::string path =
      (std::filesystem::temp_directory_path() / "cosim_fluid_mps_damaged_setup.bin").string();
  save_state(system, path);
  {
    // Header (8 + 4), count, time, step, then per particle 7 doubles and an int; then the
    // set-up's flag, its four counts, aggregate_of_key (a length and the ints) and the length of
    // the coarse rows, damaged to count^2: a bound the coarse matrix allows, but more than the
    // file holds.
    const std::uint64_t n = static_cast<std::uint64_t>(system.particle_count());
    const std::uint64_t at =
        12 + 24 + n * (7 * 8 + 4) + 1 + 16 + 8 + 4 * setup.aggregate_of_key.size();
    const std::uint64_t claimed =
        static_cast<std::uint64_t>(setup.aggregate_count) * setup.aggregate_count;
    ASSERT_GT(claimed * sizeof(int), std::filesystem::file_size(path) - at);
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(static_cast<std::streamoff>(at));
    file.write(reinterpret_cast<const char*>(&claimed), sizeof(claimed));
  }
  try {
    load_state(path);
    FAIL() << "a damaged set-up was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("pressure set-up"), std::string::npos) << error.what();
  }
  std::remove(path.c_str());
}

// A set-up record that does not fit is refused, naming it.
TEST(MpsFluidSystem, CheckpointRefusesABadPressureSetUp) {
  MpsParameters p = dam_parameters(8);
  p.pressure_preconditioner = MpsParameters::PressurePreconditioner::aggregation;
  FluidSystem system(p, dam_break(p, 0.05715, 2 * 0.05715, 4 * 0.05715, 3 * 0.05715));
  system.step(system.stable_dt());
  MpsState state = system.save_state();
  ASSERT_TRUE(state.pressure_setup.kept);
  state.pressure_setup.aggregate_of_key[0] = state.pressure_setup.aggregate_count + 4;
  cosim::checkpoint::Writer out("fluid_mps");
  save_checkpoint(state, p.dimension, out);
  try {
    load_checkpoint(cosim::checkpoint::Reader(out.encode(), "bad.ckpt", "fluid_mps"));
    FAIL() << "an aggregate beyond the count was accepted";
  } catch (const cosim::checkpoint::Error& error) {
    EXPECT_NE(std::string(error.what()).find("fluid.pressure_setup.aggregate_of_key"),
              std::string::npos)
        << error.what();
  }
}

// The stages' wall seconds are booked once each: none negative, and together no more than the
// step's own wall time; a step that rebuilds its pair list books search time, and the
// aggregation's set-up is booked apart from the CG.
TEST(MpsFluidSystem, StageSecondsAddUpToTheStep) {
  MpsParameters p = dam_parameters(20);
  p.pressure_preconditioner = MpsParameters::PressurePreconditioner::aggregation;
  FluidSystem system(p, dam_break(p, 0.05715, 2 * 0.05715, 4 * 0.05715, 3 * 0.05715));
  bool searched = false, set_up = false;
  for (int k = 0; k < 400 && !(searched && set_up && k >= 30); ++k) {
    const auto start = std::chrono::steady_clock::now();
    const StepReport report = system.step(system.stable_dt());
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const StageSeconds& t = report.stage_seconds;
    const double stages[] = {t.search,         t.explicit_part, t.collision,
                             t.density,        t.assembly,      t.pressure_setup,
                             t.pressure_solve, t.correction,    t.finish};
    double sum = 0.0;
    for (const double stage : stages) {
      EXPECT_GE(stage, 0.0);
      sum += stage;
    }
    EXPECT_LE(sum, wall * (1.0 + 1e-9));
    if (report.neighbour_searches > 0) {
      EXPECT_GT(t.search, 0.0);
      searched = true;
    }
    set_up = set_up || t.pressure_setup > 0.0;
  }
  EXPECT_TRUE(searched);
  EXPECT_TRUE(set_up);
}

// Parallel loops gather per particle and reduce in fixed blocks: thread count must not matter.
TEST(MpsFluidSystem, SameBitsWithOneAndTwoThreads) {
  MpsParameters p = dam_parameters(40);  // > 4096 particles, so the loops do run in parallel
  const ParticleSet set = dam_break(p, 0.05715, 2 * 0.05715, 4 * 0.05715, 3 * 0.05715);
  ASSERT_GT(set.size(), 4096u);
  const int threads = omp_get_max_threads();
  for (auto preconditioner :
       {MpsParameters::PressurePreconditioner::jacobi, MpsParameters::PressurePreconditioner::amg,
        MpsParameters::PressurePreconditioner::aggregation}) {
    p.pressure_preconditioner = preconditioner;
    FluidSystem one(p, set), two(p, set);
    omp_set_num_threads(1);
    for (int k = 0; k < 10; ++k) one.step(2e-4);
    omp_set_num_threads(2);
    for (int k = 0; k < 10; ++k) two.step(2e-4);
    omp_set_num_threads(threads);
    EXPECT_TRUE(same_bits(one, two));
  }
}

// 3D: a cube of water on a wall floor keeps the lattice n0 inside and steps without error.
TEST(MpsFluidSystem, ThreeDimensionalBlockSteps) {
  MpsParameters p;
  p.dimension = 3;
  p.particle_spacing = 0.02;
  p.radius_laplacian_over_l0 = 3.1;  // mps_lattice_sums.csv lists 3D radii 2.1 and 3.1
  p.max_dt = 1e-3;
  const double l0 = p.particle_spacing;
  ParticleSet set;
  const int side = 8, layers = 4;
  for (int z = -layers; z < side + layers; ++z)
    for (int y = -layers; y < side; ++y)
      for (int x = -layers; x < side + layers; ++x) {
        const int depth = std::max({-y, -x, x - side + 1, -z, z - side + 1, 0});
        const ParticleKind kind = depth == 0   ? ParticleKind::fluid
                                  : depth <= 2 ? ParticleKind::wall
                                               : ParticleKind::dummy;
        set.add(Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5) * l0, kind);
      }
  FluidSystem system(p, set);
  EXPECT_NEAR(system.n0_density(), 14.418575, 1e-6);
  // A fluid particle with a full neighbourhood (row 2 above the floor, away from the walls).
  int interior = -1;
  for (int i = 0; i < system.particle_count(); ++i) {
    if ((system.positions()[i] - Eigen::Vector3d(4.5, 2.5, 4.5) * l0).norm() < 1e-9) interior = i;
  }
  ASSERT_GE(interior, 0);
  EXPECT_NEAR(system.number_densities()[interior], system.n0_density(), 1e-9);
  for (int k = 0; k < 20; ++k) system.step(system.stable_dt());
  EXPECT_LT(system.total_fluid_momentum().norm() / (system.particle_mass() * side * side * side),
            0.5);
  EXPECT_GT(system.pressures()[interior], 0.0);
}

TEST(MpsScenes, DamBreakBuilderAndObservers) {
  MpsParameters p;
  p.particle_spacing = 0.05715 / 10;
  const double a = 0.05715;
  const ParticleSet set = dam_break(p, a, 2 * a, 4 * a, 3 * a, 2, 2);
  int fluid = 0, wall = 0, dummy = 0;
  for (ParticleKind kind : set.kinds) {
    fluid += kind == ParticleKind::fluid;
    wall += kind == ParticleKind::wall;
    dummy += kind == ParticleKind::dummy;
  }
  EXPECT_EQ(fluid, 10 * 20);
  EXPECT_EQ(wall, 2 * 40 + 2 * 2 * 30 + 4 * 2);  // bed, two side walls, corner blocks
  EXPECT_EQ(dummy, 2 * 44 + 2 * 2 * 30 + 4 * 2 + 2 * 2 * 2);
  EXPECT_FALSE(p.domain.isEmpty());
  FluidSystem system(p, set);
  EXPECT_NEAR(surge_front_position(system), a, 1e-12);
  EXPECT_NEAR(residual_column_height(system), 2 * a, 1e-12);
  EXPECT_EQ(mean_pressure_at(system, Eigen::Vector3d(0.5 * a, a, 0), 0.5 * a), 0.0);
}

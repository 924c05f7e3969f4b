// The 3D channels (boundaries.hpp): periodic_channel_3d and open_channel_3d with seed 001's
// soluble moving wall inflow across the width, its level control and the free outflow.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <set>
#include <tuple>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/observers.hpp"

#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

namespace {

// The 3D radii of dam_break_3d (density and gradient 2.1 l0, Laplacian 3.1 l0) with seed 001's
// collision distance 1.0 l0; z up.
MpsParameters channel_parameters(double l0) {
  MpsParameters p = quiet_parameters(l0);
  p.dimension = 3;
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.radius_gradient_over_l0 = 2.1;
  p.radius_laplacian_over_l0 = 3.1;
  return p;
}

// Lattice cell of a position (l0 cells, centres at half cells).
std::tuple<int, int, int> cell_of(const Eigen::Vector3d& x, double l0) {
  return {static_cast<int>(std::floor(x.x() / l0)), static_cast<int>(std::floor(x.y() / l0)),
          static_cast<int>(std::floor(x.z() / l0))};
}

}  // namespace

// The builder's particles: water nx x ny x nd, the block block_columns x ny x rows inside the
// width, walls and dummies by their Chebyshev distance to the open section, no two particles in
// one cell but the parked pool; the inflow settings name the geometry.
TEST(MpsChannels3d, OpenChannelBuildsWaterBlockAndWalls) {
  const double l0 = 0.01;
  MpsParameters p = channel_parameters(l0);
  OpenBoundarySettings settings;
  const Channel3d channel{0.05, 0.08, 2, 1};
  const ParticleSet set = open_channel_3d(p, settings, channel, 0.2, 0.03, 0.06, 3, 500);
  const int nx = 20, ny = 5, layers = 3, columns = nx + 3 + 2;
  EXPECT_EQ(count_kind(set, ParticleKind::fluid), nx * ny * 3);
  EXPECT_EQ(count_kind(set, ParticleKind::inactive), 500);
  // Cross-section: (ny + 2 layers) x (layers + 8) cells, less the open ny x 8.
  const int section = (ny + 2 * layers) * (layers + 8) - ny * 8;
  // Dummies: the outermost layer of the bed and both sides.
  const int dummies = (ny + 2 * layers) + 2 * (layers - 1 + 8);
  EXPECT_EQ(count_kind(set, ParticleKind::dummy), columns * dummies);
  EXPECT_EQ(count_kind(set, ParticleKind::wall), columns * (section - dummies) + 3 * ny * 6);
  std::set<std::tuple<int, int, int>> cells;
  int block = 0;
  for (std::size_t i = 0; i < set.positions.size(); ++i) {
    if (set.kinds[i] == ParticleKind::inactive) continue;
    const Eigen::Vector3d& x = set.positions[i];
    EXPECT_TRUE(cells.insert(cell_of(x, l0)).second)
        << "two particles in one cell at " << x.transpose();
    if (set.kinds[i] == ParticleKind::wall && x.x() < 0.0 && x.y() > 0.0 && x.y() < 0.05 &&
        x.z() > 0.0) {
      ++block;
    }
  }
  EXPECT_EQ(block, 3 * ny * 6);
  EXPECT_DOUBLE_EQ(settings.width, 0.05);
  EXPECT_EQ(settings.block_rows, 6);
  EXPECT_DOUBLE_EQ(settings.bed_height, 0.0);
  EXPECT_NEAR(settings.outflow_x, 0.23, 1e-12);
  EXPECT_FALSE(p.periodic.enabled);
  EXPECT_THROW(open_channel_3d(p, settings, channel, 0.2, 0.03, 0.0, 3, 500),
               std::invalid_argument);
  MpsParameters two_d = quiet_parameters(l0);
  EXPECT_THROW(open_channel_3d(two_d, settings, channel, 0.2, 0.03, 0.06, 3, 500),
               std::invalid_argument);
}

// Fixed wall velocity across the width: each column that passes the line releases
// inflow_rows x ny fluid particles, the block keeps its size inside the width, the count of
// every particle is kept, and the released volume is l0^3 a particle.
TEST(MpsChannels3d, MovingWallReleasesWholeColumnsAcrossTheWidth) {
  const double l0 = 0.01;
  MpsParameters p = channel_parameters(l0);
  OpenBoundarySettings settings;
  const Channel3d channel{0.04, 0.06, 2, 1};
  FluidSystem system(p, open_channel_3d(p, settings, channel, 0.2, 0.0, 0.05, 3, 600));
  settings.control = OpenBoundarySettings::Control::velocity;
  settings.velocity = 0.2;
  settings.inflow_rows = 3;
  OpenBoundaries boundaries(system, settings);
  const int total = system.particle_count();
  const int block = static_cast<int>(boundaries.block().size());
  EXPECT_EQ(block, 3 * 4 * 5);
  const int fixed =
      count_kind(system, ParticleKind::dummy) + count_kind(system, ParticleKind::wall) - block;
  while (system.time() < 0.3 - 1e-12) {
    system.step(1e-3);
    boundaries.update();
  }
  // The front column starts l0/2 before the line: columns passed = floor(U t / l0 + 1/2).
  const long columns = static_cast<long>(std::floor(0.2 * 0.3 / l0 + 0.5));
  EXPECT_EQ(boundaries.dissolved_total(), columns * 3 * 4);
  EXPECT_NEAR(boundaries.inflow_volume(), columns * 3 * 4 * l0 * l0 * l0, 1e-15);
  EXPECT_EQ(system.particle_count(), total);
  EXPECT_EQ(static_cast<int>(boundaries.block().size()), block);
  EXPECT_EQ(count_kind(system, ParticleKind::fluid),
            boundaries.dissolved_total() - boundaries.recycled_total());
  EXPECT_EQ(count_kind(system, ParticleKind::fluid) + block + boundaries.pool_size() + fixed,
            total);
  for (int i : boundaries.block()) {
    const Eigen::Vector3d& x = system.positions()[i];
    EXPECT_GT(x.y(), 0.0);
    EXPECT_LT(x.y(), 0.04);
    EXPECT_LT(x.x(), 0.0);
    EXPECT_NEAR(system.velocities()[i].x(), 0.2, 1e-15);
  }
  // The released water spans the width between the side walls: every lateral position of the
  // lattice holds some (past the brink at x = 0.2 m it may spread sideways as it falls).
  std::set<int> lateral;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid || system.positions()[i].x() > 0.2) continue;
    lateral.insert(static_cast<int>(std::floor(system.positions()[i].y() / l0)));
  }
  EXPECT_EQ(lateral, (std::set<int>{0, 1, 2, 3}));
}

// Seed 001's automatic level adjustment in 3D: q = 0.01 m^2/s per width into a 0.15 m channel
// 3 cm wide ending in a free overfall. Once the flow is established the inflow delivers q times
// the width, the gauge line half way counts it, and the outflow recycles the water.
TEST(MpsChannels3d, DischargeControlDeliversPrescribedDischarge) {
  const double l0 = 0.005, q = 0.01, width = 0.03;
  MpsParameters p = channel_parameters(l0);
  OpenBoundarySettings settings;
  const Channel3d channel{width, 0.05, 2, 1};
  FluidSystem system(p, open_channel_3d(p, settings, channel, 0.15, 0.02, 0.045, 4, 4000));
  settings.control = OpenBoundarySettings::Control::discharge;
  settings.discharge = q;
  settings.inflow_rows = 5;
  OpenBoundaries boundaries(system, settings);
  const int total = system.particle_count();
  const int fluid0 = count_kind(system, ParticleKind::fluid);
  GaugeLine gauge(0.075);
  const DischargeCount count = count_discharge(system, boundaries, gauge, 1.0, 2.0);
  const double q_in = count.inflow / count.seconds / width;
  const double q_gauge = count.gauge / count.seconds / width;
  std::cout << "[3D discharge control] q=" << q << " inflow " << q_in << " gauge " << q_gauge
            << " m^2/s; wall velocity " << boundaries.velocity() << " m/s rows "
            << boundaries.inflow_rows() << " level " << boundaries.measured_level()
            << " m; recycled " << boundaries.recycled_total() << " pool " << boundaries.pool_size()
            << "\n";
  EXPECT_NEAR(q_in, q, 0.03 * q);
  EXPECT_NEAR(q_gauge, q, 0.06 * q);
  EXPECT_GT(boundaries.recycled_total(), 1000);
  EXPECT_EQ(system.particle_count(), total);
  EXPECT_EQ(count_kind(system, ParticleKind::fluid),
            fluid0 + boundaries.dissolved_total() - boundaries.recycled_total());
}

// The periodic 3D channel: walls only on the bed and the sides, the seam at x = 0 and length.
// A pressure drop with no slope accelerates weightless water (no pressure, so no wall forces
// but the viscous ones) at a = dp / (rho L) exactly. With gravity the water 4 l0 and more from
// the bed and the side walls, below the surface rows, follows a t within 1 % (as 2D's
// MpsPeriodic.DrivenChannelInitialAcceleration). Nearer the walls it runs ahead at first: the
// rows resting on the wall lattice (the collision distance l0 is the lattice's spacing) sit on
// its particles' tops and slide off them forwards once the water moves. Every particle stays
// in the period.
TEST(MpsChannels3d, PeriodicChannelAcceleratesUnderThePressureDrop) {
  const double l0 = 0.01, length = 0.12, depth = 0.1, width = 0.12, drop = 6.0;
  const double a = drop / (1000.0 * length), t = 0.1;
  const Channel3d channel{width, 0.12, 2, 1};
  MpsParameters weightless = channel_parameters(l0);
  weightless.gravity.setZero();
  weightless.periodic.driving_pressure_drop = drop;
  FluidSystem free(weightless, periodic_channel_3d(weightless, channel, length, depth));
  EXPECT_TRUE(free.parameters().periodic.enabled);
  EXPECT_DOUBLE_EQ(free.parameters().periodic.x_max, length);
  const int fluid = count_kind(free, ParticleKind::fluid);
  EXPECT_EQ(fluid, 12 * 12 * 10);
  while (free.time() < t - 1e-12) free.step(5e-4);
  const double free_u = free.total_fluid_momentum().x() / (fluid * free.particle_mass());
  EXPECT_NEAR(free_u, a * free.time(), 1e-3 * a * free.time());

  MpsParameters p = channel_parameters(l0);
  p.periodic.driving_pressure_drop = drop;
  FluidSystem system(p, periodic_channel_3d(p, channel, length, depth));
  while (system.time() < t - 1e-12) system.step(5e-4);
  const double reach = 4.0 * l0;
  double interior_u = 0.0;
  int interior = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    const Eigen::Vector3d& x = system.positions()[i];
    EXPECT_GE(x.x(), 0.0);
    EXPECT_LT(x.x(), length);
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    if (x.z() < reach || x.z() > depth - 2.0 * l0 || x.y() < reach || x.y() > width - reach) {
      continue;
    }
    interior_u += system.velocities()[i].x();
    ++interior;
  }
  interior_u /= interior;
  const double whole_u = system.total_fluid_momentum().x() / (fluid * system.particle_mass());
  std::cout << "[3D periodic] a t " << a * system.time() << " m/s; weightless " << free_u
            << ", interior (" << interior << " particles) " << interior_u << ", whole water "
            << whole_u << " m/s\n";
  EXPECT_GT(interior, 100);
  EXPECT_NEAR(interior_u, a * system.time(), 0.01 * a * system.time());
  EXPECT_EQ(count_kind(system, ParticleKind::fluid), fluid);
}

// wall_collision_factor: with seed 001's collision distance of one lattice spacing the rows on
// the bed and the side walls rest on the wall particles in permanent collision, and once the
// water moves they slide off those particles' tops: the walls push the water along. Fluid-wall
// pairs colliding only within half of it take no collision impulse from the walls at all, while
// the fluid pairs keep theirs; factor 1 is the same model for both.
TEST(MpsChannels3d, WallCollisionFactorKeepsTheRowsOffTheWallParticles) {
  const double l0 = 0.01, length = 0.12, depth = 0.06, drop = 6.0;
  const Channel3d channel{0.08, 0.08, 2, 1};
  auto run = [&](double factor) {
    MpsParameters p = channel_parameters(l0);
    p.wall_collision_factor = factor;
    p.periodic.driving_pressure_drop = drop;
    FluidSystem system(p, periodic_channel_3d(p, channel, length, depth));
    Eigen::Vector3d wall = Eigen::Vector3d::Zero();
    long collisions = 0;
    while (system.time() < 0.1 - 1e-12) {
      const StepReport report = system.step(5e-4);
      wall += report.wall_collision_impulse;
      collisions += report.collisions;
    }
    const double mass = count_kind(system, ParticleKind::fluid) * system.particle_mass();
    std::cout << "[wall collisions] factor " << factor << ": wall collision impulse "
              << wall.transpose() / mass << " m/s, whole water "
              << system.total_fluid_momentum().x() / mass << " m/s (a t "
              << drop / (p.density * length) * system.time() << "), collisions " << collisions
              << "\n";
    return std::pair{wall, collisions};
  };
  const auto [wall_full, collisions_full] = run(1.0);
  const auto [wall_half, collisions_half] = run(0.5);
  EXPECT_GT(wall_full.x(), 0.0) << "the rows on the walls slide forward off their tops";
  EXPECT_EQ(wall_half.norm(), 0.0);
  EXPECT_GT(collisions_half, 0) << "fluid pairs still collide";
  EXPECT_LT(collisions_half, collisions_full);
}

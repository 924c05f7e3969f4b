// Neighbour exclusion across thin partition walls (seed 001 section 2.2(1)).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/scenes.hpp"

using namespace cosim::mps;

TEST(MpsPartition, CrossingTest) {
  PartitionSegment s{{0.0, 0.0}, {0.0, 1.0}};
  EXPECT_TRUE(crosses_partition({-0.1, 0.5, 0}, {0.1, 0.5, 0}, s));
  EXPECT_FALSE(crosses_partition({-0.1, 0.5, 0}, {-0.05, 0.9, 0}, s));
  EXPECT_FALSE(crosses_partition({-0.1, 1.5, 0}, {0.1, 1.5, 0}, s));  // above the top
  EXPECT_TRUE(crosses_partition({-0.1, 0.9, 0}, {0.1, 1.05, 0}, s));  // just under the tip
  EXPECT_FALSE(crosses_partition({0.0, 0.5, 0}, {0.1, 0.5, 0}, s));   // touching: same side
}

TEST(MpsPartition, ListFilterKeepsOrderAndDropsCrossingPairs) {
  std::vector<Eigen::Vector3d> x;
  for (int i = 0; i < 10; ++i) x.emplace_back(0.01 * i, 0.0, 0.0);
  NeighbourGrid grid(2, bounding_box(x, 2, 0.05), 0.05);
  grid.build(x);
  NeighbourList list = grid.neighbours(x, 0.025);
  const std::vector<PartitionSegment> wall{{{0.045, -1.0}, {0.045, 1.0}}};
  remove_partition_crossings(list, x, wall);
  for (int i = 0; i < 10; ++i) {
    for (int k = list.begin(i); k < list.end(i); ++k) {
      EXPECT_EQ(i <= 4, list.index[k] <= 4) << i << " " << list.index[k];
    }
  }
  EXPECT_EQ(list.end(4) - list.begin(4), 2);  // 2, 3
  EXPECT_EQ(list.end(5) - list.begin(5), 2);  // 6, 7
}

namespace {

// Tank 0.3 m x 0.25 m (l0 = 0.01): water 0.2 m deep on x < 0.13, a thin partition of two wall
// columns (x centres 0.135 and 0.145), the right side x > 0.15 dry. The partition segment runs
// along x = 0.14 between the columns, from under the bed to the partition top at y = 0.25.
ParticleSet partitioned_tank(MpsParameters& p) {
  const double l0 = p.particle_spacing;
  ParticleSet set = dam_break(p, 0.13, 0.2, 0.3, 0.25);
  for (int iy = 0; iy < 25; ++iy)
    for (double x : {0.135, 0.145})
      set.add(Eigen::Vector3d(x, (iy + 0.5) * l0, 0.0), ParticleKind::wall);
  return set;
}

}  // namespace

// Without the exclusion the water sees the dry face of the partition (2 l0 away, inside the
// Laplacian radius) as free surface and its pressure near the wall drops; with it the water
// stays hydrostatic, no particle passes and the dry face carries no pressure.
TEST(MpsPartition, ThinWallHoldsWaterWithoutPressureLeak) {
  MpsParameters p;
  p.particle_spacing = 0.01;
  p.max_dt = 1e-3;
  p.collision_distance_ratio = 1.0;
  p.collision_restitution = 0.2;
  p.radius_gradient_over_l0 = 4.0;
  MpsParameters with = p;
  with.partitions.push_back({{0.14, -0.1}, {0.14, 0.25}});
  const double expected = p.density * 9.81 * 0.1;
  struct Result {
    double dry_face_pressure = 0.0, max_fluid_x = 0.0, near_wall_pressure = 0.0;
  };
  auto run = [](const MpsParameters& parameters) {
    MpsParameters q = parameters;
    FluidSystem system(q, partitioned_tank(q));
    Result r;
    double sum = 0.0;
    int samples = 0;
    while (system.time() < 0.8) {
      system.step(system.stable_dt());
      for (int i = 0; i < system.particle_count(); ++i) {
        const Eigen::Vector3d& x = system.positions()[i];
        if (system.kinds()[i] == ParticleKind::fluid)
          r.max_fluid_x = std::max(r.max_fluid_x, x.x());
        if (system.kinds()[i] == ParticleKind::wall && x.x() > 0.14 && x.x() < 0.15 &&
            x.y() > 0.0) {
          r.dry_face_pressure = std::max(r.dry_face_pressure, system.pressures()[i]);
        }
      }
      if (system.time() > 0.4) {
        sum += mean_pressure_at(system, Eigen::Vector3d(0.12, 0.1, 0.0), 0.015);
        ++samples;
      }
    }
    r.near_wall_pressure = sum / samples;
    return r;
  };
  const Result tight = run(with), leaky = run(p);
  std::cout << "[partition] with exclusion: dry-face max pressure " << tight.dry_face_pressure
            << " Pa, rightmost fluid x " << tight.max_fluid_x << " m, pressure 1 l0 from the wall "
            << "at depth 0.1 m " << tight.near_wall_pressure << " Pa (rho g h " << expected
            << "); without: " << leaky.near_wall_pressure << " Pa, dry face "
            << leaky.dry_face_pressure << " Pa, rightmost fluid x " << leaky.max_fluid_x << "\n";
  EXPECT_EQ(tight.dry_face_pressure, 0.0);
  EXPECT_LT(tight.max_fluid_x, 0.13);
  EXPECT_NEAR(tight.near_wall_pressure, expected, 0.03 * expected);
}

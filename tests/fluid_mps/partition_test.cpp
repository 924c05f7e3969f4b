// Neighbour exclusion across thin partition walls (seed 001 section 2.2(1)).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/scenes.hpp"

#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

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
// columns (x centres 0.135 and 0.145), water `right_depth` deep on x > 0.15 (0: dry). The
// partition segment runs along x = 0.14 between the columns, from under the bed to the top.
ParticleSet partitioned_tank(MpsParameters& p, double right_depth) {
  const double l0 = p.particle_spacing;
  ParticleSet set = dam_break(p, 0.13, 0.2, 0.3, 0.25);
  for (int iy = 0; iy < 25; ++iy)
    for (double x : {0.135, 0.145})
      set.add(Eigen::Vector3d(x, (iy + 0.5) * l0, 0.0), ParticleKind::wall);
  for (int iy = 0; iy < std::lround(right_depth / l0); ++iy)
    for (int ix = 15; ix < 30; ++ix)
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  return set;
}

struct PartitionRun {
  double dry_face_pressure = 0.0;  // max pressure of the right wall column (dry side)
  double max_left_x = 0.0;         // rightmost fluid particle that started on the left
  double left_pressure = 0.0;      // time-averaged, 1 l0 from the partition, y = 0.05 m
  double right_pressure = 0.0;
};

PartitionRun run_partitioned(const MpsParameters& parameters, double right_depth) {
  MpsParameters q = parameters;
  FluidSystem system(q, partitioned_tank(q, right_depth));
  std::vector<char> left(system.particle_count(), 0);
  for (int i = 0; i < system.particle_count(); ++i) {
    left[i] = system.kinds()[i] == ParticleKind::fluid && system.positions()[i].x() < 0.13;
  }
  PartitionRun r;
  double sum_left = 0.0, sum_right = 0.0;
  int samples = 0;
  while (system.time() < 0.8) {
    system.step(system.stable_dt());
    for (int i = 0; i < system.particle_count(); ++i) {
      const Eigen::Vector3d& x = system.positions()[i];
      if (left[i]) r.max_left_x = std::max(r.max_left_x, x.x());
      if (system.kinds()[i] == ParticleKind::wall && x.x() > 0.14 && x.x() < 0.15 && x.y() > 0.0) {
        r.dry_face_pressure = std::max(r.dry_face_pressure, system.pressures()[i]);
      }
    }
    if (system.time() > 0.4) {
      sum_left += mean_pressure_at(system, Eigen::Vector3d(0.12, 0.05, 0.0), 0.015);
      sum_right += mean_pressure_at(system, Eigen::Vector3d(0.16, 0.05, 0.0), 0.015);
      ++samples;
    }
  }
  r.left_pressure = sum_left / samples;
  r.right_pressure = sum_right / samples;
  return r;
}

MpsParameters partition_parameters(bool exclusion) {
  MpsParameters p = quiet_parameters(0.01);
  if (exclusion) p.partitions.push_back({{0.14, -0.1}, {0.14, 0.25}});
  return p;
}

}  // namespace

// Pools at different levels on both sides of a partition two particles thick (seed 001's
// fishway situation): without the exclusion the Laplacian (4 l0) couples the water 3 l0 apart
// across the partition and the pressures leak; with it each side stays hydrostatic.
TEST(MpsPartition, ThinWallSeparatesPoolsAtDifferentLevels) {
  const double rho_g = 1000.0 * 9.81;
  const PartitionRun tight = run_partitioned(partition_parameters(true), 0.1);
  const PartitionRun leaky = run_partitioned(partition_parameters(false), 0.1);
  std::cout << "[partition, two pools] at y=0.05 m, 1 l0 from the wall: left "
            << tight.left_pressure << " Pa (rho g h " << rho_g * 0.15 << "), right "
            << tight.right_pressure << " Pa (" << rho_g * 0.05 << "); without exclusion left "
            << leaky.left_pressure << " right " << leaky.right_pressure
            << " Pa; rightmost left-side particle " << tight.max_left_x << " m\n";
  EXPECT_NEAR(tight.left_pressure, rho_g * 0.15, 0.03 * rho_g * 0.15);
  EXPECT_NEAR(tight.right_pressure, rho_g * 0.05, 0.025 * rho_g * 0.05);
  // The leak the exclusion removes: the shallow pool's pressure is off by more than that.
  EXPECT_GT(std::abs(leaky.right_pressure - rho_g * 0.05), 0.025 * rho_g * 0.05);
  EXPECT_LT(tight.max_left_x, 0.14);
}

// Dry side: no particle passes and the dry face carries no pressure.
TEST(MpsPartition, ThinWallHoldsWaterFromDrySide) {
  const double rho_g = 1000.0 * 9.81;
  const PartitionRun tight = run_partitioned(partition_parameters(true), 0.0);
  std::cout << "[partition, dry side] dry-face max pressure " << tight.dry_face_pressure
            << " Pa, rightmost fluid x " << tight.max_left_x << " m, left pressure "
            << tight.left_pressure << " Pa (rho g h " << rho_g * 0.15 << ")\n";
  EXPECT_EQ(tight.dry_face_pressure, 0.0);
  EXPECT_LT(tight.max_left_x, 0.13);
  EXPECT_NEAR(tight.left_pressure, rho_g * 0.15, 0.03 * rho_g * 0.15);
}

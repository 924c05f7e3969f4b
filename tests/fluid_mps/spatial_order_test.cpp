// The pressure unknowns' numbering along space (spatial_order.hpp): cells of the box's longest
// axis slowest, one cell's items in the order given, a permutation of the items, and no overflow
// for a particle thrown far out.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>

#include "cosim/fluid_mps/spatial_order.hpp"

namespace cosim::mps {
namespace {

// Cell of each item along `axis` (cells of size h from the smallest coordinate).
int cell_along(const std::vector<Eigen::Vector3d>& x, int item, int axis, double low, double h) {
  return static_cast<int>(std::floor((x[item][axis] - low) / h));
}

TEST(SpatialOrder, TwoDimensionalCellsAlongTheLongestAxisThenTheGivenOrder) {
  // A 40 x 6 lattice in the x-z plane (x the longest), spacing 0.1, cells of 0.25.
  std::vector<Eigen::Vector3d> x;
  for (int a = 0; a < 40; ++a)
    for (int b = 0; b < 6; ++b) x.emplace_back(0.1 * a, 7.0, 0.1 * b);  // y is not read in 2D
  std::vector<int> items(x.size());
  std::iota(items.begin(), items.end(), 0);
  std::shuffle(items.begin(), items.end(), std::mt19937(7));
  std::vector<int> given_rank(x.size());
  for (std::size_t t = 0; t < items.size(); ++t) given_rank[items[t]] = static_cast<int>(t);
  SpatialOrderWork work;
  std::vector<int> ordered = items;
  order_along_cells(x, 0.25, 2, ordered, work);

  std::vector<int> sorted = ordered;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> all(x.size());
  std::iota(all.begin(), all.end(), 0);
  ASSERT_EQ(sorted, all);  // a permutation
  for (std::size_t t = 1; t < ordered.size(); ++t) {
    const int a = ordered[t - 1], b = ordered[t];
    const int ax = cell_along(x, a, 0, 0.0, 0.25), bx = cell_along(x, b, 0, 0.0, 0.25);
    const int az = cell_along(x, a, 2, 0.0, 0.25), bz = cell_along(x, b, 2, 0.0, 0.25);
    ASSERT_LE(ax, bx) << "x (the longest axis) is the slowest";
    if (ax != bx) continue;
    ASSERT_LE(az, bz);
    if (az == bz) {
      ASSERT_LT(given_rank[a], given_rank[b]) << "one cell keeps the given order";
    }
  }
}

TEST(SpatialOrder, ThreeDimensionalTheLongestAxisIsTheSlowest) {
  // z the longest (12 cells), then x (4), then y (2): keys ordered (z, x, y).
  std::vector<Eigen::Vector3d> x;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 2000; ++k) x.emplace_back(4.0 * u(random), 2.0 * u(random), 12.0 * u(random));
  std::vector<int> items(x.size());
  std::iota(items.begin(), items.end(), 0);
  SpatialOrderWork work;
  order_along_cells(x, 1.0, 3, items, work);
  Eigen::Vector3d low = x[0];
  for (const auto& p : x) low = low.cwiseMin(p);
  auto key = [&](int i) {
    return std::array<int, 4>{cell_along(x, i, 2, low.z(), 1.0), cell_along(x, i, 0, low.x(), 1.0),
                              cell_along(x, i, 1, low.y(), 1.0), i};
  };
  for (std::size_t t = 1; t < items.size(); ++t) {
    ASSERT_LT(key(items[t - 1]), key(items[t])) << "at " << t;  // cells, then the given order
  }
}

TEST(SpatialOrder, AParticleFarOutDoesNotOverflowTheKeys) {
  std::vector<Eigen::Vector3d> x;
  for (int k = 0; k < 100; ++k) x.emplace_back(0.01 * k, 0.01 * (k % 7), 0.01 * (k % 5));
  x.emplace_back(1e12, -1e12, 1e12);  // 10^14 cells an axis before the cap
  std::vector<int> items(x.size());
  std::iota(items.begin(), items.end(), 0);
  std::reverse(items.begin(), items.end());
  SpatialOrderWork work;
  order_along_cells(x, 0.01, 3, items, work);
  std::vector<int> sorted = items;
  std::sort(sorted.begin(), sorted.end());
  for (int k = 0; k <= 100; ++k) ASSERT_EQ(sorted[k], k);
  // The far particle is alone in its cells, at one end; the near ones keep distinct x cells
  // (below the cap of 2^20 cells an axis), in x's order.
  const bool far_first = items.front() == 100;
  EXPECT_TRUE(far_first || items.back() == 100);
  for (int t = 1; t < 100; ++t) {
    EXPECT_EQ(items[t - 1 + (far_first ? 1 : 0)] + 1, items[t + (far_first ? 1 : 0)]);
  }
}

TEST(SpatialOrder, TheSameOrderOnOneAndTwoThreads) {
  // From 4 096 items the box and the keys are found in parallel.
  std::vector<Eigen::Vector3d> x;
  std::mt19937 random(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 20000; ++k) x.emplace_back(9.0 * u(random), 3.0 * u(random), u(random));
  std::vector<int> given(x.size());
  std::iota(given.begin(), given.end(), 0);
  std::shuffle(given.begin(), given.end(), random);
  std::vector<int> one = given, two = given;
  SpatialOrderWork work;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  order_along_cells(x, 0.2, 3, one, work);
  omp_set_num_threads(2);
  order_along_cells(x, 0.2, 3, two, work);
  omp_set_num_threads(threads);
  EXPECT_EQ(one, two);
  EXPECT_NE(one, given);
}

}  // namespace
}  // namespace cosim::mps

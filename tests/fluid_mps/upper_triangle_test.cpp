// The CG product over the upper triangle of the symmetric pressure matrix (upper_triangle.hpp):
// the product of the full rows to round-off, the same bits for any thread count, and the same
// solves; and the assembled pressure matrices of the scenes are symmetric in their values, which
// the triangle relies on.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <map>
#include <random>
#include <utility>

#include "../../fluid_mps/src/upper_triangle.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"
#include "laplacian_fixture.hpp"

using namespace cosim::mps;
using namespace cosim::mps::test;

namespace {

// A symmetric matrix of n rows whose pairs lie near the diagonal (within `band` rows, as the
// cell order gives), plus pairs far apart in index (a periodic wrap), in shuffled row order,
// with the diagonal summed from two entries of its column, a pair split in two entries of one
// column, and zero padding; rows with no pair at all.
SparseRows symmetric_test_matrix(int n, int band, std::mt19937& random) {
  std::uniform_real_distribution<double> number(0.1, 1.0);
  std::uniform_int_distribution<int> offset_of(1, band), far_of(0, n - 1);
  std::map<std::pair<int, int>, double> pairs;  // (i, j), i < j
  for (int i = 0; i < n; ++i) {
    if (i % 101 == 0) continue;  // rows with no pair
    for (int k = 0; k < 12; ++k) {
      const int j = i + offset_of(random);
      if (j < n) pairs[{i, j}] = -number(random);
    }
    if (i % 37 == 0) {
      const int j = far_of(random);
      if (j != i) pairs[{std::min(i, j), std::max(i, j)}] = -number(random);
    }
  }
  std::vector<std::vector<std::pair<int, double>>> rows(n);
  for (const auto& [ij, value] : pairs) {
    const auto [i, j] = ij;
    if ((i + j) % 29 == 0) {  // one pair as two entries of its column, in both rows
      rows[i].emplace_back(j, 0.25 * value);
      rows[i].emplace_back(j, 0.75 * value);
      rows[j].emplace_back(i, 0.25 * value);
      rows[j].emplace_back(i, 0.75 * value);
    } else {
      rows[i].emplace_back(j, value);
      rows[j].emplace_back(i, value);
    }
  }
  SparseRows m;
  for (int i = 0; i < n; ++i) {
    double diagonal = 1.0;
    for (const auto& entry : rows[i]) diagonal -= entry.second;
    std::shuffle(rows[i].begin(), rows[i].end(), random);
    rows[i].emplace_back(i, 0.5 * diagonal);
    rows[i].insert(rows[i].begin(), {i, 0.5 * diagonal});
    if (i % 7 == 0) rows[i].emplace_back(i, 0.0);  // padding
    for (const auto& [column, value] : rows[i]) {
      m.column.push_back(column);
      m.value.push_back(value);
    }
    m.offset.push_back(static_cast<std::int64_t>(m.column.size()));
  }
  return m;
}

std::vector<double> random_vector(int n, std::mt19937& random) {
  std::uniform_real_distribution<double> number(-1.0, 1.0);
  std::vector<double> x(n);
  for (double& v : x) v = number(random);
  return x;
}

struct Product {
  std::vector<double> y;
  double xy = 0.0;
};

Product upper_product(const SparseRows& m, const std::vector<double>& x, int threads,
                      bool single = false) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  UpperTriangle upper;
  upper.build(m, single);
  Product product;
  product.y.assign(m.rows(), std::nan(""));
  std::vector<double> partial;
  product.xy = upper.multiply(x.data(), product.y.data(), partial);
  omp_set_num_threads(before);
  return product;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// A 2D or 3D dam break (the benchmarks' column, coarse) after `steps` steps with the CG product
// `product`.
FluidSystem stepped_dam_break(int dimension, MpsParameters::PressureProduct product, int steps) {
  const double a = 0.05715;
  MpsParameters p;
  p.dimension = dimension;
  p.pressure_product = product;
  if (dimension == 3) {
    p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
    p.radius_laplacian_over_l0 = 3.1;
  }
  p.particle_spacing = a / (dimension == 3 ? 6 : 20);
  p.max_dt = 0.25 * p.particle_spacing / std::sqrt(9.81 * 2.0 * a);
  FluidSystem system(p, dimension == 3 ? dam_break_3d(p, a, 2.0 * a, 4.0 * a, a, 2.0 * a)
                                       : dam_break(p, a, 2.0 * a, 8.0 * a, 3.0 * a));
  for (int step = 0; step < steps; ++step) system.step(system.stable_dt());
  return system;
}

}  // namespace

// Every row equals the full rows' sum to round-off of its terms, x . y is the sum of its rows,
// and both the kept-once (near) and the gathered (far) pairs are exercised: bands of 300 rows
// (within one block's window) and 6 000 rows, and pairs across the whole matrix (beyond the
// 8-block windows once there are more than 8 blocks).
TEST(MpsUpperTriangle, ProductIsTheFullRowsProductToRoundOff) {
  std::mt19937 random(11);
  for (const int band : {300, 6000}) {
    for (const int n : {700, 5000, 30011}) {
      SCOPED_TRACE(::testing::Message() << "n " << n << " band " << band);
      const SparseRows m = symmetric_test_matrix(n, band, random);
      const std::vector<double> x = random_vector(n, random);
      std::vector<double> full;
      multiply(m, x, full);
      const Product half = upper_product(m, x, 2);
      double xy = 0.0, scale_xy = 0.0;
      for (int i = 0; i < n; ++i) {
        double scale = 0.0;  // sum of |terms| of the row: the size of its round-off
        for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
          scale += std::abs(m.value[k] * x[m.column[k]]);
        }
        ASSERT_NEAR(half.y[i], full[i], 1e-14 * scale) << "row " << i;
        xy += x[i] * full[i];
        scale_xy += std::abs(x[i] * full[i]);
      }
      EXPECT_NEAR(half.xy, xy, 1e-13 * scale_xy);
      UpperTriangle upper;
      upper.build(m);
      EXPECT_GT(upper.near_entries(), 0);
      if (n > (UpperTriangle::kNearBlocks + 1) * UpperTriangle::kBlock) {
        EXPECT_GT(upper.far_entries(), 0);
      }
    }
  }
}

// The sums have one order whatever the thread count: 1, 2 and 3 threads give the same bits, with
// double and with float values.
TEST(MpsUpperTriangle, BitsDoNotDependOnTheThreadCount) {
  std::mt19937 random(5);
  const int n = 40000;
  const SparseRows m = symmetric_test_matrix(n, 3000, random);
  const std::vector<double> x = random_vector(n, random);
  for (const bool single : {false, true}) {
    SCOPED_TRACE(single ? "float values" : "double values");
    const Product one = upper_product(m, x, 1, single);
    for (const int threads : {2, 3}) {
      const Product more = upper_product(m, x, threads, single);
      EXPECT_TRUE(same_bits(one.y, more.y)) << threads << " threads";
      EXPECT_EQ(std::memcmp(&one.xy, &more.xy, sizeof(double)), 0) << threads << " threads";
    }
  }
}

// Conjugate gradients with the triangle's products solve the 3D MPS Laplacian (radius 3.1 l0,
// p = 0 on two boundary layers) in the iterations of the full rows' products, to the same
// solution within the tolerance, with Jacobi and with aggregation; the bits of the solution do
// not depend on the thread count; with float values in the triangle as well.
TEST(MpsUpperTriangle, ConjugateGradientsSolveAsWithTheFullRows) {
  const double radius = 3.1;
  // 22^3 = 10 648 unknowns: 11 blocks
  const SparseRows a = boundary_lattice_laplacian(26, radius, 2);
  const int rows = a.rows();
  const std::vector<double> b = varying_rhs(rows);
  for (const Preconditioner preconditioner :
       {Preconditioner::jacobi, Preconditioner::aggregation}) {
    SCOPED_TRACE(static_cast<int>(preconditioner));
    const double tolerance = 1e-8;
    std::vector<double> x_full(rows, 0.0);
    PressureSolver full_solver(preconditioner);
    const PcgResult full = full_solver.solve(a, b, x_full, tolerance, 2000);
    ASSERT_TRUE(full.converged);
    std::vector<double> x_upper[2];
    for (const int threads : {1, 2}) {
      const int before = omp_get_max_threads();
      omp_set_num_threads(threads);
      PressureSolver upper_solver(preconditioner);
      upper_solver.set_upper_triangle_product(true);
      std::vector<double>& x = x_upper[threads - 1];
      x.assign(rows, 0.0);
      const PcgResult upper = upper_solver.solve(a, b, x, tolerance, 2000);
      omp_set_num_threads(before);
      ASSERT_TRUE(upper.converged);
      EXPECT_LE(std::abs(upper.iterations - full.iterations), 1)
          << full.iterations << " / " << upper.iterations;
    }
    EXPECT_TRUE(same_bits(x_upper[0], x_upper[1]));
    double largest = 0.0;
    const double difference = largest_difference(x_upper[0], x_full, largest);
    EXPECT_LT(difference, 1e-7 * largest);
    EXPECT_LE(relative_residual(a, b, x_upper[0]), 1.01 * tolerance);
    // With float values in the triangle, the true residuals of residual replacement (full rows,
    // double values) still decide the stop: the tolerance holds on the double system.
    PressureSolver single_solver(preconditioner);
    single_solver.set_upper_triangle_product(true);
    single_solver.set_single_precision_product(true);
    std::vector<double> x_single(rows, 0.0);
    const PcgResult single = single_solver.solve(a, b, x_single, tolerance, 2000);
    ASSERT_TRUE(single.converged);
    std::cout << "[upper triangle] " << rows << " unknowns: " << full.iterations
              << " iterations (full rows), " << single.iterations << " (float triangle)\n";
    // Each residual replacement restarts the recurrence: a few more iterations.
    EXPECT_LE(single.iterations, full.iterations + full.iterations / 8)
        << full.iterations << " / " << single.iterations;
    EXPECT_LE(relative_residual(a, b, x_single), tolerance);
  }
}

// The assembled pressure equations of a 2D and a 3D dam break, mid-collapse, are symmetric in
// their values, bit for bit (a_ij and a_ji come from w(r_ij) of the same distance), so the
// triangle's product is that of the matrix the step assembled.
TEST(MpsUpperTriangle, AssembledPressureMatricesAreSymmetric) {
  for (const int dimension : {2, 3}) {
    SCOPED_TRACE(dimension);
    const FluidSystem system =
        stepped_dam_break(dimension, MpsParameters::PressureProduct::automatic, 20);
    const SparseRows& m = system.pressure_matrix();
    ASSERT_GT(m.rows(), 100);
    std::map<std::pair<int, int>, double> entries;
    for (int i = 0; i < m.rows(); ++i) {
      for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
        if (m.column[k] != i) entries[{i, m.column[k]}] += m.value[k];
      }
    }
    int asymmetric = 0;
    for (const auto& [ij, value] : entries) {
      const auto mirror = entries.find({ij.second, ij.first});
      if (mirror == entries.end() || std::memcmp(&mirror->second, &value, sizeof value) != 0) {
        ++asymmetric;
      }
    }
    EXPECT_EQ(asymmetric, 0) << "of " << entries.size() << " pairs";
  }
}

// pressure_product: automatic takes the upper triangle in 3D and the full rows in 2D: its runs
// have the bits of the explicit choice, and the other choice gives other bits.
TEST(MpsUpperTriangle, AutomaticProductIsTheUpperTriangleIn3DOnly) {
  using Product = MpsParameters::PressureProduct;
  for (const int dimension : {2, 3}) {
    SCOPED_TRACE(dimension);
    auto run = [&](Product product) {
      return stepped_dam_break(dimension, product, 15).pressures();
    };
    const std::vector<double> automatic = run(Product::automatic);
    const std::vector<double> chosen =
        run(dimension == 3 ? Product::upper_triangle : Product::full_rows);
    const std::vector<double> other =
        run(dimension == 3 ? Product::full_rows : Product::upper_triangle);
    EXPECT_TRUE(same_bits(automatic, chosen));
    EXPECT_FALSE(same_bits(automatic, other));
  }
}

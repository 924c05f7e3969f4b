// Unit tests of the MPS building blocks: lattice sums, operators, neighbour search, PCG.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include <omp.h>

#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/operators.hpp"
#include "cosim/fluid_mps/pressure_solver.hpp"
#include "laplacian_fixture.hpp"

using namespace cosim::mps;
using namespace cosim::mps::test;

namespace {

int centre_index(int dimension, int count) {
  const int c = count / 2;
  return dimension == 3 ? (c * count + c) * count + c : c * count + c;
}

}  // namespace

TEST(MpsLatticeSums, MatchReferenceTableEveryRow) {
  std::ifstream in(std::string(COSIM_SHARED_REFERENCES) + "/mps_lattice_sums.csv");
  ASSERT_TRUE(in.good());
  std::string line;
  std::getline(in, line);  // header
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::stringstream ss(line);
    std::string field;
    std::vector<double> v;
    while (std::getline(ss, field, ',')) v.push_back(std::stod(field));
    ASSERT_EQ(v.size(), 4u);
    const LatticeSums sums = lattice_sums(static_cast<int>(v[0]), v[1]);
    EXPECT_NEAR(sums.n0, v[2], 1e-6) << line;
    EXPECT_NEAR(sums.lambda_over_l0sq, v[3], 1e-6) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 5);
}

TEST(MpsLatticeSums, NumberDensityOfLatticeInteriorEqualsN0) {
  for (int dimension : {2, 3}) {
    const double l0 = 0.01, re = 2.1 * l0;
    const int count = dimension == 2 ? 11 : 7;
    const auto points = lattice(dimension, count, l0);
    NeighbourGrid grid(dimension, box_of(points, l0), re);
    grid.build(points);
    const auto n = number_density(points, grid.neighbours(points, re), re);
    EXPECT_NEAR(n[centre_index(dimension, count)], lattice_sums(dimension, 2.1).n0, 1e-9);
  }
}

// On a full lattice, sum w r_hat r_hat^T = (n0 / d) I, so the gradient model is exact for a
// linear field and the Laplacian model is exact for |r|^2 (seed 001 eqs. (8), (9)).
TEST(MpsOperators, GradientOfLinearFieldAndLaplacianOfQuadraticOnLattice) {
  for (int dimension : {2, 3}) {
    for (double ratio : {2.1, 3.1, 4.0}) {
      if (dimension == 3 && ratio > 3.5) continue;
      const double l0 = 0.02, re = ratio * l0;
      const int count = dimension == 2 ? 13 : 9;
      const auto points = lattice(dimension, count, l0);
      NeighbourGrid grid(dimension, box_of(points, l0), re);
      grid.build(points);
      const NeighbourList list = grid.neighbours(points, re);
      const LatticeSums sums = lattice_sums(dimension, ratio);
      const Eigen::Vector3d slope(3.0, -2.0, dimension == 3 ? 5.0 : 0.0);
      std::vector<double> linear, quadratic;
      for (const auto& x : points) {
        linear.push_back(7.0 + slope.dot(x));
        quadratic.push_back(x.squaredNorm() + 0.5 * x.x());
      }
      const int c = centre_index(dimension, count);
      const auto grad = gradient(dimension, points, linear, list, re, sums.n0);
      EXPECT_LT((grad[c] - slope).norm(), 0.02 * slope.norm()) << dimension << "D re=" << ratio;
      const auto lap =
          laplacian(dimension, quadratic, list, re, sums.n0, sums.lambda_over_l0sq * l0 * l0);
      EXPECT_NEAR(lap[c], 2.0 * dimension, 0.02 * 2.0 * dimension) << dimension << "D re=" << ratio;
    }
  }
}

TEST(MpsNeighbourGrid, MatchesBruteForce) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int dimension : {2, 3}) {
    std::vector<Eigen::Vector3d> points(1500);
    for (auto& p : points) p = Eigen::Vector3d(u(rng), u(rng), dimension == 3 ? u(rng) : 0.0);
    const double radius = 0.07;
    NeighbourGrid grid(dimension,
                       Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, -0.1), Eigen::Vector3d(1, 1, 1.1)),
                       radius);
    grid.build(points);
    const NeighbourList list = grid.neighbours(points, radius);
    for (int i = 0; i < static_cast<int>(points.size()); i += 37) {
      std::vector<int> expected,
          found(list.index.begin() + list.begin(i), list.index.begin() + list.end(i));
      for (int j = 0; j < static_cast<int>(points.size()); ++j) {
        if (j != i && (points[j] - points[i]).norm() < radius) expected.push_back(j);
      }
      std::sort(found.begin(), found.end());
      EXPECT_EQ(found, expected);
      std::vector<int> queried;
      grid.query(points, points[i], 2.5 * radius, queried);
      int brute = 0;
      for (const auto& q : points) brute += (q - points[i]).norm() < 2.5 * radius;
      EXPECT_EQ(static_cast<int>(queried.size()), brute);
    }
  }
}

// The keyed search with a row mask against the plain search: a particle without a row of its
// own gets none, every other row holds exactly the plain search's partners (the masked particles
// among them), in ascending key.
TEST(MpsNeighbourGrid, KeyedSearchWithRowMaskKeepsTheOtherRows) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int dimension : {2, 3}) {
    const int n = 1200;
    std::vector<Eigen::Vector3d> points(n);
    for (auto& p : points) p = Eigen::Vector3d(u(rng), u(rng), dimension == 3 ? u(rng) : 0.0);
    // A permutation (n is not a multiple of 7919), and the same spread up to 4.9e6: the radix
    // sort of the candidates then takes three passes instead of two.
    std::vector<int> key(n);
    for (int i = 0; i < n; ++i) key[i] = (i * 7919) % n * (dimension == 3 ? 4099 : 1) + 7;
    std::vector<char> rows(n);
    for (int i = 0; i < n; ++i) rows[i] = points[i].x() < 0.4 ? 0 : 1;  // a "dummy" slab
    const double radius = 0.08;
    NeighbourGrid grid(dimension,
                       Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, -0.1), Eigen::Vector3d(1, 1, 1.1)),
                       radius);
    grid.build(points);
    const NeighbourList plain = grid.neighbours(points, radius);
    NeighbourList masked;
    grid.neighbours_by_key(points, radius, key, masked, &rows);
    int checked = 0, partners_without_row = 0;
    for (int i = 0; i < n; ++i) {
      std::vector<int> found(masked.index.begin() + masked.begin(i),
                             masked.index.begin() + masked.end(i));
      if (!rows[i]) {
        EXPECT_TRUE(found.empty()) << i;
        continue;
      }
      std::vector<int> expected(plain.index.begin() + plain.begin(i),
                                plain.index.begin() + plain.end(i));
      std::sort(expected.begin(), expected.end(), [&](int a, int b) { return key[a] < key[b]; });
      EXPECT_EQ(found, expected) << i;
      for (int j : found) partners_without_row += rows[j] == 0;
      ++checked;
    }
    EXPECT_GT(checked, n / 2);
    EXPECT_GT(partners_without_row, 0);  // the masked particles are still partners
  }
}

// The keyed search on particles dense enough that each cell is split in parts (a cell of 16 or
// more particles in 3D, 8 in 2D: a part's particles test only the candidates near their part's
// box) against all pairs by brute force, in ascending key: a jittered lattice, some particles
// exactly on the lines that split the cells, with the cells as large as the radius (as the
// fluid searches) and larger.
TEST(MpsNeighbourGrid, KeyedSearchInDenseCellsFindsEveryPairInKeyOrder) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (int dimension : {2, 3}) {
    for (double cell_over_radius : {1.0, 1.4}) {
      SCOPED_TRACE(testing::Message() << dimension << "D, cell " << cell_over_radius << " radius");
      const double radius = 3.3;  // lattice spacing 1: about 36 particles a cell in 3D, 11 in 2D
      const double cell = cell_over_radius * radius;
      const int side = dimension == 3 ? 13 : 40;
      std::vector<Eigen::Vector3d> points;
      for (int a = 0; a < side; ++a)
        for (int b = 0; b < side; ++b)
          for (int c = 0; c < (dimension == 3 ? side : 1); ++c) {
            Eigen::Vector3d x(a + jitter(rng), b + jitter(rng),
                              dimension == 3 ? c + jitter(rng) : 0);
            points.push_back(x);
          }
      // The box starts at -1, so the cells' centres lie at -1 + (k + 1/2) cell: put particles
      // exactly there, on the planes between two parts.
      for (int k = 0; k < 6; ++k) {
        const double centre = -1.0 + (k + 0.5) * cell;
        points[static_cast<std::size_t>(k) * 41 % points.size()].x() = centre;
        points[static_cast<std::size_t>(k) * 53 % points.size()].y() = centre;
        if (dimension == 3) points[static_cast<std::size_t>(k) * 67 % points.size()].z() = centre;
      }
      const int n = static_cast<int>(points.size());
      std::vector<int> key(n);
      for (int i = 0; i < n; ++i) key[i] = (i * 7919) % n;
      const Eigen::AlignedBox3d box(Eigen::Vector3d::Constant(-1.0),
                                    Eigen::Vector3d::Constant(side + 1.0));
      NeighbourGrid grid(dimension, box, cell);
      grid.build(points);
      NeighbourList list;
      grid.neighbours_by_key(points, radius, key, list);
      std::size_t pairs = 0;
      for (int i = 0; i < n; ++i) {
        std::vector<int> expected;
        for (int j = 0; j < n; ++j) {
          if (j != i && (points[j] - points[i]).squaredNorm() < radius * radius)
            expected.push_back(j);
        }
        std::sort(expected.begin(), expected.end(), [&](int a, int b) { return key[a] < key[b]; });
        const std::vector<int> found(list.index.begin() + list.begin(i),
                                     list.index.begin() + list.end(i));
        ASSERT_EQ(found, expected) << "particle " << i;
        pairs += found.size();
      }
      EXPECT_GT(pairs, static_cast<std::size_t>(n) * (dimension == 3 ? 100 : 25));
    }
  }
}

// The keyed search keeps its work arrays between searches (NeighbourSearchWork): a search
// that reuses them, into a list that held another search's pairs, gives the list of a fresh
// search, with one and two threads. The searches: particles in cell order (one thread then
// takes the buffer as the list), the same particles moved (rows out of order: copied), and more
// particles, so more pairs than the buffers held (they grow).
TEST(MpsNeighbourGrid, KeyedSearchReusingItsWorkGivesTheListsOfFreshSearches) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0), jitter(-0.02, 0.02);
  const double radius = 0.1;
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.1, -0.1, -0.1), Eigen::Vector3d(1.1, 1.1, 1.1));
  std::vector<std::vector<Eigen::Vector3d>> sets;
  std::vector<Eigen::Vector3d> first(5000);
  for (auto& p : first) p = Eigen::Vector3d(u(rng), u(rng), u(rng));
  NeighbourGrid sorter(3, box, radius);
  sorter.build(first);
  std::vector<Eigen::Vector3d> in_cell_order;
  for (int i : sorter.cell_order()) in_cell_order.push_back(first[i]);
  sets.push_back(in_cell_order);
  std::vector<Eigen::Vector3d> moved = in_cell_order;
  for (auto& p : moved) p += Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
  sets.push_back(moved);
  std::vector<Eigen::Vector3d> more = moved;
  for (int i = 0; i < 3000; ++i) more.emplace_back(u(rng), u(rng), u(rng));
  sets.push_back(more);
  const int threads_before = omp_get_max_threads();
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    NeighbourSearchWork work;
    NeighbourList reused;
    for (std::size_t set = 0; set < sets.size(); ++set) {
      SCOPED_TRACE(testing::Message() << threads << " threads, search " << set);
      const auto& points = sets[set];
      const int n = static_cast<int>(points.size());
      std::vector<int> key(n);
      for (int i = 0; i < n; ++i) key[i] = (i * 7919) % n;
      NeighbourGrid grid(3, box, radius);
      grid.build(points);
      grid.neighbours_by_key(points, radius, key, reused, nullptr, &work);
      NeighbourList fresh;
      grid.neighbours_by_key(points, radius, key, fresh);
      EXPECT_EQ(reused.offset, fresh.offset);
      EXPECT_EQ(reused.index, fresh.index);
      EXPECT_GT(fresh.pair_count(), static_cast<std::size_t>(10 * n));  // about 20 a particle
    }
  }
  omp_set_num_threads(threads_before);
}

TEST(MpsPressureSolver, SolvesOneDimensionalPoisson) {
  // -x[i-1] + 2 x[i] - x[i+1] = h^2 with Dirichlet ends: x = i (n + 1 - i) / 2 on a unit grid.
  const int n = 200;
  SparseRows a;
  std::vector<double> b(n, 1.0), x(n, 0.0);
  for (int i = 0; i < n; ++i) {
    if (i > 0) a.column.push_back(i - 1), a.value.push_back(-1.0);
    a.column.push_back(i), a.value.push_back(2.0);
    if (i < n - 1) a.column.push_back(i + 1), a.value.push_back(-1.0);
    a.offset.push_back(static_cast<std::int64_t>(a.column.size()));
  }
  for (Preconditioner preconditioner :
       {Preconditioner::jacobi, Preconditioner::incomplete_cholesky, Preconditioner::amg}) {
    std::fill(x.begin(), x.end(), 0.0);
    const PcgResult result = solve_pcg(a, b, x, 1e-10, 1000, preconditioner);
    EXPECT_TRUE(result.converged);
    EXPECT_LE(result.relative_residual, 1e-10);
    for (int i = 0; i < n; ++i) EXPECT_NEAR(x[i], 0.5 * (i + 1) * (n - i), 1e-6);
  }
}

// The MPS Laplacian (radius 4 l0) on square lattices of 20^2 to 160^2 unknowns with p = 0 on a
// ring of boundary particles: multigrid iterations stay flat while Jacobi's grow with the side.
TEST(MpsPressureSolver, MultigridIterationsDoNotGrowWithResolution) {
  const double ratio = 4.0;
  std::vector<int> amg_iterations, jacobi_iterations;
  for (int side : {20, 40, 80, 160}) {
    const int count = side + 8;  // 4 boundary rows on each side
    const auto points = lattice(2, count, 1.0);
    NeighbourGrid grid(2, box_of(points, 1.0), ratio);
    grid.build(points);
    const NeighbourList list = grid.neighbours(points, ratio);
    auto inside = [&](int i) {
      const int x = i % count, y = i / count;
      return x >= 4 && x < count - 4 && y >= 4 && y < count - 4;
    };
    std::vector<int> row_of;
    const SparseRows a = kernel_laplacian(list, points.size(), ratio, inside, row_of);
    const int rows = a.rows();
    const std::vector<double> b(rows, 1.0);
    std::vector<double> x(rows, 0.0);
    const PcgResult amg = solve_pcg(a, b, x, 1e-8, 2000, Preconditioner::amg);
    EXPECT_TRUE(amg.converged);
    std::vector<double> y(rows, 0.0);
    const PcgResult jacobi = solve_pcg(a, b, y, 1e-8, 2000, Preconditioner::jacobi);
    EXPECT_TRUE(jacobi.converged);
    double largest = 0.0;
    const double difference = largest_difference(x, y, largest);
    EXPECT_LT(difference, 1e-6 * largest) << side;  // the same solution
    std::cout << "[multigrid] " << rows << " unknowns: amg " << amg.iterations << ", jacobi "
              << jacobi.iterations << " iterations\n";
    amg_iterations.push_back(amg.iterations);
    jacobi_iterations.push_back(jacobi.iterations);
  }
  for (std::size_t k = 0; k < amg_iterations.size(); ++k) {
    EXPECT_LE(amg_iterations[k], 15) << "side " << (20 << k);
  }
  EXPECT_GT(jacobi_iterations.back(), 4 * jacobi_iterations.front());
  EXPECT_LE(amg_iterations.back(), amg_iterations.front() + 4);
}

TEST(MpsOperators, DivergenceOfLinearVelocityIsItsTrace) {
  for (int dimension : {2, 3}) {
    const double l0 = 0.02, re = 2.1 * l0;
    const int count = dimension == 2 ? 13 : 9;
    const auto points = lattice(dimension, count, l0);
    NeighbourGrid grid(dimension, box_of(points, l0), re);
    grid.build(points);
    const NeighbourList list = grid.neighbours(points, re);
    Eigen::Matrix3d g;
    g << 1.0, 2.0, -1.0, 0.5, -3.0, 2.0, 1.5, 0.25, 4.0;
    if (dimension == 2) g.row(2).setZero(), g.col(2).setZero();
    std::vector<Eigen::Vector3d> velocity;
    for (const auto& x : points) velocity.push_back(g * x);
    const auto div =
        divergence(dimension, points, velocity, list, re, lattice_sums(dimension, 2.1).n0);
    const int c = centre_index(dimension, count);
    EXPECT_NEAR(div[c], g.trace(), 1e-9 * g.norm()) << dimension << "D";
  }
}

namespace {

// Rows in the blocks of the product (so it runs in parallel): how many of A x differ in their
// bits from the plain row loop's.
int product_differing_from_plain_loop(int n, bool single = false) {
  std::mt19937 random(7);
  std::uniform_int_distribution<int> length_of(0, 40);
  std::uniform_real_distribution<double> number(-1.0, 1.0);
  cosim::mps::SparseRows m;
  for (int i = 0; i < n; ++i) {
    const int length = i == 3 ? 2 : (i % 97 == 0 ? 0 : length_of(random));
    std::uniform_int_distribution<int> column_of(0, n - 1);
    for (int k = 0; k < length; ++k) {
      m.column.push_back(i == 3 ? i : column_of(random));
      m.value.push_back(i == 3 ? -0.0 : number(random) * std::pow(10.0, length_of(random) - 20));
    }
    m.offset.push_back(static_cast<std::int64_t>(m.column.size()));
  }
  std::vector<double> x(n);
  for (double& v : x) v = number(random);
  x[3] = 1.0;  // row 3: 0 + -0 * 1 + -0 * 1 = +0
  std::vector<double> y;
  cosim::mps::multiply(m, x, y, single);
  if (static_cast<int>(y.size()) != n) return n;
  int differing = 0;
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      const double value =
          single ? static_cast<double>(static_cast<float>(m.value[k])) : m.value[k];
      sum += value * x[m.column[k]];
    }
    if (std::memcmp(&sum, &y[i], sizeof sum) != 0) ++differing;
  }
  if (!std::signbit(y[3])) return differing;  // 0 + -0 + -0 is +0
  return differing + 1;
}

}  // namespace

// The row products (double values: the rows interleaved by groups, padded with zeros; float
// values: the rows' own layout) keep each row's summation order: their bits are those of the
// plain loop, for rows of every length (empty rows, rows ending inside a group, a row of -0
// products, the last rows of the matrix) and whatever the thread count; with 16-bit column
// indices (up to 65 536 rows) and 32-bit ones.
TEST(MpsPressureSolver, MatrixProductHasTheBitsOfThePlainRowLoop) {
  for (const int n : {5000, 70000}) {
    SCOPED_TRACE(n);
    EXPECT_EQ(product_differing_from_plain_loop(n), 0);
    EXPECT_EQ(product_differing_from_plain_loop(n, true), 0);  // float values
  }
}

// CG with the float-valued product on the MPS Laplacian (3D lattice, radius 3.1 l0 as in the 3D
// scenes, p = 0 on two boundary layers, Jacobi and aggregation): it converges in about as many
// iterations (aggregation 24 / 24; Jacobi from zero 30 / 33: its last true residual asks for a
// few more), and with its true residuals (residual replacement) it meets the tolerance on the
// double matrix, as the double product does (without them it stopped at 1.1e-7 with Jacobi);
// its solution is that of the double product to the tolerance.
TEST(MpsPressureSolver, SinglePrecisionProductConvergesToTheDoubleSolution) {
  const double radius = 3.1;
  // 18^3 unknowns inside 2 boundary layers
  const SparseRows a = boundary_lattice_laplacian(22, radius, 2);
  const int rows = a.rows();
  const std::vector<double> b = varying_rhs(rows);
  for (const Preconditioner preconditioner :
       {Preconditioner::jacobi, Preconditioner::aggregation}) {
    SCOPED_TRACE(static_cast<int>(preconditioner));
    std::vector<double> x_double(rows, 0.0), x_single(rows, 0.0);
    PressureSolver double_solver(preconditioner), single_solver(preconditioner);
    single_solver.set_single_precision_product(true);
    const double tolerance = 1e-8;
    const PcgResult d = double_solver.solve(a, b, x_double, tolerance, 2000);
    const PcgResult s = single_solver.solve(a, b, x_single, tolerance, 2000);
    ASSERT_TRUE(d.converged);
    ASSERT_TRUE(s.converged);
    EXPECT_LE(std::abs(s.iterations - d.iterations), 3) << d.iterations << " / " << s.iterations;
    const double residual = relative_residual(a, b, x_single);
    double largest = 0.0;
    const double difference = largest_difference(x_single, x_double, largest);
    std::cout << "[single product] " << rows << " unknowns: " << d.iterations << " / "
              << s.iterations << " iterations, true residual " << residual << " (reported "
              << s.relative_residual << "), largest difference " << difference / largest
              << " of the largest pressure\n";
    EXPECT_LE(residual, tolerance);
    EXPECT_NEAR(residual, s.relative_residual, 1e-3 * tolerance);
    EXPECT_LT(difference, 1e-7 * largest);
    EXPECT_GT(difference, 0.0);  // it is a different product: the bits change
  }
}

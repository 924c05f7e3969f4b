// The accelerators of implicit coupling on linear fixed-point problems x = A x + b with a known
// solution x* = (I - A)^-1 b. A has an eigenvalue below -1, so plain iteration x <- H(x)
// diverges, as a partitioned scheme does for a light structure in a dense fluid.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "cosim/coupler/acceleration.hpp"

namespace cosim::coupler {
namespace {

struct LinearMap {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::VectorXd operator()(const Eigen::VectorXd& x) const { return a * x + b; }
  Eigen::VectorXd solution() const {
    return (Eigen::MatrixXd::Identity(a.rows(), a.cols()) - a).lu().solve(b);
  }
};

// Eigenvalues -2.5, -1.2, 0.3, 0.6, 0.9 in a rotated basis: contraction along three directions,
// expansion with sign change along two (what the added mass does to the structure's modes).
LinearMap expanding_map(double shift = 0.0) {
  const Eigen::VectorXd eigenvalues = (Eigen::VectorXd(5) << -2.5, -1.2, 0.3, 0.6, 0.9).finished();
  const Eigen::MatrixXd basis =
      Eigen::HouseholderQR<Eigen::MatrixXd>((Eigen::MatrixXd(5, 5) << 1, 2, 0, 1, 3, 0, 1, 4, 1, 0,
                                             2, 0, 1, 3, 1, 1, 1, 1, 0, 2, 3, 0, 2, 1, 1)
                                                .finished())
          .householderQ();
  LinearMap map;
  map.a = basis * eigenvalues.asDiagonal() * basis.transpose();
  map.b = (Eigen::VectorXd(5) << 1.0, -2.0, 0.5, 3.0, -1.0).finished();
  map.b.array() += shift;
  return map;
}

// Iterates one window from x0 until |H(x) - x| <= tolerance |x*|; returns the iterations
// (evaluations of H) it took, or -1 after `most`.
int iterate(Accelerator& accelerator, const LinearMap& map, Eigen::VectorXd x, int most,
            double tolerance = 1e-10) {
  const double scale = map.solution().norm();
  for (int k = 1; k <= most; ++k) {
    const Eigen::VectorXd h = map(x);
    if (!h.allFinite()) return -1;
    if ((h - x).norm() <= tolerance * scale) return k;
    x = accelerator.next(x, h);
  }
  return -1;
}

TEST(Acceleration, PlainIterationDivergesOnTheExpandingMap) {
  Accelerator plain({AccelerationKind::none});
  const auto map = expanding_map();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(5);
  for (int k = 0; k < 30; ++k) x = plain.next(x, map(x));
  EXPECT_GT((x - map.solution()).norm(), 1e6 * map.solution().norm());
}

TEST(Acceleration, ConstantUnderRelaxationConverges) {
  // omega (1 - lambda) must lie in (0, 2) for every eigenvalue: omega < 2 / 3.5 = 0.57.
  Accelerator relaxed({AccelerationKind::constant, 0.4});
  const auto map = expanding_map();
  const int iterations = iterate(relaxed, map, Eigen::VectorXd::Zero(5), 2000);
  EXPECT_GT(iterations, 0);
  // The slowest mode contracts by |1 - 0.4 (1 - 0.9)| = 0.96 per iteration: hundreds of them.
  EXPECT_GT(iterations, 100);
}

TEST(Acceleration, ConstantRelaxationTooLargeStillDiverges) {
  Accelerator relaxed({AccelerationKind::constant, 0.7});  // 1 - 0.7 * 3.5 = -1.45
  EXPECT_EQ(iterate(relaxed, expanding_map(), Eigen::VectorXd::Zero(5), 300), -1);
}

TEST(Acceleration, AitkenConvergesFasterThanConstantRelaxation) {
  const auto map = expanding_map();
  Accelerator constant({AccelerationKind::constant, 0.4});
  Accelerator aitken({AccelerationKind::aitken, 0.4});
  const int by_constant = iterate(constant, map, Eigen::VectorXd::Zero(5), 1000);
  const int by_aitken = iterate(aitken, map, Eigen::VectorXd::Zero(5), 1000);
  ASSERT_GT(by_aitken, 0);
  EXPECT_LT(by_aitken, by_constant);
}

TEST(Acceleration, AitkenOnAScalarMapIsTheSecantMethod) {
  // One unknown, h = -3 x + 4 (x* = 1): the secant step is exact after two evaluations.
  LinearMap map{Eigen::MatrixXd::Constant(1, 1, -3.0), Eigen::VectorXd::Constant(1, 4.0)};
  Accelerator aitken({AccelerationKind::aitken, 0.1});
  EXPECT_EQ(iterate(aitken, map, Eigen::VectorXd::Zero(1), 10, 1e-12), 3);
}

TEST(Acceleration, PositiveAitkenStartsAgainWhereTheSecantTurnsNegative) {
  // One unknown: x = 0 gives h = 1 (r = 1), the step 0.1 r to x = 0.1 gives h = 2.1 (r = 2): the
  // residual grew along the step, and the secant factor -0.1 r0 (r1 - r0) / (r1 - r0)^2 = -0.1
  // would step back, to x = -0.1.
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(1), h0 = Eigen::VectorXd::Constant(1, 1.0);
  const Eigen::VectorXd h1 = Eigen::VectorXd::Constant(1, 2.1);
  AccelerationOptions plain{AccelerationKind::aitken, 0.1};
  AccelerationOptions positive = plain;
  positive.positive_aitken = true;
  Accelerator secant(plain), restarted(positive);
  const Eigen::VectorXd x1 = secant.next(x0, h0);
  ASSERT_DOUBLE_EQ(x1[0], 0.1);
  ASSERT_DOUBLE_EQ(restarted.next(x0, h0)[0], 0.1);
  EXPECT_NEAR(secant.next(x1, h1)[0], 0.1 - 0.1 * 2.0, 1e-15);
  EXPECT_NEAR(secant.aitken_factor(), -0.1, 1e-15);
  EXPECT_NEAR(restarted.next(x1, h1)[0], 0.1 + 0.1 * 2.0, 1e-15);  // relaxation again
  EXPECT_EQ(restarted.aitken_restarts(), 1);
  EXPECT_EQ(secant.aitken_restarts(), 0);
}

TEST(Acceleration, PositiveAitkenLeavesAContractingSecantAlone) {
  // The expanding map's eigenvalues all lie below 1: the factors stay positive and the iterates
  // are those of plain Aitken.
  const auto map = expanding_map();
  AccelerationOptions positive{AccelerationKind::aitken, 0.4};
  positive.positive_aitken = true;
  Accelerator aitken({AccelerationKind::aitken, 0.4}), restarted(positive);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(5), y = x;
  for (int k = 0; k < 40; ++k) {
    x = aitken.next(x, map(x));
    y = restarted.next(y, map(y));
    ASSERT_EQ(x, y) << "iteration " << k;
  }
  EXPECT_EQ(restarted.aitken_restarts(), 0);
}

TEST(Acceleration, IqnIlsConvergesWithinTheDimensionPlusTwo) {
  // On a linear map of n unknowns the columns span the Krylov space after n differences, and
  // the least-squares step is then exact (Degroote et al. 2009 relate IQN-ILS to GMRES): at most
  // n + 2 evaluations of H (one relaxed step, n secant steps, the check of the last).
  const auto map = expanding_map();
  Accelerator iqn({AccelerationKind::iqn_ils, 0.1});
  const int iterations = iterate(iqn, map, Eigen::VectorXd::Zero(5), 50);
  ASSERT_GT(iterations, 0);
  EXPECT_LE(iterations, 7);
}

TEST(Acceleration, IqnIlsReusingThePreviousWindowConvergesAtOnce) {
  // The next window has another right-hand side but the same map: the kept columns already
  // hold its inverse Jacobian, so the first step lands on the solution.
  Accelerator fresh({AccelerationKind::iqn_ils, 0.1});
  AccelerationOptions options{AccelerationKind::iqn_ils, 0.1};
  options.reuse_windows = 1;
  Accelerator reusing(options);
  const auto first = expanding_map();
  const auto second = expanding_map(0.7);
  ASSERT_GT(iterate(fresh, first, Eigen::VectorXd::Zero(5), 50), 0);
  ASSERT_GT(iterate(reusing, first, Eigen::VectorXd::Zero(5), 50), 0);
  fresh.end_window();
  reusing.end_window();
  const Eigen::VectorXd start = first.solution();
  const int without = iterate(fresh, second, start, 50);
  const int with = iterate(reusing, second, start, 50);
  ASSERT_GT(with, 0);
  EXPECT_EQ(with, 2);
  EXPECT_GT(without, with);
}

TEST(Acceleration, IqnIlsFiltersDependentColumns) {
  // Reusing many windows of the same 2-unknown map, with room for more columns than unknowns,
  // gives columns dependent on the newer ones; the filter keeps the least-squares problem full
  // rank, so every window still converges.
  LinearMap map{(Eigen::MatrixXd(2, 2) << -2.0, 0.5, 0.3, -1.5).finished(),
                Eigen::VectorXd::Constant(2, 1.0)};
  AccelerationOptions options{AccelerationKind::iqn_ils, 0.2};
  options.reuse_windows = 5;
  options.max_columns = 10;
  Accelerator iqn(options);
  for (int window = 0; window < 6; ++window) {
    // The map changes a little from window to window, as a coupled problem does: the kept
    // columns are close to, not the same as, the new ones.
    LinearMap shifted = map;
    shifted.a *= 1.0 + 0.1 * window;
    shifted.b(1) += 0.3 * window;
    const int iterations = iterate(iqn, shifted, Eigen::VectorXd::Zero(2), 20, 1e-12);
    ASSERT_GT(iterations, 0) << "window " << window;
    iqn.end_window();
  }
  EXPECT_GT(iqn.filtered_columns(), 0);
}

// The expanding map with an answer that is not smooth in its input (a fluid whose particles
// collide and whose neighbour lists change between iterations): a deterministic jitter of
// relative size 1e-3 that jumps with every small change of x, and no answer at all (NaN) for an
// input farther than 5 |x*| from the solution (the fluid stops on an absurd input). Returns the
// evaluations to |H(x) - x| <= 1e-2 |x*| (-1: not within `most`, or an input it could not
// take), and the largest update |x_next - x| / |H(x) - x| on the way.
std::pair<int, double> iterate_noisy(Accelerator& accelerator, int most) {
  const auto map = expanding_map();
  const Eigen::VectorXd solution = map.solution();
  const double scale = solution.norm();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(5);
  double largest = 0;
  for (int k = 1; k <= most; ++k) {
    if ((x - solution).norm() > 5 * scale) return {-1, largest};
    Eigen::VectorXd h = map(x);
    for (Eigen::Index j = 0; j < 5; ++j)
      h(j) += 1e-3 * scale * std::sin(1e6 * x.sum() + 7.0 * static_cast<double>(j));
    if ((h - x).norm() <= 1e-2 * scale) return {k, largest};
    const Eigen::VectorXd next = accelerator.next(x, h);
    largest = std::max(largest, (next - x).norm() / (h - x).norm());
    x = next;
  }
  return {-1, largest};
}

TEST(Acceleration, BoundedStepKeepsIqnIlsWithinReachOfANoisyMap) {
  AccelerationOptions options{AccelerationKind::iqn_ils, 0.01};
  Accelerator free(options);
  options.max_step = 2.0;
  Accelerator bounded(options);
  const auto [free_iterations, free_largest] = iterate_noisy(free, 100);
  const auto [bounded_iterations, bounded_largest] = iterate_noisy(bounded, 100);
  // Unbounded, the fit to the jittered differences asks for updates 5 times the residual
  // (it still converges here, in 9 evaluations); bounded at 2 it takes 13, none longer.
  EXPECT_GT(free_iterations, 0);
  EXPECT_GT(free_largest, 2.0);
  EXPECT_LE(bounded_largest, 2.0 * (1 + 1e-12));
  EXPECT_GT(bounded_iterations, 0);
  EXPECT_GT(bounded.bounded_steps(), 0);
}

TEST(Acceleration, BoundedStepLeavesShortUpdatesAlone) {
  // On the smooth map every IQN-ILS update within the bound is the unbounded one, bit for bit.
  AccelerationOptions options{AccelerationKind::iqn_ils, 0.1};
  Accelerator free(options);
  options.max_step = 1e6;
  Accelerator bounded(options);
  const auto map = expanding_map();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(5), y = x;
  for (int k = 0; k < 6; ++k) {
    x = free.next(x, map(x));
    y = bounded.next(y, map(y));
    ASSERT_EQ(x, y) << "iteration " << k;
  }
  EXPECT_EQ(bounded.bounded_steps(), 0);
}

}  // namespace
}  // namespace cosim::coupler

// The band solver of the Newton step, against a dense LU. The bending joint's kernel
// (vegetation_beam/src/beam_elements.cpp): its stiffness and damping blocks are minus the
// derivatives of its forces by the node positions and velocities (central differences; by
// position at rest, since the Jacobian leaves out how the dashpot's force turns with the links),
// and both matrices are symmetric, as the Newton Jacobian assumes: the blocks off the diagonal
// are each other's transposes to the bit.
#include <gtest/gtest.h>

#include <random>

#include <Eigen/LU>

#include "beam_elements.hpp"
#include "cosim/vegetation_beam/banded_matrix.hpp"

namespace cosim::vegetation {
namespace {

struct Joint {
  Eigen::Vector3d x[3], v[3];
};

// Three nodes about 0.1 m apart, bent by up to about 60 degrees, moving at up to 1 m/s.
Joint random_joint(std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto vector = [&] { return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)); };
  Joint joint;
  joint.x[0] = vector();
  joint.x[1] = joint.x[0] + 0.1 * Eigen::Vector3d::UnitZ() + 0.03 * vector();
  joint.x[2] = joint.x[1] + 0.1 * Eigen::Vector3d::UnitZ() + 0.03 * vector();
  for (auto& v : joint.v) v = vector();
  return joint;
}

// Unsymmetric, diagonally dominant band matrices (as the Jacobian with the mass term), with the
// plants' half bandwidth 8 (the unrolled path, and its ends) and others (the general path), some
// smaller than the band.
TEST(BandedMatrix, SolvesAsADenseLu) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (const int w : {8, 1, 2, 5}) {
    for (const int n : {3, 9, 30, 61}) {
      BandedMatrix band;
      band.resize(n, w);
      for (int i = 0; i < n; ++i) {
        for (int j = std::max(0, i - w); j <= std::min(n - 1, i + w); ++j)
          band.at(i, j) = i == j ? 4.0 * (w + 1) + uniform(rng) : uniform(rng);
      }
      const Eigen::MatrixXd dense = band.to_dense();
      std::vector<double> rhs(n);
      for (double& value : rhs) value = uniform(rng);
      const Eigen::VectorXd expected =
          dense.partialPivLu().solve(Eigen::Map<const Eigen::VectorXd>(rhs.data(), n));
      ASSERT_TRUE(band.factorize());
      band.solve(rhs);
      for (int i = 0; i < n; ++i)
        EXPECT_NEAR(rhs[i], expected[i], 1e-14 * expected.cwiseAbs().maxCoeff()) << w << n << i;
    }
  }
}

TEST(BendingJoint, MatricesAreMinusTheForceDerivativesAndSymmetric) {
  std::mt19937_64 rng(7);
  const double spring = 0.847 / 0.1, damper = 0.02;
  for (int trial = 0; trial < 50; ++trial) {
    Joint joint = random_joint(rng);
    BendingJoint at;
    bending_joint(joint.x, joint.v, spring, damper, true, at);
    for (int n = 0; n < 3; ++n) {
      for (int m = 0; m < 3; ++m) {
        if (n == m) {
          EXPECT_LT((at.stiffness[n][n] - at.stiffness[n][n].transpose()).norm(),
                    1e-14 * at.stiffness[n][n].norm());
          EXPECT_LT((at.damping[n][n] - at.damping[n][n].transpose()).norm(),
                    1e-14 * at.damping[n][n].norm());
        } else {
          EXPECT_EQ(at.stiffness[n][m], at.stiffness[m][n].transpose()) << n << m;
          EXPECT_EQ(at.damping[n][m], at.damping[m][n].transpose()) << n << m;
        }
      }
    }
    for (const auto& v : joint.v) EXPECT_GT(v.norm(), 0.0);
    const Joint moving = joint;
    for (auto& v : joint.v) v.setZero();  // the dashpot's turning left out (see above)
    // Column d of block (n, m) = -(F_n(x_m + h e_d) - F_n(x_m - h e_d)) / 2h, likewise by v_m.
    const double h = 1e-6;
    double scale_k = 0, scale_c = 0, error_k = 0, error_c = 0;
    for (int m = 0; m < 3; ++m) {
      for (int d = 0; d < 3; ++d) {
        for (const bool by_velocity : {false, true}) {
          Joint plus = by_velocity ? moving : joint, minus = plus;
          (by_velocity ? plus.v : plus.x)[m][d] += h;
          (by_velocity ? minus.v : minus.x)[m][d] -= h;
          BendingJoint up, down;
          bending_joint(plus.x, plus.v, spring, damper, false, up);
          bending_joint(minus.x, minus.v, spring, damper, false, down);
          for (int n = 0; n < 3; ++n) {
            const Eigen::Vector3d column = -(up.force[n] - down.force[n]) / (2 * h);
            const Eigen::Vector3d block = (by_velocity ? at.damping : at.stiffness)[n][m].col(d);
            (by_velocity ? scale_c : scale_k) =
                std::max(by_velocity ? scale_c : scale_k, block.cwiseAbs().maxCoeff());
            (by_velocity ? error_c : error_k) =
                std::max(by_velocity ? error_c : error_k, (column - block).cwiseAbs().maxCoeff());
          }
        }
      }
    }
    EXPECT_LT(error_k, 1e-6 * scale_k) << "trial " << trial;
    EXPECT_LT(error_c, 1e-6 * scale_c) << "trial " << trial;
  }
}

}  // namespace
}  // namespace cosim::vegetation

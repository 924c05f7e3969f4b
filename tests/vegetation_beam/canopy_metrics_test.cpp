// Seed 000 eq. 24: vegetation density and its change psi; honami tip amplitude.
#include <gtest/gtest.h>

#include "cosim/vegetation_beam/canopy_metrics.hpp"

namespace cosim::vegetation {
namespace {

TEST(CanopyMetrics, NumberDensityUsesTheMpsWeight) {
  const std::vector<Eigen::Vector3d> nodes{{0, 0, 0}, {0.02, 0, 0}, {0.5, 0, 0}};
  const auto density = vegetation_number_density(nodes, 0.07);
  EXPECT_NEAR(density[0], 0.07 / 0.02 - 1.0, 1e-12);
  EXPECT_NEAR(density[1], 0.07 / 0.02 - 1.0, 1e-12);
  EXPECT_EQ(density[2], 0.0) << "no partner within the radius";
}

TEST(CanopyMetrics, BruteForceAgreesOnARandomCloud) {
  std::vector<Eigen::Vector3d> nodes;
  for (int i = 0; i < 200; ++i) nodes.emplace_back(Eigen::Vector3d::Random() * 0.1);
  const double radius = 0.03;
  const auto density = vegetation_number_density(nodes, radius);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    double expected = 0.0;
    for (std::size_t j = 0; j < nodes.size(); ++j) {
      const double r = (nodes[i] - nodes[j]).norm();
      if (j != i && r < radius) expected += radius / r - 1.0;
    }
    EXPECT_NEAR(density[i], expected, 1e-9 * (1.0 + expected));
  }
}

TEST(CanopyMetrics, PsiIsPositiveWhereThePlantsCrowd) {
  const std::vector<Eigen::Vector3d> before{{0, 0, 0}, {0.04, 0, 0}, {0.08, 0, 0}};
  const std::vector<Eigen::Vector3d> after{{0, 0, 0}, {0.02, 0, 0}, {0.08, 0, 0}};
  const auto initial = vegetation_number_density(before, 0.07);
  const auto psi = vegetation_density_change(vegetation_number_density(after, 0.07), initial);
  EXPECT_GT(psi[0], 0.0);  // its neighbour came closer
  EXPECT_LT(psi[2], 0.0);  // its neighbour moved away
}

TEST(CanopyMetrics, TipAmplitudeIsHalfTheSwing) {
  TipAmplitude amplitude(2);
  for (double t = 0; t < 1; t += 0.01) {
    amplitude.observe(0, 0.1 + 0.02 * std::sin(20 * t));
    amplitude.observe(1, 0.05);
  }
  EXPECT_NEAR(amplitude.amplitude(0), 0.02, 1e-4);
  EXPECT_EQ(amplitude.amplitude(1), 0.0);
  EXPECT_NEAR(amplitude.mean_amplitude(), 0.01, 1e-4);
}

}  // namespace
}  // namespace cosim::vegetation

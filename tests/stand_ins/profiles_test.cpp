// The prescribed flow fields against their formulas (seed 004 eq. 50-53, the log law).
#include <gtest/gtest.h>

#include <cmath>

#include "cosim/prescribed_flow/profiles.hpp"

namespace cosim::prescribed_flow {
namespace {

// Points at heights z above the bed (world frame: z up, the default bed normal).
std::vector<Eigen::Vector3d> heights(std::initializer_list<double> zs) {
  std::vector<Eigen::Vector3d> points;
  for (double z : zs) points.emplace_back(0.3, 0.0, z);
  return points;
}

TEST(PrescribedFlow, UniformFlowEverywhereBelowTheSurface) {
  ProfileSettings settings;
  settings.velocity = {0.2, 0.01, 0.0};
  settings.depth = 0.1;
  const PrescribedFlow flow(settings);
  std::vector<Eigen::Vector3d> velocity;
  std::vector<double> water;
  flow.sample(1.0, heights({0.0, 0.05, 0.1, 0.2}), velocity, water);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(velocity[i], settings.velocity);
    EXPECT_EQ(water[i], 1.0);
  }
  EXPECT_EQ(velocity[3], Eigen::Vector3d::Zero()) << "in air";
  EXPECT_EQ(water[3], 0.0);
}

TEST(PrescribedFlow, RampAndActiveInterval) {
  ProfileSettings settings;
  settings.velocity = {1.0, 0.0, 0.0};
  settings.start_time = 1.0;
  settings.end_time = 3.0;
  settings.ramp_time = 0.5;
  const PrescribedFlow flow(settings);
  std::vector<Eigen::Vector3d> velocity;
  std::vector<double> water;
  const auto point = heights({0.01});
  flow.sample(0.5, point, velocity, water);
  EXPECT_EQ(velocity[0].x(), 0.0);
  EXPECT_EQ(water[0], 0.0) << "no water before the flow starts";
  flow.sample(1.25, point, velocity, water);
  EXPECT_DOUBLE_EQ(velocity[0].x(), 0.5);
  flow.sample(2.0, point, velocity, water);
  EXPECT_DOUBLE_EQ(velocity[0].x(), 1.0);
  flow.sample(3.5, point, velocity, water);
  EXPECT_EQ(velocity[0].x(), 0.0);
}

TEST(PrescribedFlow, LogLaw) {
  ProfileSettings settings;
  settings.kind = ProfileKind::log_law;
  settings.direction = {2.0, 0.0, 0.0};
  settings.shear_velocity = 0.02;
  settings.roughness_length = 1e-4;
  const PrescribedFlow flow(settings);
  std::vector<Eigen::Vector3d> velocity;
  std::vector<double> water;
  flow.sample(0.0, heights({0.01, 5e-5}), velocity, water);
  EXPECT_NEAR(velocity[0].x(), 0.02 / 0.41 * std::log(100.0), 1e-12);
  EXPECT_EQ(velocity[0].z(), 0.0);
  EXPECT_EQ(velocity[1].x(), 0.0) << "below the roughness length";
}

TEST(PrescribedFlow, Seed004FlowingProfileIsEq50) {
  ProfileSettings settings;
  settings.kind = ProfileKind::seed004_flowing;
  settings.velocity = {1.5, 0.0, 0.0};
  settings.depth = 0.04;
  const PrescribedFlow flow(settings);
  std::vector<Eigen::Vector3d> velocity;
  std::vector<double> water;
  flow.sample(0.0, heights({0.0, 0.02, 0.04, 0.05}), velocity, water);
  EXPECT_DOUBLE_EQ(velocity[0].x(), 0.8 * 1.5);
  EXPECT_DOUBLE_EQ(velocity[1].x(), 0.9 * 1.5);
  EXPECT_DOUBLE_EQ(velocity[2].x(), 1.5);
  EXPECT_EQ(water[3], 0.0);
}

TEST(PrescribedFlow, Seed004CaptureProfileConservesDischarge) {
  ProfileSettings settings;
  settings.kind = ProfileKind::seed004_capture;
  settings.velocity = {1.0, 0.0, 0.0};
  settings.depth = 0.04;
  settings.dam_point = {1.0, 0.0, 0.0};
  settings.capture_length = 0.2;
  const PrescribedFlow flow(settings);
  for (double ponded : {0.04, 0.06, 0.1, 0.3}) {
    // The highest point upstream of the dam sets h_D.
    auto points = heights({});
    points.emplace_back(0.95, 0.0, ponded);
    const int samples = 2000;
    for (int i = 0; i <= samples; ++i) points.emplace_back(0.9, 0.0, ponded * i / samples);
    EXPECT_DOUBLE_EQ(flow.ponded_depth(points), ponded);
    std::vector<Eigen::Vector3d> velocity;
    std::vector<double> water;
    flow.sample(0.0, points, velocity, water);
    // Discharge per width: trapezoid rule over the profile, against 0.9 U h of eq. 50.
    double discharge = 0.0;
    for (int i = 1; i <= samples; ++i) {
      discharge += 0.5 * (velocity[i].x() + velocity[i + 1].x()) * ponded / samples;
    }
    const double alpha_unclipped = 1.8 * 0.04 / ponded - 1.0;
    if (alpha_unclipped > 0.1) {
      EXPECT_NEAR(discharge, 0.9 * 1.0 * 0.04, 1e-9) << "h_D = " << ponded;
    } else {
      // Eq. 52 keeps a minimum bed velocity 0.1 U; the discharge still matches by beta.
      EXPECT_NEAR(discharge, 0.9 * 1.0 * 0.04, 1e-9) << "h_D = " << ponded;
      EXPECT_DOUBLE_EQ(velocity[1].x(), 0.1);
    }
    // Outside the capture region the flowing profile applies.
    std::vector<Eigen::Vector3d> far{{0.2, 0.0, 0.0}};
    flow.sample(0.0, far, velocity, water);
    EXPECT_DOUBLE_EQ(velocity[0].x(), 0.8);
  }
}

}  // namespace
}  // namespace cosim::prescribed_flow

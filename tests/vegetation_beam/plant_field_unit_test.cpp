// Unit checks of the plant field: layout, step limits, rigid drag, contact, stability errors.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "beam_test_helpers.hpp"

namespace cosim::vegetation {
namespace {

using testing::textbook_strip;
using testing::uniform;
using testing::vacuum_parameters;

TEST(PlantFieldLayout, NodeRangesIncludeTheBase) {
  PlantSpec a = textbook_strip(4), b = textbook_strip(7);
  b.base = Eigen::Vector3d(1, 0, 0);
  const PlantField field({a, b}, vacuum_parameters());
  EXPECT_EQ(field.plant_count(), 2);
  EXPECT_EQ(field.node_count(), 5 + 8);
  EXPECT_EQ(field.node_range(0), std::make_pair(0, 5));
  EXPECT_EQ(field.node_range(1), std::make_pair(5, 13));
  EXPECT_TRUE(field.positions()[5].isApprox(b.base));
  EXPECT_NEAR(field.positions()[12].y(), 1.0, 1e-15);
  // Derived stiffnesses (PlantSpec comments): EI = E b t^3 / 12, EA = E b t.
  EXPECT_NEAR(field.specs()[0].bending_stiffness, 1e9 * 1e-8 / 12, 1e-12);
  EXPECT_NEAR(field.specs()[0].axial_stiffness, 1e9 * 1e-4, 1e-6);
}

TEST(PlantFieldLayout, RejectsInvalidSpecs) {
  PlantSpec bad = textbook_strip(4);
  bad.width = 0;
  EXPECT_THROW(PlantField({bad}, vacuum_parameters()), std::invalid_argument);
  PlantSpec no_stiffness = textbook_strip(4);
  no_stiffness.youngs_modulus = 0;
  EXPECT_THROW(PlantField({no_stiffness}, vacuum_parameters()), std::invalid_argument);
}

// Axial limit sqrt(m / (EA/l0)) scales with l0 / sqrt(EA); bending limit (l0^2/2) sqrt(m'/EI)
// with l0^2 / sqrt(EI).
TEST(StableSubstep, ScalesWithAxialStiffnessAndLinkLength) {
  PlantSpec spec = textbook_strip(10);
  spec.axial_stiffness = 1e5;
  spec.bending_stiffness = 1e-3;  // bending limit far above the axial one
  const double base = PlantField({spec}, vacuum_parameters()).stable_substep();
  PlantSpec stiffer = spec;
  stiffer.axial_stiffness *= 4;
  EXPECT_NEAR(PlantField({stiffer}, vacuum_parameters()).stable_substep() / base, 0.5, 1e-12);
  PlantSpec finer = spec;
  finer.links *= 2;
  EXPECT_NEAR(PlantField({finer}, vacuum_parameters()).stable_substep() / base, 0.5, 1e-12);
  // Value: 0.5 * l0 * sqrt(rho / E) with E = EA / A.
  EXPECT_NEAR(base, 0.5 * 0.1 * std::sqrt(1000 / (1e5 / 1e-4)), 1e-15);
}

TEST(StableSubstep, ScalesWithBendingStiffnessAndLinkLengthSquared) {
  PlantSpec spec = textbook_strip(10);
  spec.axial_stiffness = 1;  // axial limit far above the bending one
  spec.bending_stiffness = 1e4;
  const double base = PlantField({spec}, vacuum_parameters()).stable_substep();
  PlantSpec stiffer = spec;
  stiffer.bending_stiffness *= 4;
  EXPECT_NEAR(PlantField({stiffer}, vacuum_parameters()).stable_substep() / base, 0.5, 1e-12);
  PlantSpec finer = spec;
  finer.links *= 2;
  EXPECT_NEAR(PlantField({finer}, vacuum_parameters()).stable_substep() / base, 0.25, 1e-12);
  // Added mass lengthens the period: sqrt((sigma + C_M rho) / sigma) = sqrt(2).
  BeamParameters water = vacuum_parameters();
  water.fluid_density = 1000;
  EXPECT_NEAR(PlantField({spec}, water).stable_substep() / base, std::sqrt(2.0), 1e-12);
}

TEST(StableSubstep, SubstepCountAndLimitMessage) {
  BeamParameters parameters = vacuum_parameters();
  parameters.max_substeps = 50;
  const PlantField field({textbook_strip(10)}, parameters);
  const double dt = field.stable_substep();
  EXPECT_EQ(field.substeps_for(10 * dt), 10);
  EXPECT_EQ(field.substeps_for(10.5 * dt), 11);
  try {
    (void)field.substeps_for(100 * dt);
    FAIL() << "expected StabilityError";
  } catch (const StabilityError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("max_substeps"), std::string::npos) << message;
    EXPECT_NE(message.find("axial"), std::string::npos) << message;
  }
}

// A rigid plant across a uniform stream feels 0.5 rho C_D b L U_n^2 along the normal flow.
TEST(RigidPlant, KeepsNodesFixedAndFeelsAnalyticDrag) {
  PlantSpec spec = textbook_strip(16);
  BeamParameters parameters;
  parameters.rigid = true;
  parameters.drag_coefficient = 1.2;
  PlantField field({spec}, parameters);
  const auto start = field.positions();
  const double speed = 0.4, angle = std::numbers::pi / 6;
  const Eigen::Vector3d flow(speed * std::cos(angle), speed * std::sin(angle), 0);
  const WindowReport report = field.advance(1e-3, uniform(field, flow), uniform(field, flow));
  EXPECT_EQ(report.max_newton_iterations, 0);
  EXPECT_EQ(field.positions(), start);
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (const auto& f : field.window_mean_drag()) total += f;
  // Only the component normal to the plant (along x) acts.
  const double normal_speed = speed * std::cos(angle);
  const double expected = 0.5 * 1000 * 1.2 * spec.width * spec.length * normal_speed * normal_speed;
  EXPECT_NEAR(total.x(), expected, 1e-12 * expected);
  EXPECT_NEAR(total.y(), 0, 1e-15);
  EXPECT_NEAR(total.z(), 0, 1e-15);
  EXPECT_GT(field.time(), 0.99e-3);
}

// Window mean drag of a rigid plant with a ramped stream is the time average of U(t)^2.
TEST(RigidPlant, WindowMeanDragAveragesTheInterpolatedStream) {
  BeamParameters parameters;
  parameters.rigid = true;
  PlantField field({textbook_strip(8)}, parameters);
  const Eigen::Vector3d u0(0.1, 0, 0), u1(0.3, 0, 0);
  const WindowReport report = field.advance(1e-3, uniform(field, u0), uniform(field, u1));
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (const auto& f : field.window_mean_drag()) total += f;
  // First window: trapezoid over sub-steps of the ramp; the exact mean of U^2 is (0.01 + 0.03
  // + 0.09) / 3 and the trapezoid error is (0.2^2 / 6) / n^2 per unit.
  const double mean_square = (0.01 + 0.03 + 0.09) / 3;
  const double factor = 0.5 * 1000 * 1.0 * 0.01 * 1.0;
  const double n = report.substeps;
  EXPECT_NEAR(total.x(), factor * (mean_square + 0.04 / (6 * n * n)), 1e-9 * factor);
}

// Two plants pushed towards each other at the tips: contact keeps them apart, without it they
// pass through each other.
double closest_approach(bool contact, double* tip_gap) {
  PlantSpec a;
  a.length = 0.1;
  a.links = 20;
  a.width = 0.01;
  a.thickness = 0.002;
  a.youngs_modulus = 1e9;
  a.density = 1000;
  PlantSpec b = a;
  b.base = Eigen::Vector3d(2 * a.width, 0, 0);
  BeamParameters parameters;
  parameters.contact = contact;
  parameters.bending_damping_ratio = 0.5;
  parameters.gravity.setZero();
  PlantField field({a, b}, parameters);
  // Tip loads giving a static tip deflection of 3 widths each: P = 3 EI delta / L^3.
  const double load = 3 * field.specs()[0].bending_stiffness * 3 * a.width / std::pow(a.length, 3);
  std::vector<Eigen::Vector3d> loads(field.node_count(), Eigen::Vector3d::Zero());
  loads[field.node_range(0).second - 1] = Eigen::Vector3d(load, 0, 0);
  loads[field.node_range(1).second - 1] = Eigen::Vector3d(-load, 0, 0);
  field.set_external_forces(loads);
  const auto still = uniform(field, Eigen::Vector3d::Zero());
  double closest = std::numeric_limits<double>::infinity();
  for (int window = 0; window < 100; ++window) {
    field.advance(1e-3, still, still);
    for (int i = 1; i < field.node_range(0).second; ++i)
      for (int j = field.node_range(1).first + 1; j < field.node_range(1).second; ++j)
        closest = std::min(closest, (field.positions()[i] - field.positions()[j]).norm());
  }
  *tip_gap = field.positions()[field.node_range(1).second - 1].x() -
             field.positions()[field.node_range(0).second - 1].x();
  return closest;
}

TEST(Contact, KeepsPlantsPushedTogetherApart) {
  double gap_with = 0, gap_without = 0;
  const double closest_with = closest_approach(true, &gap_with);
  closest_approach(false, &gap_without);
  EXPECT_LT(gap_without, 0) << "without contact the tips cross";
  EXPECT_GT(gap_with, 0) << "with contact the tips stay on their side";
  // Contact distance is one width (two half widths); the spring allows a small overlap only.
  EXPECT_GT(closest_with, 0.5 * 0.01);
}

TEST(Stability, NanAmbientVelocityThrowsNamingTheNode) {
  PlantField field({textbook_strip(8)}, BeamParameters{});
  auto flow = uniform(field, Eigen::Vector3d(0.1, 0, 0));
  flow[3].x() = std::numeric_limits<double>::quiet_NaN();
  try {
    field.advance(1e-4, flow, flow);
    FAIL() << "expected StabilityError";
  } catch (const StabilityError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("plant 0 node 3"), std::string::npos) << message;
    EXPECT_NE(message.find("ambient"), std::string::npos) << message;
  }
}

TEST(Stability, NanVelocityInStateThrows) {
  PlantField field({textbook_strip(8)}, BeamParameters{});
  auto velocities = uniform(field, Eigen::Vector3d::Zero());
  velocities[5].y() = std::numeric_limits<double>::quiet_NaN();
  field.set_state(field.positions(), velocities);
  const auto still = uniform(field, Eigen::Vector3d::Zero());
  EXPECT_THROW(field.advance(1e-4, still, still), StabilityError);
}

TEST(Stability, AbsurdTipLoadIsReportedAsEscapeOrRunaway) {
  PlantSpec spec = textbook_strip(8);
  PlantField field({spec}, BeamParameters{});
  std::vector<Eigen::Vector3d> loads(field.node_count(), Eigen::Vector3d::Zero());
  loads.back() = Eigen::Vector3d(0, 1e9, 0);  // pulls the tip off the plant
  field.set_external_forces(loads);
  const auto still = uniform(field, Eigen::Vector3d::Zero());
  try {
    for (int window = 0; window < 1000; ++window) field.advance(1e-3, still, still);
    FAIL() << "expected StabilityError";
  } catch (const StabilityError& error) {
    EXPECT_NE(std::string(error.what()).find("plant 0 node"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace cosim::vegetation

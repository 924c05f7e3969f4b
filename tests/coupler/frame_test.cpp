// The one world frame: declarations checked at the handshake, and the 2D plane mapping.
#include <gtest/gtest.h>

#include "cosim/coupler/frame.hpp"
#include "cosim/scenario/scene.hpp"

namespace cosim::coupler {
namespace {

FrameDeclaration declared(int dimension, double span, const Eigen::Vector3d& gravity) {
  FrameDeclaration declaration;
  declaration.dimension = dimension;
  declaration.span = span;
  declaration.gravity = gravity;
  return declaration;
}

TEST(WorldFrame, AgreeingParticipantsPass) {
  scenario::WorldSettings world;
  const std::vector<std::pair<std::string, FrameDeclaration>> all{
      {"fluid_mps", declared(2, 0.1, world.gravity)},
      {"debris_dem", declared(3, 0.0, world.gravity)},
      {"vegetation_beam", declared(3, 0.0, world.gravity)}};
  EXPECT_EQ(check_declarations(all, world), "");
}

// The crash this frame exists to prevent: a DEM tilted for a flume beside a level fluid.
TEST(WorldFrame, GravityMismatchNamesBothParticipants) {
  scenario::WorldSettings world;
  const std::vector<std::pair<std::string, FrameDeclaration>> all{
      {"fluid_mps", declared(2, 0.1, world.gravity)},
      {"debris_dem", declared(3, 0.0, scenario::slope_gravity(15.0))}};
  const std::string problem = check_declarations(all, world);
  EXPECT_NE(problem.find("'debris_dem' declares gravity (2.539"), std::string::npos) << problem;
  EXPECT_NE(problem.find("'fluid_mps' declares (0, 0, -9.81)"), std::string::npos) << problem;
}

TEST(WorldFrame, EveryOtherMismatchIsNamed) {
  scenario::WorldSettings world;
  const Eigen::Vector3d g = world.gravity;
  auto problem = [&](std::vector<std::pair<std::string, FrameDeclaration>> all) {
    return check_declarations(all, world);
  };
  EXPECT_NE(
      problem({{"fluid_mps", declared(2, 0.0, g)}}).find("'fluid_mps' is 2D but declares no span"),
      std::string::npos);
  EXPECT_NE(problem({{"fluid_mps", declared(2, 0.1, g)}, {"replay", declared(2, 0.2, g)}})
                .find("'replay' stands for a span of 0.2 m but 'fluid_mps' for 0.1 m"),
            std::string::npos);
  FrameDeclaration other = declared(3, 0.0, g);
  other.frame = "y up";
  EXPECT_NE(problem({{"fluid_mps", declared(2, 0.1, g)}, {"debris_dem", other}})
                .find("'debris_dem' works in the frame \"y up\" but 'fluid_mps'"),
            std::string::npos);
  EXPECT_NE(problem({{"debris_dem", declared(3, 0.0, Eigen::Vector3d(0, 0, -9.0))}})
                .find("but the scene's world has (0, 0, -9.81)"),
            std::string::npos);
  scenario::WorldSettings y_up;
  y_up.gravity = Eigen::Vector3d(0, -9.81, 0);
  EXPECT_NE(check_declarations({{"fluid_mps", declared(2, 0.1, y_up.gravity)}}, y_up)
                .find("has a y component"),
            std::string::npos)
      << "a 2D fluid cannot carry gravity out of its plane";
}

TEST(WorldFrame, DeclarationsRoundTripAndMalformedOnesAreNamed) {
  const FrameDeclaration sent = declared(2, 0.25, Eigen::Vector3d(0.1, 0.0, -9.8));
  const FrameDeclaration got = FrameDeclaration::from_json(sent.to_json(), "fluid_mps");
  EXPECT_EQ(got.frame, sent.frame);
  EXPECT_EQ(got.dimension, 2);
  EXPECT_EQ(got.span, 0.25);
  EXPECT_EQ(got.gravity, sent.gravity);
  EXPECT_FALSE(got.limits_window);
  FrameDeclaration limiting = sent;
  limiting.limits_window = true;
  EXPECT_TRUE(FrameDeclaration::from_json(limiting.to_json(), "fluid_mps").limits_window);
  // A declaration of an older build says nothing: it may limit the window, so the coupler waits
  // for it before sizing the next one (as it did for everyone).
  EXPECT_TRUE(FrameDeclaration::from_json(
                  R"({"frame": "f", "dimension": 3, "span": 0, "gravity": [0, 0, -9.81]})", "old")
                  .limits_window);
  try {
    FrameDeclaration::from_json("", "old_solver");
    FAIL() << "an empty declaration must be refused";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("'old_solver' declared no world frame"),
              std::string::npos);
  }
  EXPECT_THROW(FrameDeclaration::from_json("{\"frame\": 3}", "x"), std::runtime_error);
}

TEST(WorldFrame, A2DSolverSeesTheXZPlaneAndForcesPerSpan) {
  const SolverFrame plane(2, 0.5);
  EXPECT_EQ(plane.to_solver(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d(1, 3, 0));
  EXPECT_EQ(plane.to_world(Eigen::Vector3d(1, 3, 0)), Eigen::Vector3d(1, 0, 3));
  EXPECT_EQ(plane.force_to_solver(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d(2, 6, 0));
  EXPECT_EQ(plane.force_to_world(Eigen::Vector3d(2, 6, 0)), Eigen::Vector3d(1, 0, 3));
  EXPECT_EQ(plane.out_of_plane(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d(0, 2, 0));
  const SolverFrame space(3, 0.0);
  EXPECT_EQ(space.to_solver(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(space.force_to_solver(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(space.out_of_plane(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d::Zero());
  EXPECT_THROW(SolverFrame(2, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace cosim::coupler

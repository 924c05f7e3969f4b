// Stiff and extreme plants through the whole chain: each case either runs to a physically
// bounded result or stops with a message naming the participant, the window and the limit.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "command.hpp"

namespace cosim::testing {
namespace {

CommandResult run_blade(const std::string& overrides) {
  const auto runs = fresh_folder("extremes");
  return run_cosim(fmt::format("run {} --runs-dir {} --quiet {}", test_scene("blade").string(),
                               runs.string(), overrides),
                   120);
}

std::string failure_of(const CommandResult& result) {
  const auto summary = read_summary(run_folder_of(result));
  return summary.contains("failure") ? summary["failure"].get<std::string>() : "";
}

double tip_of(const CommandResult& result) {
  const auto summary = read_summary(run_folder_of(result));
  return summary["participants"][1]["report"]["metrics"]["tip_streamwise_position"]["value"]
      .get<double>();
}

TEST(Extremes, AVeryStiffPlantStopsAtItsSubstepLimitWithTheReason) {
  const auto result = run_blade(
      "--set participants.vegetation_beam.plants.0.youngs_modulus=1e16 "
      "--set participants.vegetation_beam.plants.0.bending_stiffness=1e3 "
      "--set participants.vegetation_beam.max_substeps=1000");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  const std::string failure = failure_of(result);
  EXPECT_NE(failure.find("'vegetation_beam' failed in window 1"), std::string::npos) << failure;
  EXPECT_NE(failure.find("max_substeps = 1000"), std::string::npos) << failure;
  EXPECT_NE(failure.find("safety_factor"), std::string::npos) << failure;
}

TEST(Extremes, AVeryLightPlantStaysBounded) {
  // Balsa-light blades: buoyancy and added mass dominate their own mass 100 to 1.
  const auto result = run_blade("--set participants.vegetation_beam.plants.0.density=10");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const double tip = tip_of(result);
  EXPECT_GT(tip, 0.0);
  EXPECT_LT(tip, 0.045);
}

TEST(Extremes, AFastStreamBendsTheBladeFlatButBounded) {
  const auto result =
      run_blade("--set participants.prescribed_flow.velocity=[3.0,0,0] --set duration=0.05");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const double tip = tip_of(result);
  EXPECT_GT(tip, 0.5 * 0.045) << "a 3 m/s stream lays the blade over";
  EXPECT_LT(tip, 0.045);
}

TEST(Extremes, ARunawayFluidIsNamedWithStepAndParticle) {
  // An absurd time step for the MPS fluid: the solver must stop with the step, the particle
  // and the quantity instead of producing garbage.
  const auto runs = fresh_folder("extremes-fluid");
  const auto result = run_cosim(
      fmt::format(
          "run {} --runs-dir {} --quiet --set coupling.window=0.02 "
          "--set participants.fluid_mps.max_dt=0.02 --set participants.fluid_mps.courant=0.99",
          test_scene("small_dam_break").string(), runs.string()),
      120);
  if (result.exit_code == 0) GTEST_SKIP() << "the fluid survived an oversized step";
  const std::string failure = failure_of(result);
  EXPECT_NE(failure.find("'fluid_mps' failed in window"), std::string::npos) << failure;
  EXPECT_NE(failure.find("particle"), std::string::npos) << failure;
}

TEST(Extremes, AnInflowTheFishwayCannotHoldIsNamed) {
  // Twenty times the design discharge, started softly, fills the pools above the soluble moving
  // wall: the run stops and says which limit was passed instead of letting water pour back over
  // the block.
  const auto runs = fresh_folder("extremes-inflow");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet --set duration=1.5 "
                            "--set participants.fluid_mps.scene.inflow.discharge=0.28 "
                            "--set participants.fluid_mps.scene.fill_to_weir_head=false "
                            "--set participants.fluid_mps.scene.inflow.ramp_time=0.5",
                            test_scene("small_fishway").string(), runs.string()),
                200);
  EXPECT_EQ(result.exit_code, 1) << result.output;
  const std::string failure = failure_of(result);
  EXPECT_NE(failure.find("'fluid_mps' failed in window"), std::string::npos) << failure;
  EXPECT_NE(failure.find("above the block height"), std::string::npos) << failure;
}

}  // namespace
}  // namespace cosim::testing

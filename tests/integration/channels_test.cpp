// The open and periodic channels through `cosim`: validate takes periodic_channel and
// open_channel in 3D and refuses what their builders cannot make, at file, line and key; the
// free overfall runs in 2D and 3D against Rouse's end depth with its mass balance.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "command.hpp"

namespace cosim::testing {
namespace {

// `cosim validate` of free_overfall_3d with `settings` fails at `key` saying `message`.
void expect_refused(const std::string& settings, const std::string& key,
                    const std::string& message) {
  const auto result =
      run_cosim(fmt::format("validate {} {}", scenario("free_overfall_3d"), settings));
  EXPECT_NE(result.exit_code, 0) << settings;
  EXPECT_NE(result.output.find("scenario.yaml:"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("key 'participants.fluid_mps." + key + "'"), std::string::npos)
      << settings << "\n"
      << result.output;
  EXPECT_NE(result.output.find(message), std::string::npos) << settings << "\n" << result.output;
}

TEST(Channels, ValidateTakesThe3dChannelsAndRefusesWhatTheyCannotBuild) {
  const auto open = run_cosim(fmt::format("validate {}", scenario("free_overfall_3d")));
  EXPECT_EQ(open.exit_code, 0) << open.output;
  const auto periodic =
      run_cosim(fmt::format("validate {}", test_scene("periodic_channel_3d").string()));
  EXPECT_EQ(periodic.exit_code, 0) << periodic.output;
  expect_refused("--set participants.fluid_mps.fill_lattice=fcc", "fill_lattice",
                 "the 3D channels are built on the cubic lattice");
  expect_refused("--set participants.fluid_mps.scene.outlet_flat_length=0.5",
                 "scene.outlet_flat_length", "only used with dimension: 2");
  expect_refused("--set participants.fluid_mps.scene.tank_height=0.05", "scene.tank_height",
                 "must reach the top of the moving wall block");
  expect_refused(
      "--set 'participants.fluid_mps.scene.obstacles=[{min: [0.1, 0, 0], max: [0.2, 0.05, 0.02]}]'",
      "scene.obstacles", "only used with a 3D tank");
  const auto periodic_overfall =
      run_cosim(fmt::format("validate {} --set 'participants.fluid_mps.reference={{kind: "
                            "free_overfall, average_from: 0}}'",
                            test_scene("periodic_channel_3d").string()));
  EXPECT_NE(periodic_overfall.exit_code, 0);
  EXPECT_NE(periodic_overfall.output.find("key 'participants.fluid_mps.reference.kind'"),
            std::string::npos)
      << periodic_overfall.output;
  EXPECT_NE(periodic_overfall.output.find("free_overfall needs an open_channel scene"),
            std::string::npos)
      << periodic_overfall.output;
  expect_refused("--set world.slope_degrees=2", "reference.kind",
                 "free_overfall holds for a horizontal bed");
}

// The 3D periodic channel through the process: the water moves down the 1 degree slope, keeps
// every particle in the period, and the fluid's momentum budget closes.
TEST(Channels, PeriodicChannelRunsIn3d) {
  const auto runs = fresh_folder("channels-3d-periodic");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet",
                            test_scene("periodic_channel_3d").string(), runs.string()),
                120);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto summary = read_summary(run_folder_of(result));
  const auto& info = summary["participants"][0]["report"]["info"];
  ASSERT_TRUE(info.contains("momentum_budget_residual")) << info.dump(1);
  EXPECT_LT(info["momentum_budget_residual"].get<double>(), 1e-9) << info.dump(1);
  // Down the slope: at least half of g sin(1 degree) 0.1 s = 17 mm/s. (More than all of it in
  // this start: the rows on the wall lattice slide off its particles' tops, tests/fluid_mps/
  // channels_3d_test.cpp; the budget above books that push as wall collisions.)
  const double gained = info["fluid_momentum_change"][0].get<double>();
  const double fluid_mass = 1000.0 * 0.12 * 0.05 * 0.04;
  EXPECT_GT(gained / fluid_mass, 0.5 * 9.81 * std::sin(1.0 * 3.14159265358979 / 180.0) * 0.1)
      << info.dump(1);
  EXPECT_NEAR(info["fluid_momentum_change"][1].get<double>(), 0.0, 1e-12) << "no drift across";
}

// The 2D overfall at l0 = 5 mm (h_c 6.9 particles), 6 s, means over 3-6 s: the brink depth
// against Rouse's 0.715 h_c (measured 1.0 % over 4-8 s, docs/validation.md) and the mass
// balance once the flow is steady.
TEST(Channels, FreeOverfallAgainstRouseIn2d) {
  const auto runs = fresh_folder("channels-2d-overfall");
  const auto result = run_cosim(
      fmt::format(
          "run {} --runs-dir {} --quiet --set participants.fluid_mps.particle_spacing=0.005 "
          "--set coupling.timeout=30",
          scenario("free_overfall"), runs.string()),
      240);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto summary = read_summary(run_folder_of(result));
  const auto& metrics = metrics_of(summary);
  ASSERT_TRUE(metrics.contains("brink_depth_ratio")) << metrics.dump(1);
  EXPECT_LT(metrics["brink_depth_ratio"]["relative_error"].get<double>(), 0.05) << metrics.dump(1);
  EXPECT_LT(metrics["released_discharge"]["relative_error"].get<double>(), 0.01) << metrics.dump(1);
  EXPECT_LT(metrics["outflow_discharge"]["relative_error"].get<double>(), 0.03) << metrics.dump(1);
  const auto& info = summary["participants"][0]["report"]["info"];
  // Near the critical section 4 h_c upstream the depth is about h_c, the profile about uniform.
  EXPECT_NEAR(info["upstream_depth_ratio_4hc"].get<double>(), 1.0, 0.15) << info.dump(1);
  EXPECT_LT(info["energy_coefficient_4hc"].get<double>(), 1.1) << info.dump(1);
}

// The 3D overfall at a coarse l0 = 1 cm (h_c 3.4 particles, 5 across) for 0.8 s: the inflow
// delivers q across the width, the water leaves over the brink, nothing is lost.
TEST(Channels, FreeOverfallRunsIn3d) {
  const auto runs = fresh_folder("channels-3d-overfall");
  const auto result = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet --set participants.fluid_mps.particle_spacing=0.01 "
                  "--set duration=0.8 --set participants.fluid_mps.reference.average_from=0.4 "
                  "--set coupling.timeout=30",
                  scenario("free_overfall_3d"), runs.string()),
      240);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto summary = read_summary(run_folder_of(result));
  const auto& metrics = metrics_of(summary);
  ASSERT_TRUE(metrics.contains("brink_depth_ratio")) << metrics.dump(1);
  ASSERT_TRUE(metrics.contains("released_discharge")) << metrics.dump(1);
  // The wall releases whole columns (about 20 over the 0.4 s window at this l0): one column
  // more or less is 5 %.
  EXPECT_LT(metrics["released_discharge"]["relative_error"].get<double>(), 0.1) << metrics.dump(1);
  const double brink = metrics["brink_depth_ratio"]["value"].get<double>();
  EXPECT_GT(brink, 0.4) << metrics.dump(1);
  EXPECT_LT(brink, 1.0) << metrics.dump(1);
  const auto& info = summary["participants"][0]["report"]["info"];
  EXPECT_GT(info["recycled_particles"].get<double>(), 100) << info.dump(1);
}

}  // namespace
}  // namespace cosim::testing

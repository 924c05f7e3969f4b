// Pool-type fishway (seed 001) through cosim at a coarse resolution: the inflow holds its
// discharge, water passes both weirs and leaves at the outflow, and the scene reports the mass
// balance and the weir equation at the freely spilling last weir.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "command.hpp"

namespace cosim::testing {
namespace {

TEST(Fishway, SmallFishwayReportsMassBalanceAndWeirEquation) {
  const auto runs = fresh_folder("fishway");
  const auto result = run_cosim(fmt::format("run {} --runs-dir {} --quiet",
                                            test_scene("small_fishway").string(), runs.string()),
                                300);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto summary = read_summary(run_folder_of(result));
  const auto& metrics = summary["participants"][0]["report"]["metrics"];
  const double inflow = 0.01393;
  for (const char* name : {"released_discharge", "outflow_discharge", "weir_1_discharge",
                           "weir_2_discharge", "weir_1_weir_equation", "weir_2_weir_equation"}) {
    ASSERT_TRUE(metrics.contains(name)) << name << " missing: " << metrics.dump(1);
  }
  // The soluble moving wall releases whole columns: the discharge it gives is exact on average.
  EXPECT_NEAR(metrics["released_discharge"]["value"].get<double>(), inflow, 0.03 * inflow);
  // Started at the weir head, the pools pass about the inflow on to the outflow.
  EXPECT_NEAR(metrics["weir_1_discharge"]["value"].get<double>(), inflow, 0.3 * inflow);
  EXPECT_NEAR(metrics["weir_2_discharge"]["value"].get<double>(), inflow, 0.3 * inflow);
  EXPECT_NEAR(metrics["outflow_discharge"]["value"].get<double>(), inflow, 0.3 * inflow);
  // Weir equation at the measured head: both weirs spill freely. The first is fed by the calm
  // inflow pool (1.3 % at this resolution); the second's pool is stirred by the first one's
  // plunging jet, which lowers the head at its gauge (16 %).
  EXPECT_LT(metrics["weir_1_weir_equation"]["relative_error"].get<double>(), 0.1);
  EXPECT_LT(metrics["weir_2_weir_equation"]["relative_error"].get<double>(), 0.3);
  EXPECT_GT(metrics["weir_2_head"]["value"].get<double>(), 0.0);
}

}  // namespace
}  // namespace cosim::testing

// The check-dam scene through the whole chain (prescribed debris flow of seed 004 + DEM): a dam
// with beams 1.5 d_max apart traps most debris, an open dam of wide columns clearly less, and
// the DEM replays bit for bit.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "command.hpp"

namespace cosim::testing {
namespace {

std::string small_scene() {
  return (std::filesystem::path(COSIM_SCENARIOS) / "debris_capture_small").string();
}

double capture_rate_of(const CommandResult& result) {
  const auto summary = read_summary(run_folder_of(result));
  for (const auto& participant : summary["participants"]) {
    if (participant["name"] == "debris_dem") {
      return participant["report"]["metrics"]["capture_rate_P_V"]["value"].get<double>();
    }
  }
  return -1.0;
}

TEST(DebrisCapture, BeamsTrapWhatAnOpenDamLetsThrough) {
  const auto runs = fresh_folder("debris");
  const auto closed =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", small_scene(), runs.string()), 300);
  ASSERT_EQ(closed.exit_code, 0) << closed.output;
  const auto open = run_cosim(
      fmt::format(
          "run {} --runs-dir {} --quiet --set participants.debris_dem.dam.horizontal_gap=0.08 "
          "--set participants.debris_dem.dam.vertical_gap=0",
          small_scene(), runs.string()),
      300);
  ASSERT_EQ(open.exit_code, 0) << open.output;
  const double trapped = capture_rate_of(closed);
  const double passed = capture_rate_of(open);
  EXPECT_GT(trapped, 0.5) << "l_H = 2.5 d_max, l_V = 1.5 d_max";
  // Seed 004's capture-phase flow (eq. 51-53) slows the water once debris ponds at the dam, so
  // even an open dam holds back part of it (the paper notes its model over-predicts capture);
  // the wider opening must still pass clearly more.
  EXPECT_GT(trapped, passed + 0.1) << "columns 4 d_max apart, no beams";

  const auto replayed =
      run_cosim(fmt::format("replay {} --participant debris_dem --runs-dir {} --quiet",
                            run_folder_of(closed).string(), runs.string()),
                300);
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("IDENTICAL"), std::string::npos) << replayed.output;
}

}  // namespace
}  // namespace cosim::testing

// fishway_periodic_pool from the developed chain (scene.chain_state): a short run from the
// bundle's kept pool puts the chain's fluid, shifted, beside the periodic scene's own walls and
// spills over the crest; `cosim validate` refuses a bad chain_state at its file, line and key.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>

#include "command.hpp"
#include "cosim/output/point_series.hpp"

namespace cosim::testing {
namespace {

const std::filesystem::path kBundle =
    std::filesystem::path(COSIM_SCENARIOS) / "fishway_periodic_pool";
const std::filesystem::path kKept = kBundle / "chain_pool3_t6.h5";

int count_label(const output::PointFrame& frame, int kind) {
  const auto& kinds = frame.labels.at("kind");
  return static_cast<int>(std::count(kinds.begin(), kinds.end(), kind));
}

// `cosim validate` of the bundle with overrides: refused (exit 2) naming the scenario file's
// line and the key, with the reason.
void expect_refused(const std::string& overrides, const std::string& key,
                    const std::string& reason) {
  const auto result = run_cosim(fmt::format("validate {} {}", kBundle.string(), overrides));
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("scenario.yaml:"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("participants.fluid_mps.scene.chain_state." + key),
            std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find(reason), std::string::npos) << result.output;
}

TEST(ChainState, ShortRunFromTheKeptPool) {
  const auto runs = fresh_folder("chain-state");
  const auto result = run_cosim(fmt::format("run {} --runs-dir {} --quiet --set duration=0.1 --set "
                                            "output_interval=0.05 --set "
                                            "participants.fluid_mps.reference.average_from=0.05",
                                            kBundle.string(), runs.string()),
                                120);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto run = run_folder_of(result);
  const auto kept = output::read_point_frame(kKept, 0);
  const auto start = output::read_point_frame(run / "fluid_mps" / "particles.h5", 0);
  EXPECT_EQ(start.time, 0.0);
  // The kept pool's fluid, shifted from the third pool: 2 pools of 45 cells of 6.66 mm back,
  // 2 steps of 8 cells up, with its velocities.
  const Eigen::Vector3d shift(-2 * 45 * 0.00666, 0.0, 2 * 8 * 0.00666);
  const int fluid = count_label(kept, 0);
  ASSERT_GT(fluid, 1000);
  ASSERT_EQ(count_label(start, 0), fluid);
  int at = 0;
  for (std::size_t i = 0; i < kept.positions.size(); ++i) {
    if (kept.labels.at("kind")[i] != 0) continue;
    EXPECT_LT((start.positions[at] - (kept.positions[i] + shift)).norm(), 1e-12);
    EXPECT_EQ(start.vectors.at("velocity")[at], kept.vectors.at("velocity")[i]);
    EXPECT_GE(start.positions[at].x(), 0.0);
    EXPECT_LT(start.positions[at].x(), 45 * 0.00666);
    ++at;
  }
  // The walls are the periodic scene's, as many as the chain's pool had (the same geometry).
  EXPECT_EQ(count_label(start, 1), count_label(kept, 1));
  EXPECT_EQ(count_label(start, 2), count_label(kept, 2));
  // The developed pool spills from the first step: water crosses the crest.
  const auto summary = read_summary(run);
  const auto& metrics = summary["participants"][0]["report"]["metrics"];
  ASSERT_TRUE(metrics.contains("weir_1_discharge")) << metrics.dump(1);
  EXPECT_GT(metrics["weir_1_discharge"]["value"].get<double>(), 0.005);
  EXPECT_GT(metrics["weir_1_head"]["value"].get<double>(), 0.0);
}

TEST(ChainState, ValidateRefusesABadChainState) {
  const std::string state = "--set participants.fluid_mps.scene.chain_state.";
  expect_refused(state + "file=no_such.h5", "file", "no_such.h5");
  expect_refused(state + "time=7.5", "time", "no frame within");
  expect_refused(state + "pool=1", "pool", "no fluid in pool 1");
  expect_refused(state + "pool=0", "pool", "");
  expect_refused("--set participants.fluid_mps.particle_spacing=0.01", "file",
                 "not particle_spacing");
  expect_refused("--set participants.fluid_mps.scene.weir_height=0.18", "pool",
                 "are not this scene's");
  // A restart from an output frame replaces the scene: the two starts exclude each other.
  const auto both =
      run_cosim(fmt::format("validate {} --set participants.fluid_mps.restart.file={}",
                            kBundle.string(), kKept.string()));
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_NE(both.output.find("scene.chain_state': a restart replaces"), std::string::npos)
      << both.output;
  // A frame of a 3D run: particles off the x-z plane.
  const auto folder = fresh_folder("chain-state-3d");
  {
    output::PointSeriesWriter writer(folder / "particles", "fluid_mps");
    output::PointFrame frame = output::read_point_frame(kKept, 0);
    for (auto& x : frame.positions) x.y() = 0.01;
    writer.write_frame(frame);
  }
  expect_refused(state + "file=" + (folder / "particles.h5").string(), "file", "3D run");
}

TEST(ChainState, ANullChainStateStartsLevel) {
  const auto result = run_cosim(fmt::format(
      "validate {} --set participants.fluid_mps.scene.chain_state=null", kBundle.string()));
  EXPECT_EQ(result.exit_code, 0) << result.output;
}

}  // namespace
}  // namespace cosim::testing

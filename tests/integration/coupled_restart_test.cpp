// Coupled checkpoints and restarts (issue 15): a run continued from a checkpoint matches the
// uninterrupted run bit for bit (every output frame after the checkpoint, the running totals in
// summary.json), continues its time line (window numbers, times), and says where it restarted.
// Checkpoints that do not fit are refused before any process starts, naming the file.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstring>
#include <fstream>

#include "command.hpp"
#include "cosim/output/point_series.hpp"
#include "interrupted_run.hpp"

namespace cosim::testing {
namespace {

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// Every frame the restarted run wrote equals the uninterrupted run's frame at the same time, and
// the restarted run wrote every frame the uninterrupted one wrote after the checkpoint.
void expect_same_frames(const std::filesystem::path& straight,
                        const std::filesystem::path& restarted, double checkpoint_time) {
  std::vector<output::PointFrame> tail;
  for (int i = 0; i < output::count_point_frames(straight); ++i) {
    auto frame = output::read_point_frame(straight, i);
    if (frame.time > checkpoint_time + 1e-12) tail.push_back(std::move(frame));
  }
  const int count = output::count_point_frames(restarted);
  ASSERT_EQ(static_cast<std::size_t>(count), tail.size()) << restarted;
  ASSERT_GT(count, 0);
  for (int i = 0; i < count; ++i) {
    const auto frame = output::read_point_frame(restarted, i);
    const auto& expected = tail[static_cast<std::size_t>(i)];
    EXPECT_EQ(std::memcmp(&frame.time, &expected.time, sizeof(double)), 0) << frame.time;
    EXPECT_TRUE(same_bits(frame.positions, expected.positions)) << restarted << " t " << frame.time;
    for (const auto& [name, values] : expected.vectors) {
      EXPECT_TRUE(same_bits(frame.vectors.at(name), values)) << name << " t " << frame.time;
    }
    for (const auto& [name, values] : expected.scalars) {
      EXPECT_TRUE(same_bits(frame.scalars.at(name), values)) << name << " t " << frame.time;
    }
  }
}

struct Pair {
  std::filesystem::path straight, restarted;
  nlohmann::json straight_summary, restarted_summary;
};

// The scene run straight with checkpoints every `interval`, then again from the checkpoint at
// `from`.
Pair straight_and_restarted(const std::string& scene, const std::string& label,
                            const std::string& options, double interval, double from, int limit) {
  const auto runs = fresh_folder("restart-" + label);
  const std::string common = fmt::format("--runs-dir {} --quiet --set checkpoint_interval={} {}",
                                         runs.string(), interval, options);
  Pair pair;
  const auto straight = run_cosim(fmt::format("run {} {}", scene, common), limit);
  EXPECT_EQ(straight.exit_code, 0) << straight.output;
  pair.straight = run_folder_of(straight);
  if (pair.straight.empty()) return pair;
  pair.straight_summary = read_summary(pair.straight);
  const auto restarted = run_cosim(
      fmt::format("run {} {} --restart {}@{}", scene, common, pair.straight.string(), from), limit);
  EXPECT_EQ(restarted.exit_code, 0) << restarted.output;
  pair.restarted = run_folder_of(restarted);
  if (!pair.restarted.empty()) pair.restarted_summary = read_summary(pair.restarted);
  return pair;
}

// The time line continues: same window count and end time, and the summary names the restart.
void expect_continued(const Pair& pair, double from) {
  const auto& a = pair.straight_summary;
  const auto& b = pair.restarted_summary;
  ASSERT_TRUE(b.contains("restarted_from")) << b.dump(2);
  EXPECT_NEAR(b["restarted_from"]["time"].get<double>(), from, 1e-9);
  EXPECT_GE(b["restarted_from"]["window"].get<int64_t>(), 1);
  EXPECT_EQ(b["windows_completed"], a["windows_completed"]);
  EXPECT_EQ(b["simulated_time"].get<double>(), a["simulated_time"].get<double>());
  // The restarted run times its own windows (it read 0 when the clock only started at window 0).
  EXPECT_GT(b["coupling_overhead"]["windows_wall_seconds"].get<double>(), 0.0) << b.dump(2);
  EXPECT_FALSE(a["checkpoints"].empty());
  for (const auto& checkpoint : a["checkpoints"]) {
    EXPECT_TRUE(std::filesystem::exists(
        std::filesystem::path(checkpoint["folder"].get<std::string>()) / "manifest.json"));
    std::printf("checkpoint after window %lld at t = %.6g s: %llu bytes, written in %.4f s\n",
                static_cast<long long>(checkpoint["window"].get<int64_t>()),
                checkpoint["time"].get<double>(),
                static_cast<unsigned long long>(checkpoint["bytes"].get<uint64_t>()),
                checkpoint["write_seconds"].get<double>());
  }
}

TEST(CoupledRestart, FluidAndPlantsContinueBitForBit) {
  const auto pair =
      straight_and_restarted(test_scene("fluid_plants").string(), "fluid-plants",
                             "--set duration=0.12 --set output_interval=0.01", 0.05, 0.05, 300);
  ASSERT_FALSE(pair.restarted.empty());
  expect_continued(pair, 0.05);
  expect_same_frames(pair.straight / "fluid_mps" / "particles.h5",
                     pair.restarted / "fluid_mps" / "particles.h5", 0.05);
  expect_same_frames(pair.straight / "vegetation_beam" / "plants.h5",
                     pair.restarted / "vegetation_beam" / "plants.h5", 0.05);
  // The running totals carried over: the impulses of the whole run, not of its second part.
  for (const char* key : {"booked_solid_reaction_impulse", "solid_reaction_impulse"}) {
    EXPECT_EQ(info_of(pair.restarted_summary, "fluid_mps")[key],
              info_of(pair.straight_summary, "fluid_mps")[key])
        << key;
  }
  EXPECT_EQ(info_of(pair.restarted_summary, "vegetation_beam")["drag_impulse"],
            info_of(pair.straight_summary, "vegetation_beam")["drag_impulse"]);
}

TEST(CoupledRestart, DebrisContinuesBitForBit) {
  const auto pair =
      straight_and_restarted(test_scene("debris_box").string(), "debris", "", 0.1, 0.1, 300);
  ASSERT_FALSE(pair.restarted.empty());
  expect_continued(pair, 0.1);
  expect_same_frames(pair.straight / "debris_dem" / "debris.h5",
                     pair.restarted / "debris_dem" / "debris.h5", 0.1);
  EXPECT_EQ(info_of(pair.restarted_summary, "debris_dem")["fluid_impulse"],
            info_of(pair.straight_summary, "debris_dem")["fluid_impulse"]);
  EXPECT_EQ(info_of(pair.restarted_summary, "prescribed_flow")["impulse_on_solids"],
            info_of(pair.straight_summary, "prescribed_flow")["impulse_on_solids"]);
}

TEST(CoupledRestart, FluidAndDebrisContinueBitForBit) {
  const auto pair =
      straight_and_restarted(std::string(COSIM_SCENARIOS) + "/dam_break_debris", "fluid-debris",
                             "--set duration=0.1 --set output_interval=0.01", 0.04, 0.04, 400);
  ASSERT_FALSE(pair.restarted.empty());
  expect_continued(pair, 0.04);
  expect_same_frames(pair.straight / "fluid_mps" / "particles.h5",
                     pair.restarted / "fluid_mps" / "particles.h5", 0.04);
  expect_same_frames(pair.straight / "debris_dem" / "debris.h5",
                     pair.restarted / "debris_dem" / "debris.h5", 0.04);
}

// An open channel fed by the soluble moving wall (discharge control, free outflow), in 2D and 3D:
// the wall's speed, rows and level, its released and recycled totals and its pool carry over,
// so the restarted run releases the same columns at the same times.
TEST(CoupledRestart, OpenChannelInflowContinuesBitForBit) {
  for (const auto& [dimension, spacing] : {std::pair{2, 0.005}, std::pair{3, 0.01}}) {
    const auto pair = straight_and_restarted(
        std::string(COSIM_SCENARIOS) + (dimension == 2 ? "/free_overfall" : "/free_overfall_3d"),
        fmt::format("open-channel-{}d", dimension),
        fmt::format("--set duration=0.5 --set output_interval=0.05 "
                    "--set participants.fluid_mps.particle_spacing={} "
                    "--set participants.fluid_mps.reference.average_from=0.3",
                    spacing),
        0.25, 0.25, 300);
    ASSERT_FALSE(pair.restarted.empty());
    expect_continued(pair, 0.25);
    expect_same_frames(pair.straight / "fluid_mps" / "particles.h5",
                       pair.restarted / "fluid_mps" / "particles.h5", 0.25);
    for (const char* key : {"inflow_volume", "recycled_particles", "final_inflow_velocity",
                            "final_measured_level"}) {
      EXPECT_EQ(info_of(pair.restarted_summary, "fluid_mps")[key],
                info_of(pair.straight_summary, "fluid_mps")[key])
          << dimension << "D: " << key;
    }
  }
}

int count_runs(const std::filesystem::path& runs) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(runs)) count += entry.is_directory();
  return count;
}

// Each bad checkpoint stops `cosim run` before any process starts (no run folder is made) with a
// message naming the file.
TEST(CoupledRestart, BadCheckpointsAreRefusedBeforeAnyProcessStarts) {
  const auto runs = fresh_folder("restart-refused");
  const auto scene = test_scene("debris_box").string();
  const auto original = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet --set duration=0.03 --set checkpoint_interval=0.02",
                  scene, runs.string()),
      120);
  ASSERT_EQ(original.exit_code, 0) << original.output;
  const auto run = run_folder_of(original);
  const auto folder = run / "checkpoints" / "window_00000020";
  ASSERT_TRUE(std::filesystem::exists(folder / "manifest.json"));
  const int before = count_runs(runs);
  auto refused = [&](const std::string& options, const std::string& bundle = "") {
    const auto result =
        run_cosim(fmt::format("run {} --runs-dir {} --quiet --set duration=0.03 {}",
                              bundle.empty() ? scene : bundle, runs.string(), options));
    EXPECT_NE(result.exit_code, 0) << result.output;
    EXPECT_EQ(count_runs(runs), before) << "a run folder was made for " << options;
    return result.output;
  };
  const std::string restart = "--restart " + run.string();

  // A byte of the debris state changed.
  const auto file = folder / "debris_dem.ckpt";
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::string damaged = bytes;
  damaged[damaged.size() / 2] ^= 0x10;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << damaged;
  auto output = refused(restart);
  EXPECT_NE(output.find(file.string() + ": damaged checkpoint"), std::string::npos) << output;
  // Cut short.
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 3);
  output = refused(restart);
  EXPECT_NE(output.find(file.string()), std::string::npos) << output;
  // Missing.
  std::filesystem::remove(file);
  output = refused(restart);
  EXPECT_NE(output.find(file.string() + ": cannot open"), std::string::npos) << output;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;

  // Another scene, other settings of this one, another schema, a time without a checkpoint.
  output = refused(restart, test_scene("blade").string());
  EXPECT_NE(output.find("a checkpoint of scene 'debris_box_test', not of 'blade_test'"),
            std::string::npos)
      << output;
  output = refused(restart + " --set participants.prescribed_flow.velocity=[0.2,0,0]");
  EXPECT_NE(output.find("other settings of scene 'debris_box_test'"), std::string::npos) << output;
  output = refused(restart + "@0.01");
  EXPECT_NE(output.find("no checkpoint at t = 0.01 s (there are checkpoints at t = 0.02 s)"),
            std::string::npos)
      << output;
  const auto manifest_file = folder / "manifest.json";
  nlohmann::json manifest;
  std::ifstream(manifest_file) >> manifest;
  manifest["schema_version"] = 99;
  std::ofstream(manifest_file, std::ios::trunc) << manifest.dump();
  output = refused(restart);
  EXPECT_NE(output.find(manifest_file.string() + ": checkpoint schema version 99"),
            std::string::npos)
      << output;
  std::ofstream(manifest_file, std::ios::trunc) << "{\"scene\": ";
  output = refused(restart);
  EXPECT_NE(output.find(manifest_file.string() + ": damaged manifest"), std::string::npos)
      << output;
}

// SIGINT stops the run with a checkpoint after the last window granted; continuing from it (a
// continued run may change duration) gives the uninterrupted run's bits.
TEST(CoupledRestart, InterruptedRunLeavesACheckpointToContinueFrom) {
  const auto runs = fresh_folder("restart-interrupted");
  const auto scene = test_scene("debris_box").string();
  const std::string common = fmt::format("--runs-dir {} --quiet", runs.string());
  const auto stopped =
      interrupted_run(fmt::format("run {} {} --set duration=20", scene, common), 2);
  ASSERT_GE(stopped.checkpoint_time, 0.0);
  const double at = stopped.checkpoint_time;
  const std::string until = fmt::format("--set duration={}", at + 0.05);
  const auto straight = run_cosim(fmt::format("run {} {} {}", scene, common, until), 300);
  ASSERT_EQ(straight.exit_code, 0) << straight.output;
  const auto restarted = run_cosim(
      fmt::format("run {} {} {} --restart {}", scene, common, until, stopped.folder.string()), 300);
  ASSERT_EQ(restarted.exit_code, 0) << restarted.output;
  expect_same_frames(run_folder_of(straight) / "debris_dem" / "debris.h5",
                     run_folder_of(restarted) / "debris_dem" / "debris.h5", at);
}

}  // namespace
}  // namespace cosim::testing

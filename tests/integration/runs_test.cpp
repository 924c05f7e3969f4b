// End-to-end runs of the blade scene through `cosim`: outputs, lossy networks, dying and hung
// solvers, concurrent runs and replay.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <fstream>
#include <functional>
#include <future>

#include "command.hpp"
#include "cosim/output/point_series.hpp"
#include "cosim/replay/recording.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::testing {
namespace {

std::string blade() {
  return test_scene("blade").string();
}

TEST(Runs, BladeRunWritesEveryOutputOfARunFolder) {
  const auto runs = fresh_folder("outputs");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto run_dir = run_folder_of(result);
  ASSERT_FALSE(run_dir.empty()) << result.output;
  for (const char* file :
       {"scenario.yaml", "events.lcmlog", "summary.json", "logs/vegetation_beam.log",
        "logs/prescribed_flow.log", "vegetation_beam/plants.h5", "vegetation_beam/plants.xmf"}) {
    EXPECT_TRUE(std::filesystem::exists(run_dir / file)) << file;
  }
  const auto summary = read_summary(run_dir);
  EXPECT_TRUE(summary["ok"].get<bool>());
  EXPECT_EQ(summary["windows_completed"].get<int>(), 20);
  EXPECT_NEAR(summary["simulated_time"].get<double>(), 0.02, 1e-12);
  ASSERT_EQ(summary["participants"].size(), 2u);
  for (const auto& participant : summary["participants"]) {
    EXPECT_EQ(participant["windows"].get<int>(), 21) << participant.dump();  // window 0 included
    EXPECT_GE(participant["compute_seconds"].get<double>(), 0.0);
    EXPECT_GE(participant["coupling_wait_seconds"].get<double>(), 0.0);
    // CPU time of the process: positive, and a solver that mostly waits uses less than its wall.
    EXPECT_GT(participant["cpu_seconds"].get<double>(), 0.0) << participant.dump();
  }
  const auto& beam = summary["participants"][1];
  EXPECT_EQ(beam["name"], "vegetation_beam");
  EXPECT_GT(beam["steps"].get<int64_t>(), 20) << "the beam sub-cycles inside each window";
  const double tip = beam["report"]["metrics"]["tip_streamwise_position"]["value"].get<double>();
  EXPECT_GT(tip, 0.0) << "the stream bends the blade downstream";
  // Every default is written into the resolved scenario.
  const auto resolved = scenario::load_yaml_file(run_dir / "scenario.yaml");
  EXPECT_TRUE(resolved["coupling"]["resend_interval"]);
  EXPECT_TRUE(resolved["participants"]["vegetation_beam"]["added_mass_coefficient"]);
  // Frames at the output interval (0, 5, 10, 15, 20 ms).
  EXPECT_EQ(output::count_point_frames(run_dir / "vegetation_beam/plants.h5"), 5);
}

std::map<std::pair<int64_t, std::string>, std::vector<double>> beam_fields(
    const std::filesystem::path& run_dir) {
  std::map<std::pair<int64_t, std::string>, std::vector<double>> fields;
  const auto recording = replay::read_recording(run_dir / "events.lcmlog", "vegetation_beam");
  for (const auto& [window, recorded] : recording.windows) {
    for (const auto& [field, values] : recorded.fields) fields[{window, field}] = values;
  }
  return fields;
}

TEST(Runs, TenPercentMessageLossGivesTheSameResultAsNoLoss) {
  const auto runs = fresh_folder("loss");
  const auto clean = run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(clean.exit_code, 0) << clean.output;
  const auto lossy = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet --inject-loss 0.1", blade(), runs.string()));
  ASSERT_EQ(lossy.exit_code, 0) << lossy.output;
  const auto lossy_summary = read_summary(run_folder_of(lossy));
  EXPECT_GT(lossy_summary["traffic"]["dropped_injected"].get<int64_t>(), 10)
      << "loss was really injected";
  const auto expected = beam_fields(run_folder_of(clean));
  const auto actual = beam_fields(run_folder_of(lossy));
  ASSERT_EQ(expected.size(), actual.size());
  ASSERT_EQ(expected.size(), 21u * 3u);  // positions, velocities, drag for windows 0..20
  for (const auto& [key, values] : expected) {
    ASSERT_TRUE(actual.contains(key));
    EXPECT_EQ(values, actual.at(key)) << "window " << key.first << " field " << key.second;
  }
}

TEST(Runs, ASolverThatDiesIsNamedWithItsWindowWithinSeconds) {
  const auto runs = fresh_folder("exit");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet --fault vegetation_beam:exit@5", blade(),
                            runs.string()),
                60);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_LT(result.seconds, 10.0);
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_FALSE(summary.empty()) << result.output;
  const std::string failure = summary["failure"].get<std::string>();
  EXPECT_NE(failure.find("vegetation_beam"), std::string::npos) << failure;
  EXPECT_NE(failure.find("window 5"), std::string::npos) << failure;
  EXPECT_NE(result.output.find("FAILED"), std::string::npos);
}

TEST(Runs, ASolverThatHangsIsNamedWithItsWindowWithinTheTimeout) {
  const auto runs = fresh_folder("hang");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet --fault vegetation_beam:hang@7", blade(),
                            runs.string()),
                60);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_LT(result.seconds, 15.0) << "the scene's timeout is 2 s";
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_FALSE(summary.empty()) << result.output;
  const std::string failure = summary["failure"].get<std::string>();
  EXPECT_NE(failure.find("vegetation_beam"), std::string::npos) << failure;
  EXPECT_NE(failure.find("window 7"), std::string::npos) << failure;
}

TEST(Runs, ASolverErrorIsReportedWithItsMessage) {
  const auto runs = fresh_folder("throw");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet --fault prescribed_flow:throw@3", blade(),
                            runs.string()),
                60);
  EXPECT_NE(result.exit_code, 0);
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_FALSE(summary.empty()) << result.output;
  const std::string failure = summary["failure"].get<std::string>();
  EXPECT_NE(failure.find("prescribed_flow"), std::string::npos) << failure;
  EXPECT_NE(failure.find("window 3"), std::string::npos) << failure;
  EXPECT_NE(failure.find("injected fault"), std::string::npos) << failure;
}

TEST(Runs, ConcurrentRunsDoNotHearEachOther) {
  const auto runs = fresh_folder("concurrent");
  std::vector<std::future<CommandResult>> started;
  for (int i = 0; i < 3; ++i) {
    started.push_back(std::async(std::launch::async, [&] {
      return run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
    }));
  }
  std::vector<std::filesystem::path> folders;
  for (auto& run : started) {
    const auto result = run.get();
    ASSERT_EQ(result.exit_code, 0) << result.output;
    folders.push_back(run_folder_of(result));
  }
  ASSERT_NE(folders[0], folders[1]);
  for (const auto& folder : folders) {
    const auto summary = read_summary(folder);
    EXPECT_EQ(summary["traffic"]["dropped_foreign"].get<int64_t>(), 0) << folder;
  }
  EXPECT_EQ(beam_fields(folders[0]), beam_fields(folders[1]));
  EXPECT_EQ(beam_fields(folders[0]), beam_fields(folders[2]));
}

TEST(Runs, ReplayDrivesTheBeamBitForBit) {
  const auto runs = fresh_folder("replay");
  const auto recorded =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  const auto run_dir = run_folder_of(recorded);
  const auto replayed =
      run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                            run_dir.string(), runs.string()));
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("IDENTICAL"), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("63 fields"), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("1 output files"), std::string::npos) << replayed.output;
}

// Records a blade run, edits its resolved scenario with `edit`, and replays the beam against it.
CommandResult replay_edited_blade(const std::string& label,
                                  const std::function<void(YAML::Node&)>& edit) {
  const auto runs = fresh_folder(label);
  const auto recorded =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  EXPECT_EQ(recorded.exit_code, 0) << recorded.output;
  const auto run_dir = run_folder_of(recorded);
  const auto scenario_file = run_dir / "scenario.yaml";
  auto document = scenario::load_yaml_file(scenario_file);
  edit(document);
  {
    std::ofstream out(scenario_file);
    out << document;
  }
  return run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                               run_dir.string(), runs.string()));
}

TEST(Runs, ReplayDetectsADifferentSolver) {
  // Change the beam's physics in the recorded scenario: the replay must notice.
  const auto replayed = replay_edited_blade("replay-diff", [](YAML::Node& document) {
    document["participants"]["vegetation_beam"]["drag_coefficient"] = 1.0;
  });
  EXPECT_EQ(replayed.exit_code, 1) << replayed.output;
  EXPECT_NE(replayed.output.find("DIFFERENT"), std::string::npos) << replayed.output;
}

// One world: a recorded flow replayed into a scene whose world is tilted no longer shares the
// beam's gravity. The coupler refuses at the handshake, naming both participants.
TEST(Runs, ReplayIntoAnotherWorldIsRefusedAtTheHandshake) {
  const auto replayed = replay_edited_blade("replay-world", [](YAML::Node& document) {
    document["world"] = YAML::Load("{slope_degrees: 5}");
  });
  EXPECT_NE(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("participants disagree on the world"), std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("'vegetation_beam' declares gravity (0.854998"), std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("'prescribed_flow' declares (0, 0, -9.81)"), std::string::npos)
      << replayed.output;
}

}  // namespace
}  // namespace cosim::testing

namespace cosim::testing {
namespace {

TEST(Runs, SweepTabulatesEveryMetricPerValue) {
  const auto runs = fresh_folder("sweep");
  const auto result = run_cosim(fmt::format(
      "sweep {} --vary participants.vegetation_beam.plants.0.links --values 4 8 --runs-dir {} "
      "--quiet",
      blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::filesystem::path table;
  for (const auto& entry : std::filesystem::directory_iterator(runs)) {
    if (entry.path().extension() == ".csv") table = entry.path();
  }
  ASSERT_FALSE(table.empty()) << result.output;
  std::ifstream in(table);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("participants.vegetation_beam.plants.0.links,ok,wall_seconds,metric", 0),
            0u);
  int rows = 0, tip_rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    tip_rows += line.find("vegetation_beam.tip_streamwise_position") != std::string::npos;
  }
  EXPECT_EQ(tip_rows, 2) << "one row per value";
  EXPECT_EQ(rows, 4) << "two metrics of the beam for each of two values";
}

}  // namespace
}  // namespace cosim::testing

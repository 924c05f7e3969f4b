// `cosim validate` and `cosim run` refuse a bad scenario before anything starts, naming the
// file, the line and the key.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <sys/stat.h>

#include <fstream>

#include "command.hpp"

namespace cosim::testing {
namespace {

std::filesystem::path write_scene(const std::string& name, const std::string& yaml) {
  const auto folder = fresh_folder("scene-" + name);
  std::ofstream(folder / "scenario.yaml") << yaml;
  return folder;
}

const char* kGood = R"(name: check
duration: 0.01
coupling:
  window: 1.0e-3
participants:
  prescribed_flow:
    velocity: [0.1, 0, 0]
  vegetation_beam:
    plants:
      - base: [0, 0, 0]
        length: 0.045
        width: 0.002
        thickness: 1.2e-4
        youngs_modulus: 3.0e9
        density: 1390
)";

void expect_refused(const std::string& yaml, const std::string& expected_location,
                    const std::string& expected_key) {
  const auto folder = write_scene("bad", yaml);
  const auto result = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet", folder.string(), (folder / "runs").string()));
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find(expected_location), std::string::npos) << result.output;
  EXPECT_NE(result.output.find(expected_key), std::string::npos) << result.output;
  EXPECT_FALSE(std::filesystem::exists(folder / "runs")) << "nothing may start";
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  text.replace(text.find(from), from.size(), to);
  return text;
}

TEST(ScenarioErrors, TheGoodSceneValidates) {
  const auto folder = write_scene("good", kGood);
  const auto result = run_cosim("validate " + folder.string());
  EXPECT_EQ(result.exit_code, 0) << result.output;
}

TEST(ScenarioErrors, UnknownKeyIsNamedWithItsLine) {
  expect_refused(
      replace(kGood, "        density: 1390", "        density: 1390\n        colour: green"),
      "scenario.yaml:16", "colour");
}

TEST(ScenarioErrors, WrongTypeIsNamedWithItsLine) {
  expect_refused(replace(kGood, "length: 0.045", "length: long"), "scenario.yaml:11",
                 "participants.vegetation_beam.plants");
}

TEST(ScenarioErrors, OutOfRangeIsNamedWithItsLine) {
  expect_refused(replace(kGood, "window: 1.0e-3", "window: -1"), "scenario.yaml:4",
                 "coupling.window");
}

TEST(ScenarioErrors, MissingFileIsNamed) {
  expect_refused(replace(kGood, "  prescribed_flow:\n    velocity: [0.1, 0, 0]\n",
                         "  replay:\n    participant: prescribed_flow\n    log: nowhere.lcmlog\n"),
                 "scenario.yaml:8", "nowhere.lcmlog");
}

TEST(ScenarioErrors, UnknownParticipantIsNamed) {
  expect_refused(replace(kGood, "  prescribed_flow:", "  magic_flow:"), "scenario.yaml:6",
                 "magic_flow");
}

TEST(ScenarioErrors, MissingRequiredKeyIsNamed) {
  expect_refused(replace(kGood, "        width: 0.002\n", ""), "scenario.yaml:10", "width");
}

// Fishway geometry that cannot be built is refused at its key: an orifice reaching the crest, a
// pool whose soluble moving wall is lower than the water it starts with.
TEST(ScenarioErrors, FishwayGeometryIsCheckedAtItsKey) {
  const std::string fishway = R"(name: fishway
duration: 0.01
coupling:
  window: 1.0e-3
participants:
  fluid_mps:
    particle_spacing: 0.01
    scene:
      kind: pool_fishway
      weir_height: 0.2
      orifice_height: 0.3
      block_height: 0.35
      inflow:
        discharge: 0.01
)";
  expect_refused(fishway, "scenario.yaml:11", "orifice_height");
  expect_refused(replace(replace(fishway, "orifice_height: 0.3", "fill_to_weir_head: true"),
                         "block_height: 0.35", "block_height: 0.21"),
                 "scenario.yaml:12", "block_height");
}

// A key written twice is refused with both lines, at any depth, list items included (yaml-cpp
// keeps both, and which one a parser reads depended on how it looked).
TEST(ScenarioErrors, DuplicateKeyIsNamedWithBothLines) {
  expect_refused(replace(kGood, "duration: 0.01\n", "duration: 0.01\nduration: 0.02\n"),
                 "scenario.yaml:3: key 'duration': appears twice (first at line 2)", "duration");
  expect_refused(
      replace(kGood, "        density: 1390\n", "        density: 1390\n        width: 0.003\n"),
      "scenario.yaml:16: key 'participants.vegetation_beam.plants[0].width': appears "
      "twice (first at line 12)",
      "width");
}

// Not a regular file: refused at once, naming the file (a FIFO used to block `validate`).
TEST(ScenarioErrors, AScenarioThatIsNotARegularFileIsRefusedAtOnce) {
  const auto fifo_bundle = fresh_folder("scene-fifo");
  ASSERT_EQ(mkfifo((fifo_bundle / "scenario.yaml").c_str(), 0600), 0);
  const auto fifo = run_cosim("validate " + fifo_bundle.string(), 20);
  EXPECT_EQ(fifo.exit_code, 2) << fifo.output;
  EXPECT_LT(fifo.seconds, 10.0);
  EXPECT_NE(fifo.output.find((fifo_bundle / "scenario.yaml").string() + ": is a FIFO"),
            std::string::npos)
      << fifo.output;

  const auto dir_bundle = fresh_folder("scene-dir");
  std::filesystem::create_directories(dir_bundle / "scenario.yaml");
  const auto dir = run_cosim(fmt::format("run {} --runs-dir {} --quiet", dir_bundle.string(),
                                         (dir_bundle / "runs").string()));
  EXPECT_EQ(dir.exit_code, 2) << dir.output;
  EXPECT_NE(dir.output.find((dir_bundle / "scenario.yaml").string() + ": is a directory"),
            std::string::npos)
      << dir.output;
  EXPECT_FALSE(std::filesystem::exists(dir_bundle / "runs"));
}

TEST(ScenarioErrors, AHugeScenarioIsRefusedWithItsSizeAndTheLimit) {
  const auto folder = write_scene("huge", kGood);
  std::filesystem::resize_file(folder / "scenario.yaml", 100'000'000);  // sparse, no disk used
  const auto result = run_cosim("validate " + folder.string(), 20);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_LT(result.seconds, 5.0) << "refused before reading";
  EXPECT_NE(result.output.find("is 95.4 MiB (100000000 bytes); scenario files are limited to "
                               "16.0 MiB"),
            std::string::npos)
      << result.output;
}

// Command-line errors of `cosim run` are refused before a run folder exists.
void expect_option_refused(const std::string& options, const std::string& expected) {
  const auto folder = write_scene("options", kGood);
  const auto runs = folder / "runs";
  const auto result = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet {}", folder.string(), runs.string(), options));
  EXPECT_NE(result.exit_code, 0) << options << "\n" << result.output;
  EXPECT_NE(result.output.find(expected), std::string::npos) << options << "\n" << result.output;
  EXPECT_FALSE(std::filesystem::exists(runs)) << options << ": no run folder may be made";
}

TEST(ScenarioErrors, AFaultIsCheckedStrictlyBeforeAnythingStarts) {
  expect_option_refused("--fault vegetation_beam:explode@5",
                        "--fault 'vegetation_beam:explode@5': unknown kind 'explode' (known "
                        "kinds: exit, hang, throw)");
  expect_option_refused("--fault nobody:exit@5",
                        "--fault 'nobody:exit@5': this scene runs no participant 'nobody' (it "
                        "runs prescribed_flow, vegetation_beam)");
  expect_option_refused("--fault vegetation_beam:exit@abc",
                        "--fault 'vegetation_beam:exit@abc': the window 'abc' is not a whole "
                        "number (this scene has windows 1 to 10)");
  expect_option_refused("--fault vegetation_beam:exit@-1",
                        "window -1 is outside this scene's windows 1 to 10");
  expect_option_refused("--fault vegetation_beam:exit@11",
                        "window 11 is outside this scene's windows 1 to 10");
  expect_option_refused("--fault vegetation_beam:exit@0",
                        "window 0 is outside this scene's windows 1 to 10");
  expect_option_refused("--fault vegetation_beam", "expected PARTICIPANT:KIND@WINDOW");
  expect_option_refused("--fault vegetation_beam:exit@3 --fault vegetation_beam:hang@4",
                        "'vegetation_beam' is given twice");
}

TEST(ScenarioErrors, InjectedLossMustBeAFiniteFraction) {
  for (const char* value : {"nan", "inf", "-0.1", "0.6", "abc"}) {
    expect_option_refused(fmt::format("--inject-loss {}", value),
                          fmt::format("'{}' is not a finite number from 0 to 0.5", value));
  }
}

}  // namespace
}  // namespace cosim::testing

// `cosim validate` and `cosim run` refuse a bad scenario before anything starts, naming the
// file, the line and the key.
#include <gtest/gtest.h>

#include <fmt/format.h>

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

}  // namespace
}  // namespace cosim::testing

// Scenario files: checked values, errors naming file, line and key, and the resolved scenario.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "cosim/scenario/scene.hpp"

namespace cosim::scenario {
namespace {

std::filesystem::path write(const std::string& name, const std::string& yaml) {
  const auto folder = std::filesystem::temp_directory_path() / ("cosim-scene-" + name);
  std::filesystem::create_directories(folder);
  std::ofstream(folder / "scenario.yaml") << yaml;
  return folder;
}

// A parser for a made-up solid: reads two keys, one with a default.
std::map<std::string, ParticipantParser> parsers() {
  auto solid = [](Section& section, const Scene&) {
    section.number("stiffness", Range::positive());
    section.integer("links", 10, Range::between(1, 100));
  };
  auto flow = [](Section& section, const Scene&) { section.vector3("velocity"); };
  return {{"vegetation_beam", solid},
          {"prescribed_flow", flow},
          {"debris_dem", solid},
          {"replay", [](Section& section, const Scene&) { section.text("participant"); }}};
}

const char* kScene = R"(name: test
duration: 1.0
coupling:
  window: 0.1
participants:
  vegetation_beam:
    stiffness: 2.0
  prescribed_flow:
    velocity: [1, 0, 0]
)";

std::string error_of(const std::string& yaml) {
  try {
    load_scene(write("error", yaml), parsers());
  } catch (const ScenarioError& error) {
    return error.what();
  }
  return "";
}

TEST(Scene, LoadsAndOrdersTheFlowFirst) {
  const Scene scene = load_scene(write("good", kScene), parsers());
  EXPECT_EQ(scene.name, "test");
  EXPECT_EQ(scene.total_windows(), 10);
  ASSERT_EQ(scene.participants.size(), 2u);
  EXPECT_EQ(scene.participants[0].name, "prescribed_flow");
  EXPECT_EQ(scene.flow()->name, "prescribed_flow");
  EXPECT_EQ(scene.solids().size(), 1u);
  EXPECT_EQ(scene.coupling.scheme, "serial-explicit");
}

TEST(Scene, ResolvedScenarioHoldsEveryDefault) {
  const Scene scene = load_scene(write("resolved", kScene), parsers());
  EXPECT_EQ(scene.resolved["participants"]["vegetation_beam"]["links"].as<int>(), 10);
  EXPECT_EQ(scene.resolved["coupling"]["scheme"].as<std::string>(), "serial-explicit");
  EXPECT_DOUBLE_EQ(scene.resolved["coupling"]["timeout"].as<double>(), 5.0);
  EXPECT_DOUBLE_EQ(scene.resolved["output_interval"].as<double>(), 0.01);
}

TEST(Scene, ErrorsNameFileLineAndKey) {
  std::string scene = kScene;
  const std::string unknown = error_of(scene + "    colour: red\n");
  EXPECT_NE(unknown.find("scenario.yaml:10"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("participants.prescribed_flow.colour"), std::string::npos) << unknown;

  std::string wrong = kScene;
  wrong.replace(wrong.find("stiffness: 2.0"), 14, "stiffness: soft");
  const std::string type = error_of(wrong);
  EXPECT_NE(type.find("scenario.yaml:7"), std::string::npos) << type;
  EXPECT_NE(type.find("participants.vegetation_beam.stiffness"), std::string::npos) << type;

  std::string range = kScene;
  range.replace(range.find("stiffness: 2.0"), 14, "stiffness: -2.");
  const std::string out_of_range = error_of(range);
  EXPECT_NE(out_of_range.find("scenario.yaml:7"), std::string::npos) << out_of_range;

  std::string scheme = kScene;
  scheme.replace(scheme.find("window: 0.1"), 11, "window: 0.1\n  scheme: implicit");
  const std::string choice = error_of(scheme);
  EXPECT_NE(choice.find("coupling.scheme"), std::string::npos) << choice;
  EXPECT_NE(choice.find("serial-explicit"), std::string::npos) << "lists the choices: " << choice;
}

// A value from the command line (--set, --perturb, --vary) has no line in the file: the error
// says where it came from instead of pointing at line 0.
TEST(Scene, AnOverriddenKeysErrorSaysItCameFromTheCommandLine) {
  const auto folder = write("override", kScene);
  YAML::Node document = load_yaml_file(folder / "scenario.yaml");
  apply_override(document, "participants.vegetation_beam.stiffness", "-3");
  std::string error;
  try {
    load_scene(document, folder / "scenario.yaml", parsers());
  } catch (const ScenarioError& caught) {
    error = caught.what();
  }
  EXPECT_NE(error.find("scenario.yaml: key 'participants.vegetation_beam.stiffness' (set on the "
                       "command line)"),
            std::string::npos)
      << error;
  EXPECT_EQ(error.find(":0:"), std::string::npos) << error;
  // An override that adds a key the file does not have says the same, whether its value is out
  // of range or the key is unknown to the participant.
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"participants.vegetation_beam.links", "1000"},
           {"participants.vegetation_beam.colour", "red"}}) {
    YAML::Node added = load_yaml_file(folder / "scenario.yaml");
    apply_override(added, key, value);
    try {
      load_scene(added, folder / "scenario.yaml", parsers());
      ADD_FAILURE() << key << " = " << value << " is refused";
    } catch (const ScenarioError& caught) {
      const std::string what = caught.what();
      EXPECT_NE(what.find("key '" + key + "' (set on the command line)"), std::string::npos)
          << what;
      EXPECT_EQ(what.find(":0:"), std::string::npos) << what;
    }
  }
}

TEST(Scene, YamlSyntaxErrorsNameTheLine) {
  const std::string error = error_of("name: x\nduration: [1\n");
  EXPECT_NE(error.find("scenario.yaml"), std::string::npos) << error;
}

TEST(Scene, TwoFlowsAreRefused) {
  std::string scene = kScene;
  const std::string solid = "  vegetation_beam:\n    stiffness: 2.0\n";
  scene.replace(scene.find(solid), solid.size(), "  replay:\n    participant: fluid_mps\n");
  const std::string error = error_of(scene);
  EXPECT_NE(error.find("at most one flow"), std::string::npos) << error;
}

TEST(Scene, ReplaysActAsTheirParticipant) {
  std::string scene = kScene;
  scene += "  replay_dem:\n    participant: debris_dem\n";
  const Scene loaded = load_scene(write("replay", scene), parsers());
  const auto& entry = loaded.participant("debris_dem");
  EXPECT_EQ(entry.name, "replay_dem");
  EXPECT_EQ(entry.executable, "replay");
  EXPECT_EQ(entry.role, Role::solid);
}

TEST(Scene, WorldGravityIsDeclaredOnceForTheScene) {
  const auto plain = load_scene(write("world-plain", kScene), parsers());
  EXPECT_EQ(plain.world.gravity, Eigen::Vector3d(0.0, 0.0, -9.81)) << "z up by default";
  std::string sloped = kScene;
  sloped.insert(sloped.find("coupling:"), "world:\n  slope_degrees: 15\n");
  const auto flume = load_scene(write("world-slope", sloped), parsers());
  const double theta = 15.0 * std::numbers::pi / 180.0;
  EXPECT_NEAR(flume.world.gravity.x(), 9.81 * std::sin(theta), 1e-12);
  EXPECT_EQ(flume.world.gravity.y(), 0.0);
  EXPECT_NEAR(flume.world.gravity.z(), -9.81 * std::cos(theta), 1e-12);
  std::string sine = kScene;
  sine.insert(sine.find("coupling:"), "world:\n  bed_slope: 0.01\n");
  const auto channel = load_scene(write("world-sine", sine), parsers());
  EXPECT_NEAR(channel.world.gravity.x(), 9.81 * 0.01, 1e-12);
  EXPECT_NEAR(channel.world.gravity.z(), -9.81 * std::sqrt(1.0 - 1e-4), 1e-12);
  std::string both = kScene;
  both.insert(both.find("coupling:"), "world:\n  gravity: [0, 0, -9.81]\n  slope_degrees: 3\n");
  EXPECT_NE(error_of(both).find("key 'world.slope_degrees': give either"), std::string::npos)
      << error_of(both);
}

// A count beyond int used to wrap round to -2147483648 windows, and the run did nothing.
TEST(Scene, AnAbsurdNumberOfWindowsIsRefusedNamingDuration) {
  std::string long_run = kScene;
  long_run.replace(long_run.find("duration: 1.0"), 13, "duration: 1.0e9");
  const std::string problem = error_of(long_run);
  EXPECT_NE(problem.find("key 'duration'"), std::string::npos) << problem;
  EXPECT_NE(problem.find("1e+10 windows"), std::string::npos) << problem;
  std::string tiny = kScene;
  tiny.replace(tiny.find("window: 0.1"), 11, "window: 1.0e-300");
  EXPECT_NE(error_of(tiny).find("key 'duration'"), std::string::npos) << error_of(tiny);
  EXPECT_EQ(load_scene(write("windows-ok", kScene), parsers()).total_windows(), 10);
}

// The name becomes the run folder: it may not lead outside --runs-dir or be empty.
TEST(Scene, ANameThatCannotBeAFolderIsRefused) {
  for (const char* name : {"../../escaped", "/tmp/abs", "\"\"", ".hidden", "a b"}) {
    std::string yaml = kScene;
    yaml.replace(yaml.find("name: test"), 10, std::string("name: ") + name);
    const std::string problem = error_of(yaml);
    EXPECT_NE(problem.find("key 'name'"), std::string::npos) << name << ": " << problem;
  }
}

// coupling.interpolation was parsed and never used: naming it is an error, not a silent no-op.
TEST(Scene, InterpolationIsNotASetting) {
  std::string yaml = kScene;
  yaml.replace(yaml.find("  window: 0.1"), 13, "  window: 0.1\n  interpolation: linear");
  const std::string problem = error_of(yaml);
  EXPECT_NE(problem.find("key 'coupling.interpolation'"), std::string::npos) << problem;
  EXPECT_NE(problem.find("scenario.yaml:5:"), std::string::npos) << problem;
}

}  // namespace
}  // namespace cosim::scenario

// `cosim validate` refuses what a process would refuse at its start, at the key with file and
// line: the parser and the library check visit one declaration per parameter (issue 14). Each
// scene here passed validate before and then failed in the process without file or line (or
// died of std::bad_alloc).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <fstream>

#include "command.hpp"
#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/fluid_mps/parameters.hpp"
#include "cosim/vegetation_beam/plant_field.hpp"

namespace cosim::testing {
namespace {

const char* kHeader = R"(name: check
duration: 0.01
coupling:
  window: 1.0e-3
participants:
)";

const char* kPlants = R"(  prescribed_flow:
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

const char* kFluid = R"(  fluid_mps:
    particle_spacing: 0.01
    scene:
      kind: dam_break
      column_width: 0.146
      column_height: 0.292
      tank_length: 0.584
      tank_height: 0.3
)";

const char* kDebris = R"(  debris_dem:
    box: {min: [-0.05, -0.05, 0], max: [0.05, 0.05, 0.16]}
    elements:
      - {kind: sphere, center: [0, 0, 0.05], diameter: 0.015, density: 1120}
)";

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

CommandResult validate(const std::string& participants) {
  const auto folder = fresh_folder("validate-agrees");
  std::ofstream(folder / "scenario.yaml") << kHeader << participants;
  return run_cosim("validate " + folder.string());
}

void expect_refused(const std::string& participants, const std::string& where,
                    const std::string& problem) {
  const auto result = validate(participants);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find(where), std::string::npos) << result.output << "\nwant: " << where;
  EXPECT_NE(result.output.find(problem), std::string::npos) << result.output;
}

// The problem text of the library's refusal, or "" when it accepts.
template <class Check>
std::string library_problem(Check check) {
  try {
    check();
  } catch (const scenario::ParameterError& error) {
    return error.key() + ": " + error.problem();
  }
  return "";
}

TEST(ValidateAgrees, TheUnchangedScenesValidate) {
  for (const char* scene : {kPlants, kFluid, kDebris}) {
    const auto result = validate(scene);
    EXPECT_EQ(result.exit_code, 0) << result.output;
  }
}

// The parser allowed [0.5, 1], the library (0, 1): 1.0 validated and stopped the fluid process.
TEST(ValidateAgrees, SurfaceThresholdOfOneIsRefusedByValidate) {
  expect_refused(replace(kFluid, "    particle_spacing: 0.01\n",
                         "    particle_spacing: 0.01\n    surface_threshold: 1.0\n"),
                 "scenario.yaml:8: key 'participants.fluid_mps.surface_threshold'",
                 "value 1 is out of range [0.5, 1)");
  mps::MpsParameters p;
  p.surface_threshold = 1.0;
  EXPECT_EQ(library_problem([&] { mps::validate_parameters(p); }),
            "surface_threshold: value 1 is out of range [0.5, 1)");
}

// background_repulsion means something only with the hydrostatic background and a gradient form
// that has a neighbourhood minimum: elsewhere it would be silently ignored, so it is refused at
// its line.
TEST(ValidateAgrees, BackgroundRepulsionWithoutItsBackgroundOrMinimumIsRefused) {
  const std::string with = "    particle_spacing: 0.01\n    background_repulsion: full\n";
  expect_refused(replace(kFluid, "    particle_spacing: 0.01\n", with),
                 "scenario.yaml:8: key 'participants.fluid_mps.background_repulsion'",
                 "only used with pressure_background: hydrostatic");
  const std::string background = "    pressure_background: hydrostatic\n";
  expect_refused(replace(kFluid, "    particle_spacing: 0.01\n",
                         with + background + "    pressure_gradient: symmetric\n"),
                 "scenario.yaml:8: key 'participants.fluid_mps.background_repulsion'",
                 "not the symmetric forms");
  const std::string accepted = replace(kFluid, "    particle_spacing: 0.01\n", with + background);
  EXPECT_EQ(validate(accepted).exit_code, 0) << validate(accepted).output;
}

// The background's fade, its depth and what it replaces: only with the background, and a depth
// of zero (a fade over nothing) is out of range, at its line.
TEST(ValidateAgrees, BackgroundKeysWithoutTheBackgroundOrOfNoDepthAreRefused) {
  const std::string blend = "    particle_spacing: 0.01\n    background_fade: blend\n";
  expect_refused(replace(kFluid, "    particle_spacing: 0.01\n", blend),
                 "scenario.yaml:8: key 'participants.fluid_mps.background_fade'",
                 "only used with pressure_background: hydrostatic");
  const std::string background = "    pressure_background: hydrostatic\n";
  expect_refused(replace(kFluid, "    particle_spacing: 0.01\n",
                         blend + background + "    background_fade_depth_over_re: 0\n"),
                 "scenario.yaml:10: key 'participants.fluid_mps.background_fade_depth_over_re'",
                 "value 0 is out of range (0, 4]");
  expect_refused(replace(kFluid, "    particle_spacing: 0.01\n",
                         "    particle_spacing: 0.01\n    background_replaces: layer_mean\n"),
                 "scenario.yaml:8: key 'participants.fluid_mps.background_replaces'",
                 "only used with pressure_background: hydrostatic");
  const std::string accepted = replace(kFluid, "    particle_spacing: 0.01\n",
                                       blend + background +
                                           "    background_fade_depth_over_re: 2\n"
                                           "    background_replaces: layer_mean\n");
  EXPECT_EQ(validate(accepted).exit_code, 0) << validate(accepted).output;
}

// A restitution no damping ratio reaches: the DEM's bisection gave up at the process start.
TEST(ValidateAgrees, UnreachableRestitutionIsRefusedByValidate) {
  expect_refused(std::string(kDebris) + "    materials:\n      debris: {restitution: 1.0e-20}\n",
                 "scenario.yaml:11: key 'participants.debris_dem.materials.debris.restitution'",
                 "below what any damping ratio gives");
  dem::Material m;
  m.restitution = 1e-20;
  EXPECT_NE(library_problem([&] { dem::validate_material(m); }).find("restitution: value 1e-20"),
            std::string::npos);
  m.restitution = 0.5;
  EXPECT_EQ(library_problem([&] { dem::validate_material(m); }), "");
}

// E b t^3 / 12 of a 1e-110 m thin plant underflows to 0: PlantField refused it at the start.
TEST(ValidateAgrees, UnderflowingPlantStiffnessIsRefusedByValidate) {
  expect_refused(replace(kPlants, "thickness: 1.2e-4", "thickness: 1.0e-110"),
                 "scenario.yaml:14: key 'participants.vegetation_beam.plants[0].youngs_modulus'",
                 "not a positive finite number");
  vegetation::PlantSpec spec = vegetation::scenario_plant_defaults();
  spec.length = 0.045;
  spec.width = 0.002;
  spec.thickness = 1e-110;
  spec.youngs_modulus = 3e9;
  spec.density = 1390;
  EXPECT_NE(library_problem([&] { vegetation::check_plant(spec, 0); }).find("youngs_modulus"),
            std::string::npos);
}

// 1e6 plants of 1e4 links validated and then died of std::bad_alloc after 4.8 GB.
TEST(ValidateAgrees, PlantsBeyondTheMachinesMemoryAreRefusedByValidate) {
  const auto result = validate(replace(
      replace(kPlants, "        density: 1390\n",
              "        density: 1390\n        count: 1000000\n        spacing: [0.01, 0, 0]\n"),
      "        length: 0.045\n", "        length: 0.045\n        links: 10000\n"));
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("key 'participants.vegetation_beam.plants[0].count'"),
            std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("vegetation_beam needs about 16 TB of memory (1000000 plants "
                               "x 10000 links"),
            std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("of physical memory"), std::string::npos) << result.output;
  EXPECT_LT(result.seconds, 10.0) << "refused before anything is built";
}

TEST(ValidateAgrees, FluidAndDebrisBeyondTheMachinesMemoryAreRefusedByValidate) {
  expect_refused(replace(kFluid, "particle_spacing: 0.01", "particle_spacing: 1.0e-6"),
                 "key 'participants.fluid_mps.particle_spacing'", "fluid_mps needs about");
  std::string classes;
  for (int i = 0; i < 20; ++i) classes += "        - {diameter: 0.001, count: 10000000}\n";
  expect_refused(std::string(kDebris) +
                     "    packing:\n      box_min: [-0.04, -0.04, 0]\n      box_max: [0.04, "
                     "0.04, 0.1]\n      spheres:\n" +
                     classes,
                 "key 'participants.debris_dem.packing.spheres[", "debris_dem needs about");
}

// The fluid's nested keys are read from their declarations (fluid_mps/process/scene_keys.hpp,
// boundary_keys.hpp and reference_keys.hpp): a key of another scene kind, inflow control,
// dimension or reference kind is refused as "only used with ..." (it used to be an "unknown
// key", or not refused at all), and every refusal names the file, the line and the dotted key.
TEST(ValidateAgrees, FluidNestedKeysAreRefusedAtTheirKeyWithFileAndLine) {
  const std::string key = "scenario.yaml:14: key 'participants.fluid_mps.";
  expect_refused(std::string(kFluid) + "      column_x: 0.1\n", key + "scene.column_x'",
                 "only used with dimension: 3");
  expect_refused(std::string(kFluid) + "      depth: 0.1\n", key + "scene.depth'",
                 "only used with kind: still_water_tank, periodic_channel");
  expect_refused(std::string(kFluid) + "      tank_width: 0.1\n", key + "scene.tank_width'",
                 "only used with dimension: 3");
  expect_refused(
      std::string(kFluid) + "      obstacles:\n        - {min: [0, 0, 0], max: [1, 1, 1]}\n",
      key + "scene.obstacles'", "only used with dimension: 3");
  expect_refused(std::string(kFluid) + "      inflow: {control: velocity}\n", key + "scene.inflow'",
                 "only used with kind: open_channel, pool_fishway");
  // A 3D tank needs its width across.
  expect_refused(replace(kFluid, "    particle_spacing: 0.01\n",
                         "    particle_spacing: 0.01\n    dimension: 3\n"),
                 "key 'participants.fluid_mps.scene.tank_width'", "required key is missing");

  const std::string channel =
      std::string(kFluid).substr(0, std::string(kFluid).find("      kind:")) +
      R"(      kind: open_channel
      length: 1.0
      initial_depth: 0.1
      block_height: 0.4
      inflow:
        control: velocity
        inflow_rows: 4
)";
  EXPECT_EQ(validate(channel).exit_code, 0) << validate(channel).output;
  expect_refused(channel + "        discharge: 0.01\n",
                 "scenario.yaml:16: key 'participants.fluid_mps.scene.inflow.discharge'",
                 "only used with control: discharge");
  expect_refused(replace(channel, "inflow_rows: 4", "inflow_rows: 0"),
                 "scenario.yaml:15: key 'participants.fluid_mps.scene.inflow.inflow_rows'",
                 "value 0 is out of range [1, 1000]");
  expect_refused(replace(channel, "control: velocity", "control: level"),
                 "key 'participants.fluid_mps.scene.inflow.target_level'",
                 "required key is missing");

  const std::string observe =
      std::string(kFluid) + "    observe:\n      points: [0.1, 0, 0.05]\n      colour: red\n";
  expect_refused(observe, "scenario.yaml:16: key 'participants.fluid_mps.observe.colour'",
                 "unknown key");
  expect_refused(replace(observe, "0.1, 0, 0.05", "0.1, 0"),
                 "scenario.yaml:15: key 'participants.fluid_mps.observe.points'",
                 "expected a flat list of x, y, z triples");
  expect_refused(
      std::string(kFluid) + "    partitions:\n      - {from: [0.3, 0, 0], to: [0.3, 0.2]}\n",
      "scenario.yaml:15: key 'participants.fluid_mps.partitions[0].from'",
      "expected 2 numbers, got 3");

  const std::string hydrostatic =
      std::string(kFluid) +
      "    reference:\n      kind: hydrostatic\n      still_depth: 0.2\n      probe_x: 0.1\n"
      "      probe_depths: [0.05]\n";
  EXPECT_EQ(validate(hydrostatic).exit_code, 0) << validate(hydrostatic).output;
  expect_refused(hydrostatic + "      canopy_height: 0.04\n",
                 "scenario.yaml:19: key 'participants.fluid_mps.reference.canopy_height'",
                 "only used with kind: canopy_balance");
  expect_refused(hydrostatic + "      pressure_probes:\n        - {column: P1, at: [0, 0, 0]}\n",
                 "scenario.yaml:19: key 'participants.fluid_mps.reference.pressure_probes'",
                 "only used with kind: probe_series");
  expect_refused(replace(hydrostatic, "probe_depths: [0.05]", "probe_depths: [0.05, -0.1]"),
                 "scenario.yaml:18: key 'participants.fluid_mps.reference.probe_depths'",
                 "value -0.1 is out of range (0, inf]");
}

}  // namespace
}  // namespace cosim::testing

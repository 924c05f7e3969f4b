// `cosim keys` prints the key reference generated from the parameter declarations, and
// docs/scenario-keys.md is exactly its output, so the documentation cannot drift.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "command.hpp"
#include "keys_command.hpp"

namespace cosim::tool {
namespace {

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(Keys, TheCommittedReferenceIsTheGeneratorsOutput) {
  const auto docs = std::filesystem::path(COSIM_SOURCE_DIR) / "docs" / "scenario-keys.md";
  ASSERT_TRUE(std::filesystem::exists(docs));
  EXPECT_EQ(read_file(docs), keys_markdown())
      << "regenerate it: build/bin/cosim keys > docs/scenario-keys.md";
  const auto printed = testing::run_cosim("keys");
  EXPECT_EQ(printed.exit_code, 0) << printed.output;
  EXPECT_EQ(printed.output, keys_markdown());
}

TEST(Keys, OneParticipantsKeysWithTypeDefaultRangeAndUnit) {
  const auto printed = testing::run_cosim("keys fluid_mps");
  EXPECT_EQ(printed.exit_code, 0) << printed.output;
  EXPECT_NE(printed.output.find("| `surface_threshold` | number | 0.97 | [0.5, 1) |"),
            std::string::npos)
      << printed.output;
  EXPECT_NE(printed.output.find("| `particle_spacing` | number | required | (0, inf] | m |"),
            std::string::npos);
  EXPECT_EQ(printed.output.find("## vegetation_beam"), std::string::npos);
  for (const auto& name : keyed_participants()) {
    EXPECT_NE(keys_markdown().find("## " + name), std::string::npos) << name;
  }
  const std::string debris = keys_markdown("debris_dem");
  EXPECT_NE(debris.find("| `materials.logs.density` | number | 800 |"), std::string::npos);
  EXPECT_NE(debris.find("| `substep` | number | 1e-05 |"), std::string::npos);
  const auto unknown = testing::run_cosim("keys magic_flow");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("magic_flow"), std::string::npos) << unknown.output;
}

// The fluid's nested keys are listed from their declarations too: a group per scene kind and
// reference kind, with range, unit, doc and the values they are only used with.
TEST(Keys, TheFluidsNestedGroupsWithRangeAndDoc) {
  const auto printed = testing::run_cosim("keys fluid_mps");
  EXPECT_EQ(printed.exit_code, 0) << printed.output;
  const std::string& out = printed.output;
  for (const std::string expected : {
           "The scene: its kind and walls (`fluid_mps/process/scene_keys.hpp`)",
           "| `scene.kind` | choice | required | dam_break, still_water_tank, periodic_channel, "
           "open_channel, pool_fishway, periodic_pool, flume |",
           "| `scene.tank_width` | number | required | (0, inf] | m | the tank across (y), between "
           "two side walls (only with dimension: 3 (a flume's is width)) |",
           "The scene with kind: flume",
           "| `scene.outlet_x` | number | none | (0, inf] | m | fluid past this x leaves the flow; "
           "between the water's x_max and the end |",
           "The scene with kind: dam_break",
           "| `scene.column_x` | number | 0 | [0, inf] | m | the column's upstream face (only with "
           "dimension: 3) |",
           "The scene with kind: pool_fishway",
           "| `scene.inflow.inflow_rows` | integer | 5 | [1, 1000] |  | rows a column releases",
           "| `scene.inflow.discharge` | number | required | (0, inf] | m^2/s | q per unit width "
           "(only with control: discharge) |",
           "| `scene.obstacles[].min` | [x, y, z] | required |",
           "| `scene.solids[].stl` | file | required | relative to the bundle |",
           "| `restart.frame` | integer | -1 |",
           "| `partitions[].from` | [a, b] | required |",
           "| `observe.points` | list of numbers | required |",
           "| `observe.radius` | number | 2 particle_spacing | (0, inf] | m |",
           "The reference with kind: probe_series",
           "| `reference.arrival_fraction` | number | 0.1 | (0, 1] |",
           "| `reference.depth_gauges[].at` | [a, b] | required |",
           "| `sample_radius` | number | 2 particle_spacing | (0, inf] | m |",
           "- scene.orifice_height: must be below the crest",
       }) {
    EXPECT_NE(out.find(expected), std::string::npos) << "missing: " << expected;
  }
}

}  // namespace
}  // namespace cosim::tool

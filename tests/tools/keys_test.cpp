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

}  // namespace
}  // namespace cosim::tool

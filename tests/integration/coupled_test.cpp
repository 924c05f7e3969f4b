// The MPS fluid and the plants together: the fluid takes exactly the opposite of the impulse
// the plants took from it (the last window's drag is handed over after the run ends).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <Eigen/Core>

#include "command.hpp"

namespace cosim::testing {
namespace {

Eigen::Vector3d vector_of(const nlohmann::json& values) {
  return {values[0].get<double>(), values[1].get<double>(), values[2].get<double>()};
}

TEST(FluidAndPlants, MomentumGivenToTheFluidBalancesThePlantsDrag) {
  const auto runs = fresh_folder("fluid-plants");
  const auto result = run_cosim(fmt::format("run {} --runs-dir {} --quiet",
                                            test_scene("fluid_plants").string(), runs.string()),
                                300);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_EQ(summary["participants"].size(), 2u);
  const auto& fluid = summary["participants"][0]["report"]["info"];
  const auto& plants = summary["participants"][1]["report"]["info"];
  const Eigen::Vector3d drag = vector_of(plants["drag_impulse"]);
  const Eigen::Vector3d last = vector_of(plants["last_window_drag_impulse"]);
  const Eigen::Vector3d reaction = vector_of(fluid["solid_reaction_impulse"]);
  ASSERT_GT(drag.norm(), 1e-6) << "the surge must load the plants";
  const double spanwise_spacing = 0.02;
  const Eigen::Vector3d expected = -(drag - last) / spanwise_spacing;
  EXPECT_LT((reaction - expected).norm(), 1e-9 * expected.norm())
      << "fluid " << reaction.transpose() << " vs plants " << expected.transpose();
  // Nearly all of it reaches fluid particles (plant nodes in air have nothing to push).
  const Eigen::Vector3d undelivered = vector_of(fluid["undelivered_solid_force_impulse"]);
  EXPECT_LT(undelivered.norm(), 0.5 * reaction.norm());
}

}  // namespace
}  // namespace cosim::testing

// The MPS fluid and the plants together: the fluid takes exactly the opposite of the impulse
// the plants took from it (the last window's drag is handed over after the run ends).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <Eigen/Core>

#include "command.hpp"

namespace cosim::testing {
namespace {

// The world impulses of a fluid + plants run: what the link handed the fluid, what its particles
// received, and what could not be delivered, against the impulse the plants took.
void expect_momentum_balance(const std::string& extra_options, const std::string& label) {
  const auto runs = fresh_folder("fluid-plants-" + label);
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet {}", test_scene("fluid_plants").string(),
                            runs.string(), extra_options),
                300);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_EQ(summary["participants"].size(), 2u);
  const auto& fluid = summary["participants"][0]["report"]["info"];
  const auto& plants = summary["participants"][1]["report"]["info"];
  const Eigen::Vector3d drag = vector_of(plants["drag_impulse"]);
  const Eigen::Vector3d last = vector_of(plants["last_window_drag_impulse"]);
  const auto [booked, received, undelivered, out_of_plane] = flow_impulses(fluid);
  ASSERT_GT(drag.norm(), 1e-6) << "the surge must load the plants";
  // World frame, forces in newtons: the span scaling is undone before the report.
  const Eigen::Vector3d expected = -(drag - last);
  EXPECT_LT((booked - expected).norm(), 1e-9 * expected.norm())
      << "booked " << booked.transpose() << " vs plants " << expected.transpose();
  // Every booked newton-second reached fluid particles or is reported as undeliverable.
  EXPECT_LT((received + undelivered - booked).norm(), 1e-9 * booked.norm())
      << "received " << received.transpose() << " undelivered " << undelivered.transpose()
      << " booked " << booked.transpose();
  // Nearly all of it reaches fluid particles (plant nodes in air have nothing to push).
  EXPECT_LT(undelivered.norm(), 0.5 * received.norm());
  // The fluid's own momentum budget (gravity, walls, pressure, collisions, plants) closes.
  EXPECT_LT(fluid["momentum_budget_residual"].get<double>(), 1e-12);
  // The plants stand in the x-z plane of the 2D fluid: nothing is out of it.
  EXPECT_EQ(out_of_plane.norm(), 0.0);
}

TEST(FluidAndPlants, MomentumGivenToTheFluidBalancesThePlantsDrag) {
  expect_momentum_balance("", "adaptive");
}

// Fixed windows of three fluid steps each (max_dt 0.4 ms in 1 ms windows): the plants' reaction
// acts in all three steps, so the fluid still receives the whole booked impulse.
TEST(FluidAndPlants, SplitWindowsDeliverTheWholeReaction) {
  expect_momentum_balance(
      "--set coupling.adaptive_window=false --set participants.fluid_mps.max_dt=4.0e-4", "split");
}

}  // namespace
}  // namespace cosim::testing

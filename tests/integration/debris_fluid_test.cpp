// The MPS fluid and the DEM together, both ways: a dam break carrying boulders and logs (momentum
// exchanged to round-off, the fluid's own budget closed), a sphere settling in still liquid, and a
// floating log.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <Eigen/Core>

#include "command.hpp"

namespace cosim::testing {
namespace {

Eigen::Vector3d vector_of(const nlohmann::json& values) {
  return {values[0].get<double>(), values[1].get<double>(), values[2].get<double>()};
}

nlohmann::json run_scene(const std::string& scene, const std::string& label,
                         const std::string& options, int limit) {
  const auto runs = fresh_folder("debris-fluid-" + label);
  const auto result = run_cosim(fmt::format("run {}/{} --runs-dir {} --quiet {}", COSIM_SCENARIOS,
                                            scene, runs.string(), options),
                                limit);
  EXPECT_EQ(result.exit_code, 0) << result.output;
  if (result.exit_code != 0) return {};
  return read_summary(run_folder_of(result));
}

const nlohmann::json& participant(const nlohmann::json& summary, const std::string& name) {
  for (const auto& entry : summary["participants"]) {
    if (entry["name"] == name) return entry;
  }
  throw std::runtime_error("no participant " + name);
}

TEST(FluidAndDebris, ADamBreakCarriesTheDebrisAndMomentumBalances) {
  const auto summary = run_scene("dam_break_debris", "dam-break", "--set duration=0.4", 300);
  ASSERT_FALSE(summary.is_null());
  const auto& fluid = participant(summary, "fluid_mps")["report"]["info"];
  const auto& debris = participant(summary, "debris_dem")["report"]["info"];
  const Eigen::Vector3d took = vector_of(debris["interaction_impulse"]);
  const Eigen::Vector3d last = vector_of(debris["last_window_interaction_impulse"]);
  const Eigen::Vector3d booked = vector_of(fluid["booked_solid_reaction_impulse"]);
  const Eigen::Vector3d received = vector_of(fluid["solid_reaction_impulse"]);
  const Eigen::Vector3d undelivered = vector_of(fluid["undelivered_solid_force_impulse"]);
  const Eigen::Vector3d out_of_plane = vector_of(fluid["out_of_plane_solid_force_impulse"]);
  ASSERT_GT(took.norm(), 1e-5) << "the surge must drag the debris";
  // Everything the debris took from the fluid (drag, added mass) the fluid was handed back, one
  // window later, in the world frame: in its x-z plane, or booked as out of it (the debris'
  // cross-flume drag has no place in a 2D fluid).
  EXPECT_LT((booked + out_of_plane + (took - last)).norm(), 1e-9 * took.norm())
      << booked.transpose() << " vs " << (took - last).transpose();
  EXPECT_GT(out_of_plane.norm(), 0.0) << "the log lying at an angle is pushed across the flume";
  // Every booked newton-second reached fluid particles or is reported as undeliverable.
  EXPECT_LT((received + undelivered - booked).norm(), 1e-9 * booked.norm());
  // The fluid's own momentum budget, the debris' reaction included, closes.
  EXPECT_LT(fluid["momentum_budget_residual"].get<double>(), 1e-12);
  // The debris moved downstream with the surge.
  EXPECT_GT(vector_of(debris["mean_velocity"]).x(), 0.01);
}

TEST(FluidAndDebris, ASphereSettlesAtTheCorrelationsTerminalVelocity) {
  const auto summary = run_scene("sphere_settling", "settling", "", 300);
  ASSERT_FALSE(summary.is_null());
  const auto& metric = participant(summary, "debris_dem")["report"]["metrics"]["terminal_velocity"];
  EXPECT_LT(metric["relative_error"].get<double>(), 0.05) << metric.dump();
}

TEST(FluidAndDebris, ALogFloatsAtItsArchimedesDraft) {
  const auto summary =
      run_scene("floating_log", "floating",
                "--set participants.fluid_mps.particle_spacing=0.003 --set duration=2.0 "
                "--set participants.debris_dem.reference.average_from=1.0",
                300);
  ASSERT_FALSE(summary.is_null());
  const auto& metrics = participant(summary, "debris_dem")["report"]["metrics"];
  EXPECT_LT(metrics["draft"]["relative_error"].get<double>(), 0.10) << metrics.dump();
}

}  // namespace
}  // namespace cosim::testing

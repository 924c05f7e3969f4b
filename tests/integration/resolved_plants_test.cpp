// coupling.resolved_plants through `cosim run`: the light blade stood in the 2D MPS fluid as a
// moving line of wall particles, its fluid load the pressure difference across it. The blade is
// some 200 times lighter than the water it moves, and serial-explicit coupling diverges once the
// surge reaches it: the run stops naming the participant, the window and the quantity. One
// coupling iteration per window of serial-implicit is the explicit scheme bit for bit (the
// blade's wall particles survive the rollback). A scene that cannot resolve its plants is refused
// before anything starts, with its file, line and key.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>

#include "command.hpp"
#include "cosim/output/point_series.hpp"

namespace cosim::testing {
namespace {

CommandResult run_resolved(const std::string& label, const std::string& options, int limit = 120) {
  return run_cosim(
      fmt::format("run {} --runs-dir {} --quiet {}", test_scene("light_blade_resolved").string(),
                  fresh_folder("resolved-" + label).string(), options),
      limit);
}

TEST(ResolvedPlants, SerialExplicitCouplingDivergesAndStopsNamingTheLimit) {
  const auto result = run_resolved("explicit", "");
  EXPECT_NE(result.exit_code, 0) << result.output;
  // The fluid's runaway check (or an escaped particle) stops it in a window after the surge
  // reached the blade (t = 0.1 s), the message naming participant, window and quantity.
  EXPECT_NE(result.output.find("'fluid_mps' failed in window"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("fluid_mps unstable at step"), std::string::npos) << result.output;
  const auto folder = run_folder_of(result);
  ASSERT_FALSE(folder.empty()) << result.output;
  const auto summary = read_summary(folder);
  EXPECT_FALSE(summary["ok"].get<bool>());
  EXPECT_GT(summary["windows_completed"].get<int>(), 50);  // the water reaches it in window 50
  EXPECT_LT(summary["windows_completed"].get<int>(), 150);
}

TEST(ResolvedPlants, OneIterationPerWindowIsTheSerialExplicitSchemeBitForBit) {
  const auto explicit_run = run_resolved("short-explicit", "--set duration=0.12");
  const auto one = run_resolved("short-one",
                                "--set duration=0.12 "
                                "--set coupling.scheme=serial-implicit "
                                "--set coupling.implicit.max_iterations=1");
  ASSERT_EQ(explicit_run.exit_code, 0) << explicit_run.output;
  ASSERT_EQ(one.exit_code, 0) << one.output;
  const auto a = run_folder_of(explicit_run), b = run_folder_of(one);
  for (const char* file : {"vegetation_beam/plants.h5", "fluid_mps/particles.h5"}) {
    const int count = output::count_point_frames(a / file);
    ASSERT_GT(count, 1) << file;
    ASSERT_EQ(output::count_point_frames(b / file), count) << file;
    for (int i = 0; i < count; ++i) {
      const auto x = output::read_point_frame(a / file, i).positions;
      const auto y = output::read_point_frame(b / file, i).positions;
      ASSERT_EQ(x.size(), y.size()) << file << " frame " << i;
      EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])), 0)
          << file << " frame " << i;
    }
  }
  // The blade was loaded by the water before 0.12 s.
  const auto load = info_of(read_summary(a), "vegetation_beam")["fluid_load_impulse"];
  EXPECT_GT(std::abs(load[0].get<double>()), 0.0);
}

// A blade resolved in water that is already there: the fluid makes room for it (0.9 l0) and the
// channel stays calm enough to run. Before, the two lattice columns beside the blade were crowded to several
// times n0 and thrown out at 6 m/s; a particle escaped at t = 0.076 s.
TEST(ResolvedPlants, ABladeStandingInWaterFromTheStartLeavesItCalm) {
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", test_scene("blade_in_channel").string(),
                            fresh_folder("resolved-in-water").string()),
                120);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto folder = run_folder_of(result);
  std::ifstream log_file(folder / "logs" / "fluid_mps.log");
  const std::string log((std::istreambuf_iterator<char>(log_file)), {});
  EXPECT_NE(log.find("fluid particles within 0.9 l0 of it taken out"), std::string::npos) << log;
  const auto file = folder / "fluid_mps" / "particles.h5";
  const int count = output::count_point_frames(file);
  ASSERT_GE(count, 3);
  const auto last = output::read_point_frame(file, count - 1);
  const auto& kinds = last.labels.at("kind");
  const auto& velocity = last.vectors.at("velocity");
  double fastest = 0.0;
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (kinds[i] == 0) fastest = std::max(fastest, velocity[i].norm());
  }
  // Driven from rest by g S = 0.196 m/s^2 for 0.15 s (3 cm/s without the blade), the water
  // settles into the room made for the blade at up to 0.44 m/s (0.36 m/s at 0.15 s); without
  // the room the crowded particles flew off at 4-6.5 m/s.
  EXPECT_LT(fastest, 1.0) << "at t = " << last.time;
}

TEST(ResolvedPlants, ASceneThatCannotResolveItsPlantIsRefused) {
  // scenarios/single_blade: one plant in a prescribed flow, no fluid to stand it in.
  const auto single_blade = test_scene("../../../scenarios/single_blade");
  const auto no_fluid = run_cosim(
      fmt::format("validate {} --set coupling.resolved_plants=true", single_blade.string()), 30);
  EXPECT_NE(no_fluid.exit_code, 0) << no_fluid.output;
  EXPECT_NE(no_fluid.output.find("resolved_plants"), std::string::npos) << no_fluid.output;
  EXPECT_NE(no_fluid.output.find("needs fluid_mps and vegetation_beam"), std::string::npos)
      << no_fluid.output;
  // The parallel-implicit scheme does not iterate the fluid's load.
  const auto parallel = run_cosim(fmt::format("validate {} --set coupling.scheme=parallel-implicit",
                                              test_scene("light_blade_resolved").string()),
                                  30);
  EXPECT_NE(parallel.exit_code, 0) << parallel.output;
  EXPECT_NE(parallel.output.find("scenario.yaml:"), std::string::npos) << parallel.output;
  EXPECT_NE(parallel.output.find("use serial-implicit"), std::string::npos) << parallel.output;
}

}  // namespace
}  // namespace cosim::testing

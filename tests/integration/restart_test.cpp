// A fluid run restarted from one of its own output frames continues exactly like the straight
// run: the frame holds everything the solver needs, bit for bit.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstring>

#include "command.hpp"
#include "cosim/output/point_series.hpp"

namespace cosim::testing {
namespace {

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(FluidRestart, RestartFromAnOutputFrameMatchesTheStraightRun) {
  const auto runs = fresh_folder("restart");
  const auto scene = test_scene("small_dam_break").string();
  const auto straight =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", scene, runs.string()));
  ASSERT_EQ(straight.exit_code, 0) << straight.output;
  const auto straight_output = run_folder_of(straight) / "fluid_mps" / "particles.h5";
  ASSERT_EQ(output::count_point_frames(straight_output), 6);  // t = 0, 0.01, ..., 0.05
  const auto frame = output::read_point_frame(straight_output, 2);
  EXPECT_NEAR(frame.time, 0.02, 1e-9);

  const auto restarted = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet --set participants.fluid_mps.restart.file={} "
                  "--set participants.fluid_mps.restart.frame=2 --set duration=0.03",
                  scene, runs.string(), straight_output.string()));
  ASSERT_EQ(restarted.exit_code, 0) << restarted.output;
  const auto restarted_output = run_folder_of(restarted) / "fluid_mps" / "particles.h5";
  const auto expected = output::read_point_frame(straight_output, -1);
  const auto actual = output::read_point_frame(restarted_output, -1);
  EXPECT_EQ(expected.time, actual.time);
  EXPECT_TRUE(same_bits(expected.positions, actual.positions));
  EXPECT_TRUE(same_bits(expected.vectors.at("velocity"), actual.vectors.at("velocity")));
  EXPECT_TRUE(same_bits(expected.scalars.at("pressure"), actual.scalars.at("pressure")));
  // The water has moved since the restart frame: the comparison is not trivial.
  EXPECT_FALSE(same_bits(frame.positions, actual.positions));
}

}  // namespace
}  // namespace cosim::testing

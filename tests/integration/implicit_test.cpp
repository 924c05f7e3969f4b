// Implicit coupling (issue 15) through `cosim run`: a window is iterated until the fields the
// plants hand the fluid converge, every participant rolled back to the window start between
// iterations, with the iteration counts in summary.json; one iteration per window is the
// serial-explicit scheme bit for bit (iteration 0 reads what the explicit scheme reads).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "command.hpp"
#include "cosim/output/point_series.hpp"
#include "interrupted_run.hpp"

namespace cosim::testing {
namespace {

struct Run {
  std::filesystem::path folder;
  nlohmann::json summary;
};

Run run_light_blade(const std::string& label, const std::string& options, int limit = 120) {
  const auto runs = fresh_folder("implicit-" + label);
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet {}", test_scene("light_blade").string(),
                            runs.string(), options),
                limit);
  Run run;
  run.folder = run_folder_of(result);
  EXPECT_FALSE(run.folder.empty()) << result.output;
  if (!run.folder.empty()) run.summary = read_summary(run.folder);
  return run;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void expect_same_frames(const std::filesystem::path& a, const std::filesystem::path& b) {
  const int count = output::count_point_frames(a);
  ASSERT_GT(count, 1) << a;
  ASSERT_EQ(output::count_point_frames(b), count) << b;
  for (int i = 0; i < count; ++i) {
    const auto one = output::read_point_frame(a, i);
    const auto two = output::read_point_frame(b, i);
    EXPECT_EQ(std::memcmp(&one.time, &two.time, sizeof(double)), 0) << one.time;
    EXPECT_TRUE(same_bits(one.positions, two.positions)) << b << " frame " << i;
    for (const auto& [name, values] : one.vectors) {
      EXPECT_TRUE(same_bits(two.vectors.at(name), values)) << name << " frame " << i;
    }
  }
}

TEST(ImplicitCoupling, OneIterationPerWindowIsTheSerialExplicitSchemeBitForBit) {
  const auto explicit_run = run_light_blade("explicit", "--set duration=0.06");
  const auto one = run_light_blade("one-iteration",
                                   "--set duration=0.06 --set coupling.scheme=serial-implicit "
                                   "--set coupling.implicit.max_iterations=1");
  ASSERT_FALSE(explicit_run.folder.empty());
  ASSERT_FALSE(one.folder.empty());
  ASSERT_TRUE(explicit_run.summary["ok"].get<bool>()) << explicit_run.summary.dump(2);
  ASSERT_TRUE(one.summary["ok"].get<bool>()) << one.summary.dump(2);
  // Every window stopped at its one iteration.
  const auto& implicit = one.summary["implicit"];
  EXPECT_EQ(implicit["iterations_max"], 1);
  EXPECT_EQ(implicit["iterations_total"], one.summary["windows_completed"]);
  expect_same_frames(explicit_run.folder / "fluid_mps" / "particles.h5",
                     one.folder / "fluid_mps" / "particles.h5");
  expect_same_frames(explicit_run.folder / "vegetation_beam" / "plants.h5",
                     one.folder / "vegetation_beam" / "plants.h5");
  EXPECT_EQ(info_of(one.summary, "vegetation_beam")["drag_impulse"],
            info_of(explicit_run.summary, "vegetation_beam")["drag_impulse"]);
}

// The light blade in the surge, iterated: windows take several iterations while the surge loads
// the blade, every window converges (no window at the limit in the first 0.15 s), and summary.json
// counts them.
TEST(ImplicitCoupling, WindowsConvergeWithTheirIterationsInTheSummary) {
  const auto run = run_light_blade("iqn-ils",
                                   "--set duration=0.15 --set coupling.scheme=serial-implicit "
                                   "--set coupling.implicit.acceleration=iqn-ils");
  ASSERT_FALSE(run.folder.empty());
  ASSERT_TRUE(run.summary["ok"].get<bool>()) << run.summary.dump(2);
  const auto& implicit = run.summary["implicit"];
  ASSERT_TRUE(implicit.is_object()) << run.summary.dump(2);
  EXPECT_EQ(implicit["acceleration"], "iqn-ils");
  const auto per_window = implicit["iterations_per_window"].get<std::vector<int>>();
  ASSERT_EQ(static_cast<int64_t>(per_window.size()), run.summary["windows_completed"]);
  int total = 0;
  int most = 0;
  for (const int n : per_window) {
    EXPECT_GE(n, 1);
    total += n;
    most = std::max(most, n);
  }
  EXPECT_EQ(implicit["iterations_total"], total);
  EXPECT_EQ(implicit["iterations_max"], most);
  EXPECT_EQ(implicit["windows_at_max_iterations"], 0);
  // While the surge loads the blade the drag changes within a window: a second iteration is
  // needed there, and the accelerator converges well before the limit.
  EXPECT_GT(most, 1);
  EXPECT_LT(most, implicit["max_iterations"].get<int>());
  std::printf("iterations per window: mean %.2f, max %d, total %d over %zu windows\n",
              implicit["iterations_mean"].get<double>(), most, total, per_window.size());
  // implicit_convergence.csv: a row per iteration, each field's residual over its tolerance;
  // the last row of every window converged (all <= 1), the rows before it not.
  std::ifstream csv(run.folder / "implicit_convergence.csv");
  ASSERT_TRUE(csv) << run.folder;
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("window,time,iteration,", 0), 0u) << line;
  EXPECT_NE(line.find("\"velocities of vegetation_beam\""), std::string::npos) << line;
  const auto fields = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) - 2;
  std::vector<std::vector<double>> rows;
  while (std::getline(csv, line)) {
    std::vector<double> row;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    ASSERT_EQ(row.size(), fields + 3) << line;
    rows.push_back(row);
  }
  ASSERT_EQ(static_cast<int>(rows.size()), total);
  std::size_t k = 0;
  for (std::size_t w = 0; w < per_window.size(); ++w) {
    for (int i = 0; i < per_window[w]; ++i, ++k) {
      EXPECT_EQ(rows[k][0], static_cast<double>(w + 1)) << "row " << k;
      EXPECT_EQ(rows[k][2], static_cast<double>(i)) << "row " << k;
      const double worst = *std::max_element(rows[k].begin() + 3, rows[k].end());
      if (i + 1 == per_window[w]) {
        EXPECT_LE(worst, 1.0) << "window " << w + 1 << " accepted unconverged";
      } else {
        EXPECT_GT(worst, 1.0) << "window " << w + 1 << " iterated past convergence";
      }
    }
  }
  // The replay plays every recorded coupling iteration: the plants driven by the replayed fluid
  // iterate the same windows the same number of times, to the same bits.
  const auto replay =
      run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                            run.folder.string(), fresh_folder("implicit-replay").string()),
                120);
  EXPECT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find(fmt::format("{} windows ({} coupling iterations)",
                                           per_window.size() + 1, total + 1)),
            std::string::npos)
      << replay.output;
  EXPECT_NE(replay.output.find("IDENTICAL"), std::string::npos) << replay.output;
}

// The limit: with at_max_iterations: stop, a window that cannot converge in its iterations
// stops the run naming the window.
// The plant's tip series (tips.csv, tip_heights.csv) get one row per tip time: the rows are
// written once the coupler accepted the window, not by every iteration (before, a window that
// took three iterations wrote its row three times, and a mean over the file weighted each time
// by its iteration count).
TEST(ImplicitCoupling, TipSeriesHoldOneRowPerTime) {
  const auto run = run_light_blade("tips",
                                   "--set duration=0.05 --set coupling.scheme=serial-implicit "
                                   "--set coupling.implicit.acceleration=iqn-ils "
                                   "--set participants.vegetation_beam.canopy.streamwise=[1,0,0] "
                                   "--set participants.vegetation_beam.canopy.tip_interval=0.01");
  ASSERT_FALSE(run.folder.empty());
  ASSERT_TRUE(run.summary["ok"].get<bool>()) << run.summary.dump(2);
  EXPECT_GT(run.summary["implicit"]["iterations_max"].get<int>(), 1);  // windows did iterate
  for (const char* file : {"tips.csv", "tip_heights.csv"}) {
    std::ifstream csv(run.folder / "vegetation_beam" / file);
    ASSERT_TRUE(csv) << file;
    std::string line;
    std::getline(csv, line);  // header
    std::vector<std::string> times;
    while (std::getline(csv, line)) times.push_back(line.substr(0, line.find(',')));
    const std::vector<std::string> expected = {"0", "0.01", "0.02", "0.03", "0.04", "0.05"};
    EXPECT_EQ(times, expected) << file;
  }
}

TEST(ImplicitCoupling, AWindowAtTheLimitStopsTheRunWhenAskedTo) {
  const auto runs = fresh_folder("implicit-stop");
  const auto result = run_cosim(
      fmt::format(
          "run {} --runs-dir {} --quiet --set duration=0.15 "
          "--set coupling.scheme=serial-implicit --set coupling.implicit.max_iterations=2 "
          "--set coupling.implicit.relative_tolerance=1e-12 "
          "--set coupling.implicit.absolute_force=0 --set coupling.implicit.absolute_position=0 "
          "--set coupling.implicit.absolute_velocity=0 "
          "--set coupling.implicit.at_max_iterations=stop",
          test_scene("light_blade").string(), runs.string()),
      120);
  EXPECT_NE(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("did not converge in 2 coupling iterations"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("at_max_iterations: stop"), std::string::npos) << result.output;
}

// Frames of `restarted` equal the frames of `straight` at the same times, and it wrote every
// frame `straight` wrote after `from`.
void expect_same_tail(const std::filesystem::path& straight, const std::filesystem::path& restarted,
                      double from) {
  std::vector<output::PointFrame> tail;
  for (int i = 0; i < output::count_point_frames(straight); ++i) {
    auto frame = output::read_point_frame(straight, i);
    if (frame.time > from + 1e-12) tail.push_back(std::move(frame));
  }
  ASSERT_FALSE(tail.empty()) << straight;
  ASSERT_EQ(static_cast<std::size_t>(output::count_point_frames(restarted)), tail.size())
      << restarted;
  for (std::size_t i = 0; i < tail.size(); ++i) {
    const auto frame = output::read_point_frame(restarted, static_cast<int>(i));
    EXPECT_EQ(std::memcmp(&frame.time, &tail[i].time, sizeof(double)), 0) << frame.time;
    EXPECT_TRUE(same_bits(frame.positions, tail[i].positions)) << restarted << " t " << frame.time;
    for (const auto& [name, values] : tail[i].vectors) {
      EXPECT_TRUE(same_bits(frame.vectors.at(name), values)) << name << " t " << frame.time;
    }
  }
}

const char* kIqnIls =
    "--set coupling.scheme=serial-implicit --set coupling.implicit.acceleration=iqn-ils";

// A checkpoint of an implicit run is the state after an accepted window: continued from it, the
// run iterates the next windows exactly as the uninterrupted run did.
TEST(ImplicitCoupling, ARunContinuedFromACheckpointIteratesTheSameBits) {
  const auto straight = run_light_blade(
      "checkpoints", fmt::format("--set duration=0.12 --set checkpoint_interval=0.04 {}", kIqnIls));
  ASSERT_FALSE(straight.folder.empty());
  ASSERT_TRUE(straight.summary["ok"].get<bool>()) << straight.summary.dump(2);
  const auto restarted = run_light_blade(
      "checkpoints-restarted",
      fmt::format("--set duration=0.12 {} --restart {}@0.04", kIqnIls, straight.folder.string()));
  ASSERT_FALSE(restarted.folder.empty());
  ASSERT_TRUE(restarted.summary["ok"].get<bool>()) << restarted.summary.dump(2);
  for (const char* file : {"fluid_mps/particles.h5", "vegetation_beam/plants.h5"}) {
    expect_same_tail(straight.folder / file, restarted.folder / file, 0.04);
  }
  // The iterations after the checkpoint are those of the uninterrupted run.
  const auto all = straight.summary["implicit"]["iterations_per_window"].get<std::vector<int>>();
  const auto after = restarted.summary["implicit"]["iterations_per_window"].get<std::vector<int>>();
  ASSERT_LE(after.size(), all.size());
  EXPECT_TRUE(std::equal(after.rbegin(), after.rend(), all.rbegin()));
}

// SIGINT in the middle of an implicit window: every participant rolls back to the start of the
// window it iterates and saves it, the state after the last accepted window; continuing from
// that checkpoint gives the uninterrupted run's bits.
TEST(ImplicitCoupling, AnInterruptedRunSavesTheLastAcceptedWindow) {
  const auto runs = fresh_folder("implicit-interrupted");
  const std::string common = fmt::format("--runs-dir {} --quiet {}", runs.string(), kIqnIls);
  const auto stopped = interrupted_run(
      fmt::format("run {} {} --set duration=20", test_scene("light_blade").string(), common), 3);
  ASSERT_GE(stopped.checkpoint_time, 0.0);
  const double at = stopped.checkpoint_time;
  const std::string until = fmt::format("--set duration={}", at + 0.02);
  const auto straight = run_light_blade("interrupted-straight", until + " " + kIqnIls);
  ASSERT_FALSE(straight.folder.empty());
  const auto restarted =
      run_light_blade("interrupted-restarted",
                      fmt::format("{} {} --restart {}", until, kIqnIls, stopped.folder.string()));
  ASSERT_FALSE(restarted.folder.empty());
  ASSERT_TRUE(restarted.summary["ok"].get<bool>()) << restarted.summary.dump(2);
  for (const char* file : {"fluid_mps/particles.h5", "vegetation_beam/plants.h5"}) {
    expect_same_tail(straight.folder / file, restarted.folder / file, at);
  }
}

}  // namespace
}  // namespace cosim::testing

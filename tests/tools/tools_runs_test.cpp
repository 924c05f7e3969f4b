// `cosim` on real runs of the blade scene: progress lines in a pipe, `cosim plot` of a run,
// the figure of a sweep, and a sweep that cannot draw stopping before it runs anything.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "command.hpp"
#include "cosim/output/point_series.hpp"
#include "plot_support.hpp"

namespace cosim::testing {
namespace {

namespace fs = std::filesystem;

std::string blade() {
  return test_scene("blade").string();
}

bool is_png(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(8, '\0');
  in.read(head.data(), 8);
  return in && head == "\x89PNG\r\n\x1a\n";
}

std::size_t folders_in(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& entry : fs::directory_iterator(dir)) n += entry.is_directory() ? 1 : 0;
  return n;
}

TEST(Progress, PipedRunPrintsPlainLinesWithAnEta) {
  const auto runs = fresh_folder("progress");
  // 300 windows: a few seconds, several lines at 0.3 s.
  const auto result = run_cosim(fmt::format(
      "run {} --runs-dir {} --set duration=0.3 --progress-interval 0.3", blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_EQ(result.output.find('\r'), std::string::npos) << "no redraws in a pipe";
  const std::regex line(
      R"(\[blade_test\] window (\d+)/300  t = \S+ s of 0.3 s  wall [^E]+  ETA ([^\n]+))");
  int lines = 0, with_eta = 0, last_window = 0;
  for (auto it = std::sregex_iterator(result.output.begin(), result.output.end(), line);
       it != std::sregex_iterator(); ++it, ++lines) {
    const int window = std::stoi((*it)[1]);
    EXPECT_GE(window, last_window);
    last_window = window;
    if ((*it)[2] != "--") ++with_eta;
  }
  EXPECT_GE(lines, 3) << result.output;
  EXPECT_GE(with_eta, 2) << result.output;
  EXPECT_NE(result.output.find("[blade_test] done: 300/300 windows"), std::string::npos)
      << result.output;

  const auto quiet = run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("[blade_test]"), std::string::npos) << quiet.output;
}

TEST(Plot, RunOfTheBladeGetsAFigurePerMetricFromItsSeries) {
  const auto runs = fresh_folder("plot-run");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto run_dir = run_folder_of(result);
  // The plants' HDF5 holds the solver's own series and the frames' statistics.
  std::vector<std::string> names;
  for (const auto& series : output::read_series(run_dir / "vegetation_beam/plants.h5")) {
    names.push_back(series.name);
    EXPECT_FALSE(series.times.empty()) << series.name;
  }
  for (const char* name : {"frame_points", "frame_velocity_max_magnitude"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  }
  // Metrics of the beam that have a series of their name (whatever the solver calls them).
  std::vector<std::string> plotted;
  const auto summary = read_summary(run_dir);
  for (const auto& participant : summary["participants"]) {
    if (participant["acts_as"] != "vegetation_beam") continue;
    for (const auto& [metric, value] : participant["report"]["metrics"].items()) {
      if (std::find(names.begin(), names.end(), metric) != names.end()) plotted.push_back(metric);
    }
  }
  ASSERT_FALSE(plotted.empty()) << "no metric of the beam has a time series";
  if (!matplotlib_available()) GTEST_SKIP() << "no python3 with matplotlib here";
  const auto plot = run_cosim("plot " + run_dir.string(), 60);
  ASSERT_EQ(plot.exit_code, 0) << plot.output;
  plotted.push_back("plants-series");
  for (const auto& name : plotted) {
    const std::string file = "plot-vegetation_beam-" + name + ".png";
    EXPECT_TRUE(is_png(run_dir / file)) << file << "\n" << plot.output;
  }
}

TEST(Sweep, WritesItsFigureBesideTheTable) {
  if (!matplotlib_available()) GTEST_SKIP() << "no python3 with matplotlib here";
  const auto runs = fresh_folder("sweep-figure");
  const auto result = run_cosim(
      fmt::format("sweep {} --vary coupling.window --values 1e-3 5e-4 --runs-dir {} --quiet",
                  blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::smatch csv, png;
  ASSERT_TRUE(std::regex_search(result.output, csv, std::regex("table written to (\\S+\\.csv)")))
      << result.output;
  ASSERT_TRUE(std::regex_search(result.output, png, std::regex("figure written to (\\S+\\.png)")))
      << result.output;
  EXPECT_EQ(fs::path(png[1].str()).replace_extension(".csv"), fs::path(csv[1].str()));
  EXPECT_TRUE(is_png(png[1].str()));
}

TEST(Sweep, WithoutMatplotlibStopsBeforeRunningAnything) {
  const auto runs = fresh_folder("sweep-no-matplotlib");
  const auto wrapper = runs / "python-without-matplotlib";
  std::ofstream(wrapper) << kPythonWithoutMatplotlib;
  fs::permissions(wrapper, fs::perms::owner_all);
  const auto result = run_command(fmt::format(
      "env COSIM_PYTHON={} {}/cosim sweep {} --vary coupling.window --values 1e-3 --runs-dir {}",
      wrapper.string(), COSIM_BIN_DIR, blade(), runs.string()));
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("apt-get install python3-matplotlib"), std::string::npos)
      << result.output;
  EXPECT_EQ(folders_in(runs), 0u) << "no run was started";
  // --no-plot runs it anyway, with the table only.
  const auto table = run_command(fmt::format(
      "env COSIM_PYTHON={} {}/cosim sweep {} --vary coupling.window --values 1e-3 --runs-dir {} "
      "--quiet --no-plot",
      wrapper.string(), COSIM_BIN_DIR, blade(), runs.string()));
  EXPECT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("table written to"), std::string::npos) << table.output;
  EXPECT_EQ(table.output.find("figure written to"), std::string::npos) << table.output;
}

// cosim spread: the bundle and one run per perturbation, then each metric's range over them.
TEST(Spread, RunsTheBundleAndEachPerturbationAndTabulatesTheRange) {
  const auto runs = fresh_folder("spread");
  const auto result =
      run_cosim(fmt::format("spread {} --perturb coupling.window=5e-4 --perturb "
                            "participants.vegetation_beam.safety_factor=0.4 --runs-dir {} --quiet "
                            "--record none",
                            blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("spread 1/3: bundle"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("spread 2/3: window=5e-4"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("spread 3/3: safety_factor=0.4"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("spread over 3 runs (the bundle and 2 perturbations)"),
            std::string::npos)
      << result.output;
  EXPECT_EQ(folders_in(runs), 3u) << "one run folder each";
  std::smatch csv;
  ASSERT_TRUE(std::regex_search(result.output, csv, std::regex("table written to (\\S+\\.csv)")))
      << result.output;
  std::ifstream in(csv[1].str());
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("perturbation,ok,wall_seconds,metric", 0), 0u) << header;
  // A perturbation that is not KEY=VALUE, or out of range, stops before anything runs.
  const auto bad = run_cosim(
      fmt::format("spread {} --perturb coupling.window --runs-dir {}", blade(), runs.string()));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--perturb expects KEY=VALUE"), std::string::npos) << bad.output;
  const auto range = run_cosim(
      fmt::format("spread {} --perturb participants.vegetation_beam.safety_factor=-1 --runs-dir {}",
                  blade(), runs.string()));
  EXPECT_EQ(range.exit_code, 2) << range.output;
  EXPECT_NE(range.output.find("(set on the command line)"), std::string::npos) << range.output;
  EXPECT_EQ(folders_in(runs), 3u) << "no run was started";
}

}  // namespace
}  // namespace cosim::testing

// The pieces of `cosim` that need no running scene: version, progress lines, the sweep figure,
// `cosim plot` on a hand-made run folder, and the README's Quick start commands.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "command.hpp"
#include "cosim/output/point_series.hpp"
#include "plot_support.hpp"
#include "progress.hpp"
#include "sweep.hpp"
#include "thread_wait.hpp"

namespace cosim::testing {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool is_png(const fs::path& path) {
  return slurp(path).rfind("\x89PNG\r\n\x1a\n", 0) == 0;
}

void write_executable(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  fs::permissions(path, fs::perms::owner_all | fs::perms::group_read | fs::perms::others_read);
}

// --- version ------------------------------------------------------------------------------

TEST(Version, PrintsTheProjectVersionAndGitDescribe) {
  const auto result = run_cosim("--version", 30);
  EXPECT_EQ(result.exit_code, 0) << result.output;
  // The project version exactly; the git part is read when cosim was configured, which may be
  // an earlier commit than this test's in a working checkout.
  const std::string expected = COSIM_EXPECTED_VERSION;
  const std::string project = expected.substr(0, expected.find(" (git"));
  EXPECT_EQ(result.output.rfind(project, 0), 0u) << result.output << " vs " << expected;
  EXPECT_TRUE(std::regex_search(result.output, std::regex(R"(^cosim \d+\.\d+\.\d+)")))
      << result.output;
}

// --- progress -----------------------------------------------------------------------------

TEST(Progress, DurationsReadLikeAClock) {
  EXPECT_EQ(tool::format_duration(0.04), "0.0 s");
  EXPECT_EQ(tool::format_duration(59.94), "59.9 s");
  EXPECT_EQ(tool::format_duration(61), "1 min 01 s");
  EXPECT_EQ(tool::format_duration(3599.4), "59 min 59 s");
  EXPECT_EQ(tool::format_duration(3720), "1 h 02 min");
  EXPECT_EQ(tool::format_duration(-1), "?");
}

TEST(Progress, EtaComesFromTheRateSinceTheWindowsStarted) {
  tool::ProgressState state;
  state.scene = "scene";
  state.total_windows = 20;
  state.duration = 1.0;
  state.wall = 100.0;  // 90 s of it were start-up: they do not count
  EXPECT_FALSE(tool::estimate_remaining(state));
  EXPECT_NE(tool::progress_line(state).find("starting"), std::string::npos);
  state.started = true;
  state.window = 6;
  state.simulated = 0.25;
  state.stepping_wall = 10.0;
  ASSERT_TRUE(tool::estimate_remaining(state));
  EXPECT_DOUBLE_EQ(*tool::estimate_remaining(state), 30.0);
  EXPECT_EQ(tool::progress_line(state),
            "[scene] window 6/20  t = 0.25 s of 1 s  wall 1 min 40 s  ETA 30.0 s");
  state.simulated = 0.0;  // window 1 only just began
  EXPECT_NE(tool::progress_line(state).find("ETA --"), std::string::npos);
}

// --- sweep figure -------------------------------------------------------------------------

tool::SweepRow row(const std::string& value, double wall, double error) {
  tool::SweepRow r;
  r.value = value;
  r.ok = true;
  r.wall = wall;
  r.metrics.emplace_back(
      "fluid.front",
      nlohmann::json{{"value", 1.0}, {"unit", "m"}, {"reference", 1.1}, {"relative_error", error}});
  r.metrics.emplace_back("fluid.count", nlohmann::json{{"value", 3.0}, {"unit", ""}});
  return r;
}

TEST(SweepFigure, PlotsRelativeErrorAgainstWallTime) {
  const auto figure =
      tool::sweep_figure("dam", "participants.fluid_mps.particle_spacing",
                         {row("0.02", 1.5, 0.2), row("0.01", 6.0, 0.05)}, "/tmp/x.png");
  EXPECT_EQ(figure["file"], "/tmp/x.png");
  EXPECT_EQ(figure["xscale"], "log");
  EXPECT_EQ(figure["ylabel"], "relative error [%]");
  ASSERT_EQ(figure["lines"].size(), 1u) << "only metrics with an error";
  const auto& line = figure["lines"][0];
  EXPECT_EQ(line["label"], "fluid.front");
  EXPECT_EQ(line["x"], (nlohmann::json{1.5, 6.0}));
  EXPECT_EQ(line["y"], (nlohmann::json{20.0, 5.0}));
  EXPECT_EQ(line["annotations"],
            (nlohmann::json{"particle_spacing=0.02", "particle_spacing=0.01"}));
}

TEST(SweepFigure, WithoutReferencesShowsEachValueAgainstWallTime) {
  tool::SweepRow a;
  a.value = "1";
  a.wall = 2.0;
  a.metrics.emplace_back("beam.tip", nlohmann::json{{"value", 0.5}, {"unit", "m"}});
  const auto figure = tool::sweep_figure("blade", "coupling.window", {a}, "/tmp/y.png");
  ASSERT_EQ(figure["panels"].size(), 1u);
  EXPECT_EQ(figure["panels"][0]["ylabel"], "beam.tip [m]");
  EXPECT_EQ(figure["panels"][0]["lines"][0]["y"], (nlohmann::json{0.5}));
}

// --- spread ------------------------------------------------------------------------------

TEST(MetricSpreads, RangeOfEachMetricOverTheRunsFromTheBase) {
  auto base = row("bundle", 1.0, 0.10);
  auto tighter = row("pcg_tolerance=1e-9", 1.1, 0.12);
  auto longer = row("courant=0.19", 1.2, 0.07);
  longer.metrics[1].second["value"] = 5.0;  // a metric without a reference
  tighter.metrics.pop_back();               // one run did not report it
  tighter.metrics.emplace_back("fluid.extra", nlohmann::json{{"value", 9.0}});  // not in the base
  const auto spreads = tool::metric_spreads({base, tighter, longer});
  ASSERT_EQ(spreads.size(), 2u) << "the base run's metrics, in its order";
  EXPECT_EQ(spreads[0].name, "fluid.front");
  EXPECT_EQ(spreads[0].unit, "m");
  EXPECT_EQ(spreads[0].runs, 3);
  EXPECT_TRUE(spreads[0].has_error);
  EXPECT_DOUBLE_EQ(spreads[0].base_error, 0.10);
  EXPECT_DOUBLE_EQ(spreads[0].min_error, 0.07);
  EXPECT_DOUBLE_EQ(spreads[0].max_error, 0.12);
  EXPECT_EQ(spreads[1].name, "fluid.count");
  EXPECT_EQ(spreads[1].runs, 2);
  EXPECT_FALSE(spreads[1].has_error);
  EXPECT_DOUBLE_EQ(spreads[1].base_value, 3.0);
  EXPECT_DOUBLE_EQ(spreads[1].min_value, 3.0);
  EXPECT_DOUBLE_EQ(spreads[1].max_value, 5.0);
  EXPECT_TRUE(tool::metric_spreads({}).empty());
}

// --- cosim plot ---------------------------------------------------------------------------

// A run folder as `cosim run` leaves it, with one participant's series.
fs::path fake_run(const std::string& name) {
  const auto run = fresh_folder(name);
  {
    output::PointSeriesWriter writer(run / "vegetation_beam" / "plants", "vegetation_beam");
    output::PointFrame frame;
    for (int i = 0; i < 4; ++i) frame.positions.emplace_back(0, 0, 0.01 * i);
    frame.scalars["psi"] = {0, 0.1, 0.2, 0.3};
    writer.write_frame(frame);
    frame.time = 1.0;
    writer.write_frame(frame);
    output::SeriesInfo info;
    info.unit = "m";
    info.description = "tip displacement";
    info.reference_times = {0.0, 1.0};
    info.reference_values = {0.0, 0.02};
    info.reference_source = "analytic";
    writer.write_series("tip", {0.0, 0.5, 1.0}, {0.0, 0.012, 0.019}, info);
    writer.write_series("front", {0.0, 1.0}, {0.1, 0.4}, info);
  }
  const nlohmann::json summary{
      {"scene", "fake"},
      {"participants",
       {{{"name", "prescribed_flow"}, {"acts_as", "prescribed_flow"}, {"report", nullptr}},
        {{"name", "vegetation_beam"},
         {"acts_as", "vegetation_beam"},
         {"report",
          {{"metrics",
            {{"tip",
              {{"value", 0.019}, {"unit", "m"}, {"reference", 0.02}, {"relative_error", 0.05}}},
             {"front_error", {{"value", 0.1}, {"unit", "relative"}, {"relative_error", 0.1}}},
             {"no_series", {{"value", 1.0}, {"unit", ""}}}}}}}}}}};
  std::ofstream(run / "summary.json") << summary.dump(2);
  return run;
}

TEST(Plot, DrawsEachMetricWithItsSeriesAndAnOverviewPerFile) {
  if (!matplotlib_available()) GTEST_SKIP() << "no python3 with matplotlib here";
  const auto run = fake_run("plot");
  const auto result = run_cosim("plot " + run.string(), 60);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  // An error metric is drawn with the series of the quantity it measures ("front").
  for (const char* file : {"plot-vegetation_beam-tip.png", "plot-vegetation_beam-front_error.png",
                           "plot-vegetation_beam-plants-series.png"}) {
    EXPECT_TRUE(is_png(run / file)) << file << "\n" << result.output;
    EXPECT_NE(result.output.find(file), std::string::npos) << result.output;
  }
  EXPECT_NE(result.output.find("metric 'no_series' has no time series"), std::string::npos)
      << result.output;
  EXPECT_FALSE(fs::exists(run / "plot-vegetation_beam-no_series.png"));
}

TEST(Plot, WithoutMatplotlibIsAClearError) {
  const auto run = fake_run("no-matplotlib");
  const auto wrapper = run / "python-without-matplotlib";
  write_executable(wrapper, kPythonWithoutMatplotlib);
  const auto result = run_command(fmt::format("env COSIM_PYTHON={} {}/cosim plot {}",
                                              wrapper.string(), COSIM_BIN_DIR, run.string()),
                                  60);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("needs python3 with matplotlib"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("apt-get install python3-matplotlib"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("no matplotlib"), std::string::npos) << result.output;

  const auto missing =
      run_command(fmt::format("env COSIM_PYTHON=/nonexistent/python3 {}/cosim plot {}",
                              COSIM_BIN_DIR, run.string()),
                  60);
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("/nonexistent/python3 (COSIM_PYTHON): not found"),
            std::string::npos)
      << missing.output;
  EXPECT_FALSE(fs::exists(run / "plot-vegetation_beam-tip.png"));
}

TEST(Plot, AFolderThatIsNoRunIsAClearError) {
  const auto folder = fresh_folder("not-a-run");
  const auto result = run_cosim("plot " + folder.string(), 30);
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("not a run folder"), std::string::npos) << result.output;
}

// --- README Quick start -------------------------------------------------------------------

// The shell blocks under "## Quick start", in order.
std::vector<std::string> quick_start_commands() {
  const std::string readme = slurp(fs::path(COSIM_SOURCE_DIR) / "README.md");
  const auto start = readme.find("## Quick start");
  const auto end = readme.find("\n## ", start + 1);
  const std::string section = readme.substr(start, end - start);
  std::vector<std::string> commands;
  const std::regex block("```sh\n([^`]*?)\n```");
  for (auto it = std::sregex_iterator(section.begin(), section.end(), block);
       it != std::sregex_iterator(); ++it) {
    commands.push_back((*it)[1]);
  }
  return commands;
}

// Runs the install command in a folder with stand-ins for apt-get, cmake and cosim that log
// how they were called; `with_sudo` adds a sudo that marks what it runs.
std::string run_install_command(const std::string& shell, bool with_sudo, int& exit_code) {
  const auto root = fresh_folder(
      fmt::format("quick-start-{}-{}", fs::path(shell).filename().string(), with_sudo));
  const auto bin = root / "stubs";
  fs::create_directories(bin);
  fs::create_directories(root / "tools");
  fs::create_directories(root / "build" / "bin");
  fs::copy_file(fs::path(COSIM_SOURCE_DIR) / "tools" / "debian-packages.txt",
                root / "tools" / "debian-packages.txt");
  const auto log = root / "calls.log";
  const std::string logger = fmt::format(
      "#!/bin/sh\necho \"${{COSIM_VIA_SUDO:+sudo }}$(basename \"$0\") $*\" >> {}\n", log.string());
  write_executable(bin / "apt-get", logger);
  write_executable(bin / "cmake", logger);
  write_executable(root / "build" / "bin" / "cosim", logger);
  fs::create_symlink("/bin/cat", bin / "cat");
  fs::create_symlink("/usr/bin/basename", bin / "basename");
  if (with_sudo) {
    write_executable(bin / "sudo", "#!/bin/sh\nCOSIM_VIA_SUDO=1 exec \"$@\"\n");
  }
  const std::string script = root / "install.sh";
  std::ofstream(script) << quick_start_commands().at(0) << "\n";
  const auto result = run_command(
      fmt::format("env -i -C {} PATH={} {} {}", root.string(), bin.string(), shell, script), 30);
  exit_code = result.exit_code;
  return slurp(log) + result.output;
}

TEST(QuickStart, InstallCommandIsOneLineAndKeepsBothCommands) {
  const auto commands = quick_start_commands();
  ASSERT_EQ(commands.size(), 2u);
  EXPECT_EQ(commands[0].find('\n'), std::string::npos) << commands[0];
  EXPECT_NE(commands[0].find("build/bin/cosim run scenarios/single_blade"), std::string::npos);
  EXPECT_EQ(commands[1].rfind("cmake --build build && ctest --test-dir build", 0), 0u)
      << commands[1];
}

TEST(QuickStart, InstallCommandWorksOnARootShellWithoutSudo) {
  for (const char* shell : {"/bin/sh", "/bin/bash"}) {
    SCOPED_TRACE(shell);
    int code = -1;
    const auto calls = run_install_command(shell, false, code);
    EXPECT_EQ(code, 0) << calls;
    EXPECT_NE(calls.find("\napt-get install -y build-essential"), std::string::npos) << calls;
    EXPECT_EQ(calls.rfind("apt-get update", 0), 0u) << calls;
    EXPECT_NE(calls.find("cmake -S . -B build"), std::string::npos) << calls;
    EXPECT_NE(calls.find("cosim run scenarios/single_blade"), std::string::npos) << calls;
    EXPECT_EQ(calls.find("sudo"), std::string::npos) << calls;
  }
}

TEST(QuickStart, InstallCommandUsesSudoWhereThereIsOne) {
  for (const char* shell : {"/bin/sh", "/bin/bash"}) {
    SCOPED_TRACE(shell);
    int code = -1;
    const auto calls = run_install_command(shell, true, code);
    EXPECT_EQ(code, 0) << calls;
    EXPECT_EQ(calls.rfind("sudo apt-get update", 0), 0u) << calls;
    EXPECT_NE(calls.find("\nsudo apt-get install -y build-essential"), std::string::npos) << calls;
    // Only the installation needs root: the build and the run stay the user's.
    EXPECT_NE(calls.find("\ncmake -S . -B build"), std::string::npos) << calls;
    EXPECT_EQ(calls.find("sudo cmake"), std::string::npos) << calls;
    EXPECT_EQ(calls.find("sudo cosim"), std::string::npos) << calls;
  }
}

// The solvers' threads spin briefly, then sleep, unless the user chose how they wait.
TEST(ThreadWait, BoundedSpinUnlessTheUserChoseAWait) {
  using tool::thread_wait_settings;
  const auto none = [](const char*) -> const char* { return nullptr; };
  const auto settings = thread_wait_settings(none);
  ASSERT_EQ(settings.size(), 2u);
  EXPECT_EQ(settings[0].name, "OMP_WAIT_POLICY");
  EXPECT_EQ(settings[0].value, "passive");
  EXPECT_EQ(settings[1].name, "GOMP_SPINCOUNT");
  EXPECT_EQ(settings[1].value, "10000");
  for (const char* chosen : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT"}) {
    SCOPED_TRACE(chosen);
    const auto user = [chosen](const char* name) -> const char* {
      return std::string(name) == chosen ? "passive" : nullptr;
    };
    EXPECT_TRUE(thread_wait_settings(user).empty());
  }
}

TEST(ThreadWait, SetsTheEnvironmentTheSolversInherit) {
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  const char* spin = std::getenv("GOMP_SPINCOUNT");
  const std::string saved_policy = policy ? policy : "", saved_spin = spin ? spin : "";
  unsetenv("OMP_WAIT_POLICY");
  unsetenv("GOMP_SPINCOUNT");
  tool::set_thread_wait();
  EXPECT_STREQ(std::getenv("OMP_WAIT_POLICY"), "passive");
  EXPECT_STREQ(std::getenv("GOMP_SPINCOUNT"), tool::kBoundedSpinCount);
  setenv("GOMP_SPINCOUNT", "0", 1);
  tool::set_thread_wait();  // a chosen wait stays
  EXPECT_STREQ(std::getenv("GOMP_SPINCOUNT"), "0");
  unsetenv("OMP_WAIT_POLICY");
  unsetenv("GOMP_SPINCOUNT");
  if (policy) setenv("OMP_WAIT_POLICY", saved_policy.c_str(), 1);
  if (spin) setenv("GOMP_SPINCOUNT", saved_spin.c_str(), 1);
}

}  // namespace
}  // namespace cosim::testing

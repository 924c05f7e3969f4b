#include "plot.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "cosim/coupler/process_group.hpp"
#include "cosim/output/point_series.hpp"

extern char** environ;

namespace cosim::tool {

namespace {

constexpr int kMissingMatplotlib = 3;  // tools/cosim_plot.py's exit code
constexpr std::size_t kMostPoints = 20000;

std::filesystem::path plot_script() {
  const auto beside = coupler::executable_dir() / "cosim_plot.py";
  if (std::filesystem::exists(beside)) return beside;
  return COSIM_PLOT_SCRIPT_SOURCE;
}

// Runs a program; returns its exit status, or -errno when it could not be started.
int run_program(const std::vector<std::string>& arguments, bool quiet) {
  std::vector<char*> argv;
  for (const auto& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  if (quiet) posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t child = 0;
  const int error = posix_spawnp(&child, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) return -error;
  int status = 0;
  while (waitpid(child, &status, 0) < 0) {
    if (errno != EINTR) return -errno;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string in_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const auto candidate = std::filesystem::path(dir.empty() ? "." : dir) / program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return "";
}

std::string describe_failure(int status) {
  if (status == -ENOENT || status == 127) return "not found";
  if (status < 0) return std::strerror(-status);
  if (status == kMissingMatplotlib) return "no matplotlib";
  return fmt::format("exit code {}", status);
}

// Every `step`-th sample, so a long series stays a small figure file; the last one always.
nlohmann::json thinned(const std::vector<double>& values) {
  const std::size_t step =
      std::max<std::size_t>(1, (values.size() + kMostPoints - 1) / kMostPoints);
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t i = 0; i < values.size(); i += step) {
    out.push_back(std::isfinite(values[i]) ? nlohmann::json(values[i]) : nlohmann::json(nullptr));
  }
  if (!values.empty() && (values.size() - 1) % step != 0) {
    out.push_back(std::isfinite(values.back()) ? nlohmann::json(values.back())
                                               : nlohmann::json(nullptr));
  }
  return out;
}

std::string with_unit(const std::string& name, const std::string& unit) {
  if (unit.empty() || unit == "unspecified" || unit == "1") return name;
  return fmt::format("{} [{}]", name, unit);
}

std::string safe_file_part(std::string text) {
  for (char& c : text) {
    if (c == '/' || c == ' ' || c == '\\') c = '_';
  }
  return text;
}

nlohmann::json series_lines(const output::Series& series) {
  nlohmann::json lines = nlohmann::json::array();
  lines.push_back({{"label", series.name},
                   {"x", thinned(series.times)},
                   {"y", thinned(series.values)},
                   {"style", "line"}});
  if (!series.info.reference_times.empty()) {
    lines.push_back({{"label", series.info.reference_source.empty()
                                   ? std::string("reference")
                                   : "reference: " + series.info.reference_source},
                     {"x", thinned(series.info.reference_times)},
                     {"y", thinned(series.info.reference_values)},
                     {"style", "reference"}});
  }
  return lines;
}

}  // namespace

std::string plotting_python() {
  static std::string found;
  if (!found.empty()) return found;
  const auto script = plot_script().string();
  std::vector<std::pair<std::string, std::string>> candidates;  // (program, shown as)
  if (const char* chosen = std::getenv("COSIM_PYTHON"); chosen != nullptr && *chosen != 0) {
    candidates.emplace_back(chosen, fmt::format("{} (COSIM_PYTHON)", chosen));
  } else {
    const std::string on_path = in_path("python3");
    if (!on_path.empty()) candidates.emplace_back(on_path, "python3 (" + on_path + ")");
    std::error_code ec;
    if (on_path.empty() || !std::filesystem::equivalent(on_path, "/usr/bin/python3", ec)) {
      candidates.emplace_back("/usr/bin/python3", "/usr/bin/python3");
    }
  }
  std::vector<std::string> tried;
  for (const auto& [program, shown] : candidates) {
    const int status = run_program({program, script, "--check"}, true);
    if (status == 0) {
      found = program;
      return found;
    }
    tried.push_back(shown + ": " + describe_failure(status));
  }
  std::string list;
  for (const auto& entry : tried) list += (list.empty() ? "" : "; ") + entry;
  throw PlotError(fmt::format(
      "drawing figures needs python3 with matplotlib (Debian: apt-get install python3-matplotlib; "
      "or set COSIM_PYTHON to such an interpreter). Tried {}",
      list));
}

void draw_figures(const nlohmann::json& figures) {
  const std::string python = plotting_python();
  char name[] = "/tmp/cosim-figures-XXXXXX.json";
  const int fd = ::mkstemps(name, 5);
  if (fd < 0) throw PlotError(std::string("cannot make a temporary file: ") + std::strerror(errno));
  ::close(fd);
  const std::filesystem::path spec = name;
  {
    std::ofstream out(spec);
    out << figures.dump();
    if (!out) throw PlotError("cannot write " + spec.string());
  }
  const int status = run_program({python, plot_script().string(), spec.string()}, false);
  std::filesystem::remove(spec);
  if (status != 0) {
    throw PlotError(
        fmt::format("{} {} failed: {}", python, plot_script().string(), describe_failure(status)));
  }
}

std::vector<std::filesystem::path> plot_run(const std::filesystem::path& run_dir,
                                            std::vector<std::string>& notes) {
  const auto summary_file = run_dir / "summary.json";
  std::ifstream in(summary_file);
  if (!in) {
    throw std::runtime_error(
        fmt::format("{} is not a run folder: it has no summary.json", run_dir.string()));
  }
  const auto summary = nlohmann::json::parse(in);
  nlohmann::json figures = nlohmann::json::array();
  std::vector<std::filesystem::path> files;
  auto add = [&](nlohmann::json figure, const std::filesystem::path& file) {
    figure["file"] = file.string();
    figures.push_back(std::move(figure));
    files.push_back(file);
  };
  const nlohmann::json participants = summary.value("participants", nlohmann::json::array());
  for (const auto& participant : participants) {
    const std::string name = participant.value("acts_as", participant.value("name", ""));
    std::map<std::string, output::Series> by_name;
    const auto folder = run_dir / name;
    std::vector<std::filesystem::path> h5_files;
    if (std::filesystem::is_directory(folder)) {
      for (const auto& entry : std::filesystem::directory_iterator(folder)) {
        if (entry.path().extension() == ".h5") h5_files.push_back(entry.path());
      }
    }
    std::sort(h5_files.begin(), h5_files.end());
    for (const auto& h5 : h5_files) {
      const auto all = output::read_series(h5);
      if (all.empty()) continue;
      nlohmann::json panels = nlohmann::json::array();
      for (const auto& series : all) {
        by_name.emplace(series.name, series);
        panels.push_back({{"title", series.name},
                          {"xlabel", "time [s]"},
                          {"ylabel", with_unit(series.name, series.info.unit)},
                          {"lines", series_lines(series)}});
      }
      add({{"title", fmt::format("{}: every series of {}", name, h5.filename().string())},
           {"panels", panels}},
          run_dir / fmt::format("plot-{}-{}-series.png", safe_file_part(name),
                                safe_file_part(h5.stem().string())));
    }
    const nlohmann::json report = participant.value("report", nlohmann::json::object());
    const nlohmann::json metrics =
        report.is_object() ? report.value("metrics", nlohmann::json::object()) : nlohmann::json{};
    for (const auto& [metric, value] : metrics.items()) {
      // The series of a metric has its name; an error metric ("surge_front_error") may also
      // have the series of the quantity it measures ("surge_front").
      auto found = by_name.find(metric);
      const std::string suffix = "_error";
      const bool error_metric = metric.size() > suffix.size() && metric.ends_with(suffix);
      const std::string quantity =
          error_metric ? metric.substr(0, metric.size() - suffix.size()) : metric;
      if (found == by_name.end()) found = by_name.find(quantity);
      if (found == by_name.end()) {
        notes.push_back(fmt::format(
            "{}: metric '{}' has no time series in {}/*.h5 (looked for "
            "/series/{})",
            name, metric, name, error_metric ? metric + " and /series/" + quantity : metric));
        continue;
      }
      const auto& series = found->second;
      const bool same_quantity = found->first == metric;
      const std::string unit =
          same_quantity ? value.value("unit", series.info.unit) : series.info.unit;
      auto lines = series_lines(series);
      if (same_quantity && value.contains("reference") && value["reference"].is_number()) {
        lines.push_back(
            {{"label", fmt::format("reference {:.6g} {}{}", value["reference"].get<double>(), unit,
                                   value.contains("reference_source")
                                       ? " (" + value["reference_source"].get<std::string>() + ")"
                                       : std::string())},
             {"y", {value["reference"].get<double>()}},
             {"style", "hline"},
             {"color", "black"}});
      }
      if (same_quantity && value.contains("value") && value["value"].is_number() &&
          unit != "relative") {
        lines.push_back(
            {{"label", fmt::format("reported {:.6g} {}", value["value"].get<double>(), unit)},
             {"y", {value["value"].get<double>()}},
             {"style", "hline"},
             {"color", "tab:red"}});
      }
      std::string title = fmt::format("{}: {}", name, metric);
      if (value.contains("relative_error") && value["relative_error"].is_number()) {
        title += fmt::format("  (error {:.3g} %)", 100 * value["relative_error"].get<double>());
      }
      add({{"title", title},
           {"xlabel", "time [s]"},
           {"ylabel", with_unit(series.name, unit)},
           {"lines", lines}},
          run_dir / fmt::format("plot-{}-{}.png", safe_file_part(name), safe_file_part(metric)));
    }
  }
  if (figures.empty()) {
    throw std::runtime_error(fmt::format(
        "{}: no participant wrote a time series (HDF5 /series) to plot", run_dir.string()));
  }
  draw_figures({{"figures", figures}});
  return files;
}

}  // namespace cosim::tool

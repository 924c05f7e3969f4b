#include "runner.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>

#include <stdlib.h>

#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/process_main.hpp"
#include "progress.hpp"

namespace cosim::tool {

namespace {

int64_t new_run_id() {
  std::random_device device;
  const uint64_t high = device();
  const uint64_t low = device();
  const auto now =
      static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  // Positive, and different for runs started together by one test.
  return static_cast<int64_t>(((high << 32) ^ low ^ now) & 0x7fffffffffffffffULL);
}

std::filesystem::path make_run_dir(const std::filesystem::path& runs_dir, const std::string& name,
                                   int64_t run_id) {
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  const std::string folder =
      fmt::format("{}-{:%Y%m%d-%H%M%S}-{:06x}", name, fmt::localtime(now), run_id & 0xffffff);
  const auto run_dir = std::filesystem::absolute(runs_dir / folder);
  std::filesystem::create_directories(run_dir / "logs");
  return run_dir;
}

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

nlohmann::json parse_metrics(const std::string& text) {
  if (text.empty()) return nlohmann::json::object();
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    return nlohmann::json{{"unparsed", text}};
  }
}

}  // namespace

RunOutcome run_scene(const scenario::Scene& scene, const RunRequest& request) {
  RunOutcome outcome;
  const int64_t run_id = new_run_id();
  const std::string url = coupler::run_lcm_url(run_id);
  const std::string label =
      request.run_label.empty() ? scene.name : scene.name + "-" + request.run_label;
  outcome.run_dir = make_run_dir(request.runs_dir, label, run_id);
  const auto resolved_file = outcome.run_dir / "scenario.yaml";
  {
    YAML::Emitter emitter;
    emitter << scene.resolved;
    write_text(resolved_file, std::string("# Resolved scenario: every value this run used.\n") +
                                  emitter.c_str() + "\n");
  }
  for (const auto& [name, fault] : request.faults) {
    bool known = false;
    for (const auto& entry : scene.participants)
      known |= entry.name == name || entry.acts_as == name;
    if (!known)
      throw std::runtime_error(
          fmt::format("--fault names '{}', which this scene does not run", name));
  }

  coupler::CouplerOptions options;
  options.url = url;
  options.run_id = run_id;
  if (request.record_mode != coupler::RecordMode::none) {
    options.event_log = outcome.run_dir / "events.lcmlog";
  }
  options.record_mode = request.record_mode;
  options.loss_probability = request.loss_probability;
  // The progress lines (with an estimate of the time left) come from the monitor below, which
  // listens to the coupler's window broadcasts.
  coupler::Coupler coupler(scene, options);
  std::optional<ProgressMonitor> progress;
  if (request.show_progress) {
    progress.emplace(ProgressMonitor::Options{url, run_id, label, scene.duration,
                                              scene.total_windows(), request.progress_interval,
                                              stderr});
  }

  coupler::ProcessGroup processes;
  const auto bin = coupler::executable_dir();
  // Solvers share the machine with each other: OpenMP threads that spin while waiting would
  // steal the cores their partners compute on (docs/performance.md, fluid_mps).
  setenv("OMP_WAIT_POLICY", "passive", 0);
  for (const auto& entry : scene.participants) {
    const auto executable = bin / entry.executable;
    if (!std::filesystem::exists(executable)) {
      throw std::runtime_error(fmt::format("the solver '{}' is not built: {} does not exist",
                                           entry.executable, executable.string()));
    }
    std::string fault;
    if (auto found = request.faults.find(entry.name); found != request.faults.end())
      fault = found->second;
    if (auto found = request.faults.find(entry.acts_as); found != request.faults.end())
      fault = found->second;
    processes.start(
        entry.name,
        coupler::process_arguments(executable, resolved_file, outcome.run_dir, entry.name, url,
                                   run_id, request.loss_probability, fault),
        outcome.run_dir / "logs" / (entry.name + ".log"));
  }
  outcome.result = coupler.run(processes);
  const auto& result = outcome.result;
  if (progress) {
    progress->finish(result.ok, result.windows_completed, result.simulated_time,
                     result.wall_seconds);
  }
  outcome.exit_code = result.ok ? 0 : 1;

  nlohmann::json summary;
  summary["scene"] = scene.name;
  summary["scenario"] = scene.file.string();
  summary["run_id"] = run_id;
  summary["lcm_url"] = url;
  summary["ok"] = result.ok;
  if (!result.ok) summary["failure"] = result.failure;
  summary["scheme"] = scene.coupling.scheme;
  summary["duration"] = scene.duration;
  summary["simulated_time"] = result.simulated_time;
  summary["windows_completed"] = result.windows_completed;
  summary["total_windows"] = result.total_windows;
  summary["wall_seconds"] = result.wall_seconds;
  summary["injected_loss"] = request.loss_probability;
  // `cosim replay` reads this to tell a log without field values from a damaged one.
  summary["record"] = coupler::record_mode_name(request.record_mode);
  nlohmann::json participants = nlohmann::json::array();
  for (const auto& report : result.participants) {
    const auto& entry = scene.participant(report.name);
    participants.push_back({{"name", entry.name},
                            {"acts_as", entry.acts_as},
                            {"executable", entry.executable},
                            {"role", scenario::role_name(entry.role)},
                            {"compute_seconds", report.compute_seconds},
                            {"cpu_seconds", report.cpu_seconds},
                            {"coupling_wait_seconds", report.wait_seconds},
                            {"physics_seconds", report.physics_seconds},
                            {"windows", report.windows},
                            {"steps", report.steps},
                            {"report", parse_metrics(report.metrics_json)}});
  }
  summary["participants"] = participants;
  summary["traffic"] = {{"accepted", result.traffic.accepted},
                        {"dropped_injected", result.traffic.dropped_injected},
                        {"dropped_duplicate", result.traffic.dropped_duplicate},
                        {"dropped_foreign", result.traffic.dropped_foreign},
                        {"gaps_detected", result.traffic.gaps_detected},
                        {"resends_requested", result.traffic.resends_requested}};
  // Wall time of windows 1..N that no participant's physics explains (coupler.hpp).
  summary["coupling_overhead"] = {
      {"windows_wall_seconds", result.windows_wall_seconds},
      {"critical_physics_seconds", result.critical_physics_seconds},
      {"overhead_seconds", result.overhead_seconds},
      {"overhead_fraction", result.overhead_fraction},
      {"overhead_ms_per_window", result.overhead_ms_per_window}};
  write_text(outcome.run_dir / "summary.json", summary.dump(2) + "\n");
  return outcome;
}

void print_report(const std::filesystem::path& run_dir) {
  std::ifstream in(run_dir / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  fmt::print("run folder: {}\n", run_dir.string());
  fmt::print("{}: {} windows, {:.4g} s simulated in {:.2f} s wall\n",
             summary["scene"].get<std::string>(), summary["windows_completed"].get<int64_t>(),
             summary["simulated_time"].get<double>(), summary["wall_seconds"].get<double>());
  for (const auto& participant : summary["participants"]) {
    fmt::print("  {:<16} compute {:8.2f} s  coupling wait {:8.2f} s  steps {}\n",
               participant["name"].get<std::string>(), participant["compute_seconds"].get<double>(),
               participant["coupling_wait_seconds"].get<double>(),
               participant["steps"].get<int64_t>());
    const auto& report = participant["report"];
    if (!report.contains("metrics")) continue;
    // A metric the run could not measure (NaN, stored as null) prints as nan, never throws.
    auto number = [](const nlohmann::json& v) {
      return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN();
    };
    for (const auto& [metric, value] : report["metrics"].items()) {
      if (value.contains("reference")) {
        fmt::print("    {:<28} {:>12.5g} {:<6} reference {:>12.5g}  error {:>7.3f} %  ({})\n",
                   metric, number(value["value"]), value.value("unit", ""),
                   number(value["reference"]), 100.0 * number(value["relative_error"]),
                   value.value("reference_source", ""));
      } else if (value.contains("reference_source")) {
        fmt::print("    {:<28} {:>12.5g} {:<6} against {}\n", metric, number(value["value"]),
                   value.value("unit", ""), value.value("reference_source", ""));
      } else {
        fmt::print("    {:<28} {:>12.5g} {}\n", metric, number(value["value"]),
                   value.value("unit", ""));
      }
    }
  }
  if (!summary["ok"].get<bool>()) {
    fmt::print("FAILED: {}\n", summary["failure"].get<std::string>());
  }
}

}  // namespace cosim::tool

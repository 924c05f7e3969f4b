#include "run_summary.hpp"

#include <fmt/format.h>
#include <string.h>

#include <algorithm>

#include "cosim/coupler/event_log.hpp"

namespace cosim::tool {
namespace {

nlohmann::json parse_metrics(const std::string& text) {
  if (text.empty()) return nlohmann::json::object();
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    return nlohmann::json{{"unparsed", text}};
  }
}

}  // namespace

std::string signal_name(int signal) {
  const char* abbreviation = sigabbrev_np(signal);
  return abbreviation ? std::string("SIG") + abbreviation : fmt::format("signal {}", signal);
}

nlohmann::json summary_of(const scenario::Scene& scene, const RunRequest& request,
                          const RunOutcome& outcome, int64_t run_id, const std::string& url,
                          const std::optional<ResolvedRestart>& restart) {
  const auto& result = outcome.result;
  nlohmann::json summary;
  summary["scene"] = scene.name;
  summary["scenario"] = scene.file.string();
  summary["run_id"] = run_id;
  summary["lcm_url"] = url;
  summary["ok"] = result.ok;
  if (!result.ok) summary["failure"] = result.failure;
  if (outcome.interrupted_by != 0) summary["interrupted_by"] = signal_name(outcome.interrupted_by);
  summary["scheme"] = scene.coupling.scheme;
  summary["duration"] = scene.duration;
  summary["simulated_time"] = result.simulated_time;
  summary["windows_completed"] = result.windows_completed;
  summary["total_windows"] = result.total_windows;
  summary["wall_seconds"] = result.wall_seconds;
  if (restart) {
    summary["restarted_from"] = {{"checkpoint", restart->folder.string()},
                                 {"window", restart->point.window},
                                 {"time", restart->point.time},
                                 {"build", restart->manifest.value("build", "")}};
  }
  summary["checkpoints"] = result.checkpoints;
  if (scene.coupling.is_implicit()) {
    // Coupling iterations of windows 1..N (each a full run of every participant's window).
    const auto& its = result.iterations;
    int64_t total = 0;
    for (const int n : its) total += n;
    summary["implicit"] = {
        {"acceleration", result.acceleration},
        {"max_iterations", scene.coupling.implicit.max_iterations},
        {"iterations_total", total},
        {"iterations_mean", its.empty() ? 0.0 : static_cast<double>(total) / its.size()},
        {"iterations_max", its.empty() ? 0 : *std::max_element(its.begin(), its.end())},
        {"windows_at_max_iterations", result.windows_at_max_iterations},
        {"aitken_restarts", result.aitken_restarts},
        {"iterations_per_window", its}};
  }
  summary["injected_loss"] = request.loss_probability;
  summary["remote_participants"] = request.remote;
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
  summary["coupling_overhead"] = {{"windows_wall_seconds", result.windows_wall_seconds},
                                  {"critical_physics_seconds", result.critical_physics_seconds},
                                  {"overhead_seconds", result.overhead_seconds},
                                  {"overhead_fraction", result.overhead_fraction},
                                  {"overhead_ms_per_window", result.overhead_ms_per_window}};
  return summary;
}

std::string convergence_csv(const coupler::RunResult& result) {
  std::string text = "window,time,iteration";
  for (const auto& field : result.convergence_fields) text += ",\"" + field + "\"";
  text += "\n";
  for (const auto& row : result.convergence) {
    text += fmt::format("{},{:.9g},{}", row.window, row.time, row.iteration);
    for (const double ratio : row.ratios) text += fmt::format(",{:.6g}", ratio);
    text += "\n";
  }
  return text;
}

}  // namespace cosim::tool

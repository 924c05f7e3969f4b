#include "runner.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <fmt/ranges.h>
#include <signal.h>
#include <stdlib.h>

#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <stdexcept>
#include <thread>

#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/event_log.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/output/files.hpp"
#include "progress.hpp"
#include "run_summary.hpp"
#include "thread_wait.hpp"

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
  output::write_file_atomically(file, text);
}

// Holds SIGINT and SIGTERM for the whole run and turns them into an interruption of the
// process group, which the coupler handles like a failed child: ABORT to everyone, SIGTERM,
// then SIGKILL for what is left. Blocking the signals in every thread of the run (the mask is
// inherited by the threads started after it) and taking them in one watcher thread with
// sigtimedwait keeps system calls elsewhere from failing with EINTR halfway.
class InterruptWatch {
 public:
  explicit InterruptWatch(coupler::ProcessGroup& processes) : processes_(processes) {
    sigemptyset(&signals_);
    sigaddset(&signals_, SIGINT);
    sigaddset(&signals_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals_, &previous_);
    thread_ = std::thread([this] { watch(); });
  }
  ~InterruptWatch() {
    stop_ = true;
    thread_.join();
    // A signal that came after the watcher stopped would kill the process once unblocked,
    // after the run has ended and been written: take it here.
    const timespec now{};
    while (sigtimedwait(&signals_, nullptr, &now) > 0) {
    }
    pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
  }
  InterruptWatch(const InterruptWatch&) = delete;
  InterruptWatch& operator=(const InterruptWatch&) = delete;
  int signal() const { return signal_.load(); }

 private:
  void watch() {
    const timespec tick{0, 100'000'000};
    while (!stop_) {
      const int got = sigtimedwait(&signals_, nullptr, &tick);
      if (got <= 0) continue;
      int none = 0;
      // The first signal stops the run; repeats while it stops change nothing.
      if (signal_.compare_exchange_strong(none, got)) processes_.interrupt(got);
    }
  }

  coupler::ProcessGroup& processes_;
  sigset_t signals_{};
  sigset_t previous_{};
  std::atomic<int> signal_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

void check_fault(const scenario::Scene& scene, const std::string& name, const std::string& spec) {
  const std::string given = name + ":" + spec;
  auto refuse = [&](const std::string& problem) {
    throw std::invalid_argument(fmt::format("--fault '{}': {}", given, problem));
  };
  const bool known =
      std::any_of(scene.participants.begin(), scene.participants.end(),
                  [&](const auto& entry) { return entry.name == name || entry.acts_as == name; });
  if (!known) refuse(no_participant(scene, name));
  const auto at = spec.find('@');
  if (at == std::string::npos)
    refuse("expected PARTICIPANT:KIND@WINDOW, e.g. vegetation_beam:exit@5");
  const std::string kind = spec.substr(0, at);
  const std::string window_text = spec.substr(at + 1);
  const auto& kinds = fault_kinds();
  if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end()) {
    refuse(fmt::format("unknown kind '{}' (known kinds: {})", kind, fmt::join(kinds, ", ")));
  }
  const int64_t total = scene.total_windows();
  int64_t window = 0;
  const char* end = window_text.data() + window_text.size();
  const auto parsed = std::from_chars(window_text.data(), end, window);
  if (window_text.empty() || parsed.ec != std::errc() || parsed.ptr != end) {
    refuse(fmt::format("the window '{}' is not a whole number (this scene has windows 1 to {})",
                       window_text, total));
  }
  if (window < 1 || window > total) {
    refuse(fmt::format("window {} is outside this scene's windows 1 to {}", window, total));
  }
}

bool is_remote(const RunRequest& request, const std::string& name) {
  return std::find(request.remote.begin(), request.remote.end(), name) != request.remote.end();
}

void check_executables(const scenario::Scene& scene, const RunRequest& request) {
  const auto bin = coupler::executable_dir();
  for (const auto& entry : scene.participants) {
    if (is_remote(request, entry.name)) continue;  // built on its own host
    const auto executable = bin / entry.executable;
    if (!std::filesystem::exists(executable)) {
      throw std::runtime_error(fmt::format("the solver '{}' is not built: {} does not exist",
                                           entry.executable, executable.string()));
    }
  }
}

void check_remote(const scenario::Scene& scene, const RunRequest& request) {
  std::vector<std::string> seen;
  for (const auto& name : request.remote) {
    const auto refuse = [&](const std::string& problem) {
      throw std::invalid_argument(fmt::format("--remote '{}': {}", name, problem));
    };
    const auto* entry = find_participant(scene, name);
    if (!entry) refuse(no_participant(scene, name));
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) refuse("given twice");
    seen.push_back(name);
    if (request.faults.contains(entry->name) || request.faults.contains(entry->acts_as)) {
      refuse("a fault can only be injected into a process this command starts");
    }
  }
  if (!request.remote.empty() && (request.lcm_ttl < 1 || request.lcm_ttl > 255)) {
    throw std::invalid_argument(fmt::format(
        "--lcm-ttl {}: a run with remote participants needs 1 to 255", request.lcm_ttl));
  }
}

// What to type on the other host: `cosim join` with this run's address and scenario.
std::string join_command(const std::filesystem::path& run_dir, const std::string& name,
                         const std::string& url, int64_t run_id) {
  return fmt::format("cosim join --scenario {} --run-dir {} --name {} --lcm-url '{}' --run-id {}",
                     (run_dir / "scenario.yaml").string(), run_dir.string(), name, url, run_id);
}

}  // namespace

const scenario::ParticipantEntry* find_participant(const scenario::Scene& scene,
                                                   const std::string& name) {
  for (const auto& entry : scene.participants)
    if (entry.name == name) return &entry;
  return nullptr;
}

std::string no_participant(const scenario::Scene& scene, const std::string& name) {
  std::vector<std::string> names;
  for (const auto& entry : scene.participants) names.push_back(entry.name);
  return fmt::format("this scene runs no participant '{}' (it runs {})", name,
                     fmt::join(names, ", "));
}

const std::vector<std::string>& fault_kinds() {
  static const std::vector<std::string> kinds{"exit", "hang", "throw"};
  return kinds;
}

void check_run_request(const scenario::Scene& scene, const RunRequest& request) {
  for (const auto& [name, spec] : request.faults) check_fault(scene, name, spec);
  check_remote(scene, request);
  const double loss = request.loss_probability;
  if (!std::isfinite(loss) || loss < 0.0 || loss > 0.5) {
    throw std::invalid_argument(
        fmt::format("--inject-loss {}: must be a finite fraction from 0 to 0.5", loss));
  }
}

namespace {

// Starts every participant and runs the coupler over them. The coupler (and with it the event
// log) is closed on return, so the log's write errors are known to the caller.
void run_participants(const scenario::Scene& scene, const RunRequest& request,
                      const coupler::CouplerOptions& options, const std::string& label,
                      const std::filesystem::path& restart_folder, coupler::ProcessGroup& processes,
                      RunOutcome& outcome) {
  // The progress lines (with an estimate of the time left) come from the monitor below, which
  // listens to the coupler's window broadcasts.
  coupler::Coupler coupler(scene, options);
  std::optional<ProgressMonitor> progress;
  if (request.show_progress) {
    progress.emplace(ProgressMonitor::Options{options.url, options.run_id, label, scene.duration,
                                              scene.total_windows(), request.progress_interval,
                                              stderr});
  }
  const auto bin = coupler::executable_dir();
  const auto resolved_file = outcome.run_dir / "scenario.yaml";
  set_thread_wait();
  for (const auto& entry : scene.participants) {
    if (is_remote(request, entry.name)) {
      // Printed and flushed before the handshake waits for it.
      fmt::print(
          "cosim: start '{}' on its host now (the run waits {:.0f} s for it); copy {} "
          "there first unless that host shares this folder:\n  {}\n",
          entry.name, options.startup_timeout, (outcome.run_dir / "scenario.yaml").string(),
          join_command(outcome.run_dir, entry.name, options.url, options.run_id));
      std::fflush(stdout);
      continue;
    }
    std::string fault;
    if (auto found = request.faults.find(entry.name); found != request.faults.end())
      fault = found->second;
    if (auto found = request.faults.find(entry.acts_as); found != request.faults.end())
      fault = found->second;
    processes.start(
        entry.name,
        coupler::process_arguments(bin / entry.executable, resolved_file, outcome.run_dir,
                                   entry.name, options.url, options.run_id,
                                   request.loss_probability, fault, restart_folder),
        outcome.run_dir / "logs" / (entry.name + ".log"));
  }
  outcome.result = coupler.run(processes);
  const auto& result = outcome.result;
  if (progress) {
    progress->finish(result.ok, result.windows_completed, result.simulated_time,
                     result.wall_seconds);
  }
}

}  // namespace

RunOutcome run_scene(const scenario::Scene& scene, const RunRequest& request) {
  // Everything the command line got wrong is refused before the run folder exists.
  check_run_request(scene, request);
  check_executables(scene, request);
  // A checkpoint that does not fit is refused before the run folder exists.
  std::optional<ResolvedRestart> restart;
  if (request.restart) restart = resolve_restart(scene, *request.restart);
  RunOutcome outcome;
  const int64_t run_id = new_run_id();
  const std::string url =
      coupler::run_lcm_url(run_id, request.remote.empty() ? 0 : request.lcm_ttl);
  const std::string label =
      request.run_label.empty() ? scene.name : scene.name + "-" + request.run_label;
  outcome.run_dir = make_run_dir(request.runs_dir, label, run_id);
  {
    YAML::Emitter emitter;
    emitter << scene.resolved;
    write_text(
        outcome.run_dir / "scenario.yaml",
        std::string("# Resolved scenario: every value this run used.\n") + emitter.c_str() + "\n");
  }
  coupler::CouplerOptions options;
  options.url = url;
  options.run_id = run_id;
  if (request.record_mode != coupler::RecordMode::none) {
    options.event_log = outcome.run_dir / "events.lcmlog.zst";
  }
  options.record_mode = request.record_mode;
  options.loss_probability = request.loss_probability;
  options.checkpoints.folder = outcome.run_dir / "checkpoints";
  options.checkpoints.interval = scene.run.checkpoint_interval;
  options.checkpoints.manifest = manifest_base(scene);
  if (restart) {
    options.restart = restart->point;
    options.checkpoints.manifest["restarted_from"] = restart->folder.string();
  }
  options.startup_timeout =
      request.startup_timeout > 0.0 ? request.startup_timeout : (request.remote.empty() ? 60 : 600);

  coupler::ProcessGroup processes;
  InterruptWatch watch(processes);
  run_participants(scene, request, options, label, restart ? restart->folder : "", processes,
                   outcome);
  auto& result = outcome.result;
  outcome.exit_code = result.ok ? 0 : 1;
  if (const int signal = watch.signal(); signal != 0) {
    const int64_t at = std::min(result.windows_completed + 1, result.total_windows);
    result.ok = false;
    result.failure = fmt::format("interrupted by {} at window {} of {}", signal_name(signal), at,
                                 result.total_windows);
    outcome.interrupted_by = signal;
    outcome.exit_code = 128 + signal;
  }
  nlohmann::json summary = summary_of(scene, request, outcome, run_id, url, restart);
  if (!options.event_log.empty()) {
    if (const auto error = coupler::EventRecorder::write_failure(options.event_log);
        !error.empty()) {
      summary["event_log_error"] = error;
      if (result.ok) {
        result.ok = false;
        result.failure = error + " (every window ran, but the log is incomplete)";
        summary["ok"] = false;
        summary["failure"] = result.failure;
        outcome.exit_code = 1;
      }
    }
  }
  if (scene.coupling.is_implicit()) {
    try {
      write_text(outcome.run_dir / "implicit_convergence.csv", convergence_csv(result));
    } catch (const std::runtime_error& error) {
      summary["implicit"]["convergence_log_error"] = error.what();
    }
  }
  try {
    write_text(outcome.run_dir / "summary.json", summary.dump(2) + "\n");
  } catch (const std::runtime_error& error) {
    // The summary was where the outcome would be read: say it here instead.
    fmt::print(stderr, "error: {}; the run {}\n", error.what(),
               result.ok ? std::string("itself finished") : "failed: " + result.failure);
    if (const auto log_error = coupler::EventRecorder::write_failure(options.event_log);
        !log_error.empty() && log_error != result.failure) {
      fmt::print(stderr, "error: {}\n", log_error);
    }
    if (outcome.exit_code == 0) outcome.exit_code = 1;
  }
  return outcome;
}

std::string interruption_line(const RunOutcome& outcome) {
  return fmt::format("cosim: {} ({} windows completed); every process stopped; run folder: {}",
                     outcome.result.failure, outcome.result.windows_completed,
                     outcome.run_dir.string());
}

void print_report(const std::filesystem::path& run_dir) {
  fmt::print("run folder: {}\n", run_dir.string());
  std::ifstream in(run_dir / "summary.json");
  const auto summary = nlohmann::json::parse(in, nullptr, false);
  if (!summary.is_object()) {
    // run_scene has said why (a full disk, say); the run folder is still worth naming.
    fmt::print("FAILED: the run folder has no readable summary.json\n");
    return;
  }
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
    fmt::print("FAILED: {}\n", summary.value("failure", std::string("(no reason recorded)")));
  }
}

}  // namespace cosim::tool

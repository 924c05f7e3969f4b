#include "cosim/coupler/coupler.hpp"

#include "cosim/coupler/frame.hpp"
#include "steady_clock.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

namespace cosim::coupler {

namespace {
using cosim_msgs::status_t;
using cosim_msgs::window_t;

std::vector<std::pair<std::string, std::string>> names_of(const scenario::Scene& scene) {
  std::vector<std::pair<std::string, std::string>> names;
  for (const auto& entry : scene.participants) names.emplace_back(entry.acts_as, entry.name);
  return names;
}
}  // namespace

Coupler::Coupler(const scenario::Scene& scene, CouplerOptions options)
    : scene_(scene), options_(std::move(options)), book_(options_.checkpoints, names_of(scene)) {
  BusOptions bus_options;
  bus_options.url = options_.url;
  bus_options.run_id = options_.run_id;
  bus_options.name = "coupler";
  bus_options.record_log = options_.event_log;
  bus_options.loss_probability = options_.loss_probability;
  bus_options.loss_seed = static_cast<uint64_t>(options_.run_id) + 17;
  bus_options.chunk_values = scene_.coupling.chunk_values;
  bus_options.record_mode = options_.record_mode;
  bus_options.resend_interval = scene_.coupling.resend_interval;
  // The coupler records fields but never uses them, except to iterate an implicit scheme's window.
  bus_options.keep_fields = scene_.coupling.is_implicit();
  bus_ = std::make_unique<Bus>(bus_options);
  for (const auto& entry : scene_.participants) {
    names_.push_back(entry.acts_as);
    reports_[entry.acts_as].name = entry.acts_as;
  }
}

std::string Coupler::window_text(int64_t index) const {
  const double time =
      index >= 0 && index < static_cast<int64_t>(plan_.size()) ? plan_[index].first : 0.0;
  return fmt::format("window {} (t = {:.6g} s)", index, time);
}

void Coupler::book_report(const status_t& status, bool new_window,
                          std::map<int64_t, double>& stable_dt) {
  auto& report = reports_[status.header.sender];
  report.windows += new_window ? 1 : 0;
  report.steps += status.steps;
  report.compute_seconds = status.compute_seconds;
  report.cpu_seconds = status.cpu_seconds;
  report.wait_seconds = status.wait_seconds;
  if (status.header.window == 0) {
    report.physics_at_window_zero = status.physics_seconds;
  } else if (report.physics_at_window_zero >= 0.0) {
    report.physics_seconds = status.physics_seconds - report.physics_at_window_zero;
  }
  if (status.stable_dt > 0.0) {
    // Windows after this one may already be sized and granted without it.
    if (!limiting_.contains(status.header.sender)) {
      throw Failure(fmt::format(
          "'{}' reported a stable dt of {:.6g} s in {} but declared at the handshake that it does "
          "not limit the window (a process of another build?)",
          status.header.sender, status.stable_dt, window_text(status.header.window)));
    }
    auto [it, inserted] = stable_dt.try_emplace(status.header.window, status.stable_dt);
    if (!inserted) it->second = std::min(it->second, status.stable_dt);
  }
}

double Coupler::start_plan() {
  // A restart's first window is the checkpoint's window N again (dt 0: its fields published
  // again), and window N + 1 starts where the checkpoint stands. Window 0 exchanges initial
  // states.
  const int64_t first = options_.restart ? options_.restart->window : 0;
  plan_.assign(static_cast<std::size_t>(first) + 1, {0.0, 0.0});
  if (!options_.restart) return 0.0;
  plan_[first] = {options_.restart->time, 0.0};
  return options_.restart->time;
}

bool Coupler::plan_next_window(double& next_time, const std::map<int64_t, double>& stable_dt,
                               RunResult& result) {
  const bool adaptive = scene_.coupling.adaptive_window;
  const auto index = static_cast<int64_t>(plan_.size());
  double dt = scene_.coupling.window;
  if (adaptive) {
    if (const auto found = stable_dt.find(index - 1); found != stable_dt.end()) {
      dt = std::min(dt, found->second);
    }
  }
  // Land on the scene's duration; a remainder within round-off of the window is the window
  // (the window length, not a value 1e-19 shorter, is what the solvers were given before).
  const double remaining = scene_.duration - next_time;
  if (remaining < dt * (1.0 - 1e-9)) dt = remaining;
  if (dt <= scene_.duration * 1e-12) return false;
  plan_.emplace_back(next_time, dt);
  // Fixed windows: no round-off drift over long runs.
  next_time = adaptive
                  ? next_time + dt
                  : std::min(static_cast<double>(index) * scene_.coupling.window, scene_.duration);
  book_.plan(index, plan_.back().first, next_time);
  // Adaptive windows may need more than the nominal count.
  result.total_windows = std::max(result.total_windows, index);
  return true;
}

void Coupler::book_overhead(RunResult& result, Clock::time_point windows_started, int64_t completed,
                            bool serial) const {
  const double windows_wall =
      windows_started == Clock::time_point{} ? 0.0 : seconds_since(windows_started);
  double physics_sum = 0.0;
  double physics_max = 0.0;
  for (const auto& name : names_) {
    physics_sum += reports_.at(name).physics_seconds;
    physics_max = std::max(physics_max, reports_.at(name).physics_seconds);
  }
  result.windows_wall_seconds = windows_wall;
  result.critical_physics_seconds = serial ? physics_sum : physics_max;
  result.overhead_seconds = std::max(0.0, windows_wall - result.critical_physics_seconds);
  result.overhead_fraction = windows_wall > 0.0 ? result.overhead_seconds / windows_wall : 0.0;
  result.overhead_ms_per_window =
      completed >= 1 ? 1e3 * result.overhead_seconds / static_cast<double>(completed) : 0.0;
}

bool Coupler::take_reports(Progress& progress) {
  bool progressed = false;
  auto& statuses = bus_->statuses();
  while (!statuses.empty()) {
    status_t status = std::move(statuses.front());
    statuses.pop_front();
    const std::string sender = status.header.sender;
    if (status.state == status_t::STATE_FAILED) {
      throw Failure(fmt::format("'{}' failed in {}: {}", sender, window_text(status.header.window),
                                status.message));
    }
    if (status.state == status_t::STATE_CHECKPOINTED) {
      book_.answer(status);
      continue;
    }
    const auto done = progress.done.find(sender);
    if (status.state != status_t::STATE_DONE || done == progress.done.end()) continue;
    if (status.header.window <= done->second) continue;
    auto& queue = progress.early[sender];
    queue.emplace(status.header.window, std::move(status));
    while (!queue.empty() && queue.begin()->first == done->second + 1) {
      book_report(queue.begin()->second, true, progress.stable_dt);
      done->second = queue.begin()->first;
      queue.erase(queue.begin());
      progressed = true;
    }
  }
  return progressed;
}

void Coupler::stop_on_exit(ProcessGroup& processes, const ChildExit& exit, Progress& progress,
                           int64_t first, RunResult& result) {
  // Its last reports may still be on their way (on a loaded machine LCM's receive thread can lag
  // the exit by tens of ms): take them until the bus has been quiet for 50 ms, at most 0.5 s,
  // before naming its window.
  const auto drain_start = Clock::now();
  while (bus_->poll(0.05) && seconds_since(drain_start) < 0.5) take_reports(progress);
  take_reports(progress);
  std::string acts_as = exit.name;
  for (const auto& entry : scene_.participants) {
    if (entry.name == exit.name) acts_as = entry.acts_as;
  }
  const auto done = progress.done.find(acts_as);
  const int64_t window = done != progress.done.end() ? done->second + 1 : progress.completed + 1;
  if (exit.interrupted && progress.granted > first) {
    // Stopped from outside: save the state after the last window granted (no participant is
    // past it) before the run ends.
    book_.request(progress.granted, end_of(progress.granted));
    await_checkpoints(processes, progress.granted, true);
    if (book_.complete(progress.granted)) result.windows_completed = progress.granted;
  }
  throw Failure(fmt::format("{} during {} (see logs/{}.log)", exit.describe(), window_text(window),
                            exit.name));
}

double Coupler::run_windows(ProcessGroup& processes, RunResult& result) {
  // The coupler grants a few windows ahead and the participants go on as soon as their
  // partners' data is there: the coupler's own round trip leaves the critical path. An adaptive
  // window k + 1 is sized from the stable dt of window k, so it is planned once every
  // participant that limits the window has reported window k; the others (plants, debris:
  // sub-cycling) need not have finished it, and they get the grant while they compute.
  const bool adaptive = scene_.coupling.adaptive_window;
  const int64_t lookahead = 2;
  const double resend = scene_.coupling.resend_interval;
  double next_time = start_plan();
  const int64_t first = static_cast<int64_t>(plan_.size()) - 1;
  bool plan_complete = false;
  Progress progress;
  for (const auto& name : names_) progress.done[name] = first - 1;
  progress.completed = first - 1;
  progress.granted = first - 1;
  // The last window whose stable dt is known from every limiting participant.
  auto sized_through = [&] {
    int64_t lowest = std::numeric_limits<int64_t>::max();
    for (const auto& name : limiting_) {
      if (const auto found = progress.done.find(name); found != progress.done.end()) {
        lowest = std::min(lowest, found->second);
      }
    }
    return lowest;
  };
  auto last_broadcast = Clock::now();
  auto last_check = Clock::now();
  Clock::time_point window_one_started{};
  auto broadcast = [&] {
    std::vector<std::pair<double, double>> windows(plan_.begin() + (progress.completed + 1),
                                                   plan_.begin() + (progress.granted + 1));
    bus_->publish_window(
        Stamp{progress.completed + 1, windows.front().first, windows.front().second},
        window_t::COMMAND_ADVANCE, result.total_windows, "", windows,
        book_.pending(progress.granted));
    last_broadcast = Clock::now();
  };

  while (true) {
    const int64_t sized = adaptive ? sized_through() : std::numeric_limits<int64_t>::max();
    while (!plan_complete &&
           static_cast<int64_t>(plan_.size()) <= progress.completed + 2 + lookahead &&
           static_cast<int64_t>(plan_.size()) - 1 <= sized) {
      plan_complete = !plan_next_window(next_time, progress.stable_dt, result);
    }
    const int64_t last_planned = static_cast<int64_t>(plan_.size()) - 1;
    if (plan_complete && progress.completed == last_planned) break;
    const int64_t target = std::min(progress.completed + 1 + lookahead, last_planned);
    if (target > progress.granted) {
      progress.granted = target;
      broadcast();
    } else if (seconds_since(last_broadcast) >= resend) {
      broadcast();  // retransmission of the grant, and the coupler's heartbeat
    }
    bus_->poll(std::max(0.0, resend - seconds_since(last_broadcast)));
    const bool progressed = take_reports(progress);
    if (progressed) {
      int64_t lowest = std::numeric_limits<int64_t>::max();
      for (const auto& [name, window] : progress.done) lowest = std::min(lowest, window);
      if (lowest > progress.completed) {
        // The windows' wall time runs from the end of this run's first window (window 0, or
        // the first after a restart's checkpoint): the processes' start-up is not in it.
        if (progress.completed == first - 1 && lowest >= first) window_one_started = Clock::now();
        progress.completed = lowest;
        if (progress.completed >= 1) result.windows_completed = progress.completed;
      }
    }
    // Exits and silence are checked every few milliseconds, not after every message.
    if (seconds_since(last_check) >= 0.01 || !progressed) {
      last_check = Clock::now();
      for (const auto& exit : processes.poll_exits()) {
        stop_on_exit(processes, exit, progress, first, result);
      }
      for (const auto& name : names_) {
        const int64_t done = progress.done[name];
        if (done < progress.granted) check_silence({name}, window_text(done + 1));
      }
    }
  }
  await_checkpoints(processes, progress.granted, false);
  book_overhead(result, window_one_started, progress.completed,
                scene_.coupling.scheme == "serial-explicit");
  return next_time;
}

double Coupler::end_of(int64_t index) const {
  if (scene_.coupling.adaptive_window) return plan_[index].first + plan_[index].second;
  return std::min(static_cast<double>(index) * scene_.coupling.window, scene_.duration);
}

RunResult Coupler::run(ProcessGroup& processes) {
  RunResult result;
  result.total_windows = scene_.total_windows();
  started_ = Clock::now();
  double time = 0.0;
  int64_t index = 0;
  try {
    handshake(processes);
    time = scene_.coupling.is_implicit() ? run_implicit_windows(processes, result)
                                         : run_windows(processes, result);
    index = result.windows_completed + 1;
    finish(processes, result.windows_completed + 1, time);
    result.ok = true;
  } catch (const Failure& failure) {
    result.failure = failure.what();
    const auto reached = static_cast<std::size_t>(result.windows_completed);
    if (reached >= 1 && reached < plan_.size()) {
      time = plan_[reached].first + plan_[reached].second;
      index = result.windows_completed + 1;
    }
    for (int repeat = 0; repeat < 3; ++repeat) {
      bus_->publish_window(Stamp{index, time, 0.0}, window_t::COMMAND_ABORT, scene_.total_windows(),
                           result.failure);
      bus_->poll(0.01);
    }
    processes.terminate_all();
  }
  processes.wait_all(result.ok ? 10.0 : 2.0);
  result.simulated_time = time;
  result.wall_seconds = seconds_since(started_);
  for (const auto& name : names_) result.participants.push_back(reports_[name]);
  result.traffic = bus_->counters();
  result.checkpoints = book_.written();
  return result;
}

}  // namespace cosim::coupler

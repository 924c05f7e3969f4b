#include "progress.hpp"

#include <fmt/format.h>
#include <unistd.h>
#include <lcm/lcm-cpp.hpp>

#include <cmath>

#include "cosim/coupler/bus.hpp"
#include "cosim_msgs/window_t.hpp"

namespace cosim::tool {

namespace {
using Clock = std::chrono::steady_clock;

double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}
}  // namespace

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  if (seconds < 60) return fmt::format("{:.1f} s", seconds);
  const auto whole = static_cast<int64_t>(std::llround(seconds));
  if (whole < 3600) return fmt::format("{} min {:02d} s", whole / 60, whole % 60);
  return fmt::format("{} h {:02d} min", whole / 3600, (whole % 3600) / 60);
}

std::optional<double> estimate_remaining(const ProgressState& state) {
  const double done = state.simulated - state.stepping_from;
  const double left = state.duration - state.simulated;
  if (!state.started || done <= 0 || state.stepping_wall <= 0) return std::nullopt;
  return std::max(0.0, left) * state.stepping_wall / done;
}

std::string progress_line(const ProgressState& state) {
  if (!state.started) {
    return fmt::format("[{}] starting: waiting for every participant  wall {}", state.scene,
                       format_duration(state.wall));
  }
  const auto remaining = estimate_remaining(state);
  return fmt::format("[{}] window {}/{}  t = {:.4g} s of {:.4g} s  wall {}  ETA {}", state.scene,
                     state.window, state.total_windows, state.simulated, state.duration,
                     format_duration(state.wall),
                     remaining ? format_duration(*remaining) : std::string("--"));
}

ProgressMonitor::ProgressMonitor(Options options) : options_(std::move(options)) {
  terminal_ = ::isatty(::fileno(options_.out)) != 0;
  if (options_.interval <= 0) options_.interval = terminal_ ? 1.0 : 10.0;
  started_ = Clock::now();
  last_print_ = started_;
  state_.scene = options_.scene;
  state_.duration = options_.duration;
  state_.total_windows = options_.total_windows;
  thread_ = std::thread([this] { listen(); });
}

ProgressMonitor::~ProgressMonitor() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ProgressMonitor::print() {
  const std::string line = progress_line(state_);
  if (terminal_) {
    // Redrawn in place; blanks cover the end of a longer previous line.
    fmt::print(options_.out, "\r{:<100}", line);
  } else {
    fmt::print(options_.out, "{}\n", line);
  }
  std::fflush(options_.out);
  printed_any_ = true;
}

void ProgressMonitor::listen() {
  lcm::LCM lcm(options_.url);
  if (!lcm.good()) return;  // the run reports its own transport problems
  const int64_t run_id = options_.run_id;
  struct Handler {
    ProgressMonitor* monitor;
    int64_t run_id;
    void on_window(const lcm::ReceiveBuffer* buffer, const std::string&) {
      cosim_msgs::window_t message;
      if (message.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) < 0) return;
      if (message.header.run_id != run_id || message.header.sender != "coupler") return;
      if (message.command != cosim_msgs::window_t::COMMAND_ADVANCE) return;
      const auto now = Clock::now();
      std::lock_guard lock(monitor->mutex_);
      auto& state = monitor->state_;
      if (message.header.window < 1 || message.header.window < state.window) return;
      if (!state.started) {
        state.started = true;
        state.stepping_from = message.header.sim_time;
        monitor->stepping_started_ = now;
      }
      state.window = message.header.window;
      state.simulated = message.header.sim_time;
      // Adaptive windows may need more than the nominal count.
      state.total_windows = std::max(state.total_windows, message.total_windows);
      state.total_windows = std::max(state.total_windows, state.window);
    }
  } handler{this, run_id};
  lcm.subscribe(coupler::kWindowChannel, &Handler::on_window, &handler);
  bool announced = false;
  while (!stop_) {
    lcm.handleTimeout(100);
    const auto now = Clock::now();
    std::lock_guard lock(mutex_);
    state_.wall = seconds_between(started_, now);
    if (state_.started) state_.stepping_wall = seconds_between(stepping_started_, now);
    // A log gets its first line as soon as the windows start, then one per interval.
    const bool first = state_.started && !announced;
    if (first || seconds_between(last_print_, now) >= options_.interval) {
      announced = announced || state_.started;
      last_print_ = now;
      print();
    }
  }
}

void ProgressMonitor::finish(bool ok, int64_t windows_completed, double simulated_time,
                             double wall_seconds) {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(mutex_);
  if (terminal_ && printed_any_) fmt::print(options_.out, "\r{:<100}\r", "");
  fmt::print(options_.out, "[{}] {}: {}/{} windows, t = {:.4g} s of {:.4g} s, wall {}\n",
             state_.scene, ok ? "done" : "stopped", windows_completed,
             std::max(state_.total_windows, windows_completed), simulated_time, state_.duration,
             format_duration(wall_seconds));
  std::fflush(options_.out);
}

}  // namespace cosim::tool

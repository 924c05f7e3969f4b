#include "cosim/coupler/coupler.hpp"

#include "cosim/coupler/frame.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <thread>


namespace cosim::coupler {

namespace {
using Clock = std::chrono::steady_clock;
using cosim_msgs::status_t;
using cosim_msgs::window_t;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}
}  // namespace

Coupler::Coupler(const scenario::Scene& scene, CouplerOptions options)
    : scene_(scene), options_(std::move(options)) {
  BusOptions bus_options;
  bus_options.url = options_.url;
  bus_options.run_id = options_.run_id;
  bus_options.name = "coupler";
  bus_options.record_log = options_.event_log;
  bus_options.loss_probability = options_.loss_probability;
  bus_options.loss_seed = static_cast<uint64_t>(options_.run_id) + 17;
  bus_options.chunk_values = scene_.coupling.chunk_values;
  bus_ = std::make_unique<Bus>(bus_options);
  for (const auto& entry : scene_.participants) {
    names_.push_back(entry.acts_as);
    reports_[entry.acts_as].name = entry.acts_as;
  }
}

void Coupler::check_processes(ProcessGroup& processes, const std::string& during) {
  for (const auto& exit : processes.poll_exits()) {
    throw Failure(
        fmt::format("{} during {} (see logs/{}.log)", exit.describe(), during, exit.name));
  }
}

void Coupler::check_silence(const std::vector<std::string>& pending, const std::string& during) {
  for (const auto& name : pending) {
    const auto heard = bus_->last_heard(name);
    if (heard &&
        std::chrono::duration<double>(Clock::now() - *heard).count() > scene_.coupling.timeout) {
      throw Failure(fmt::format("'{}' stopped answering during {}: silent for more than {:.1f} s",
                                name, during, scene_.coupling.timeout));
    }
  }
}

void Coupler::collect(ProcessGroup& processes, const Collection& collection) {
  std::vector<std::string> pending = names_;
  auto last_broadcast = Clock::now() - std::chrono::hours(1);
  const auto start = Clock::now();
  const double resend = scene_.coupling.resend_interval;
  while (!pending.empty()) {
    // Rebroadcasting is both retransmission and the coupler's heartbeat. A participant still
    // initialising after a few seconds is asked less often.
    const double interval =
        collection.patient && seconds_since(start) >= 2.0 ? std::max(resend, 0.5) : resend;
    if (seconds_since(last_broadcast) >= interval) {
      bus_->publish_window(collection.stamp, collection.command, scene_.total_windows());
      last_broadcast = Clock::now();
    }
    bus_->poll(resend);
    auto& statuses = bus_->statuses();
    while (!statuses.empty()) {
      const status_t status = statuses.front();
      statuses.pop_front();
      const std::string& sender = status.header.sender;
      if (status.state == status_t::STATE_FAILED) {
        throw Failure(
            fmt::format("'{}' failed {}: {}", sender, collection.failed_during, status.message));
      }
      if (status.state != collection.answer) continue;
      if (collection.answer == status_t::STATE_DONE &&
          status.header.window != collection.stamp.window) {
        continue;
      }
      if (std::find(pending.begin(), pending.end(), sender) == pending.end()) continue;
      std::erase(pending, sender);
      if (collection.accept) collection.accept(status);
    }
    check_processes(processes, collection.during);
    check_silence(pending, collection.during);
    if (collection.check) collection.check(pending, seconds_since(start));
  }
}

void Coupler::handshake(ProcessGroup& processes) {
  Collection collection;
  collection.stamp = Stamp{0, 0.0, 0.0};
  collection.command = window_t::COMMAND_HANDSHAKE;
  collection.answer = status_t::STATE_READY;
  collection.during = "start-up";
  collection.failed_during = "while starting";
  collection.patient = true;
  // A participant still building its initial state (packing debris, say) sends heartbeats: it
  // may take as long as it needs while it keeps them coming. Only a participant never heard
  // from within the start-up timeout is reported.
  collection.check = [this](const std::vector<std::string>& pending, double waited) {
    if (waited <= options_.startup_timeout) return;
    std::vector<std::string> never_heard;
    for (const auto& name : pending) {
      if (!bus_->last_heard(name)) never_heard.push_back(name);
    }
    if (!never_heard.empty()) {
      throw Failure(fmt::format("participant(s) {} did not start within {:.0f} s",
                                fmt::join(never_heard, ", "), options_.startup_timeout));
    }
  };
  std::map<std::string, std::string> declared;
  collection.accept = [&declared](const status_t& status) {
    declared[status.header.sender] = status.message;
  };
  collect(processes, collection);
  // One world: every participant computes in the same frame under the same gravity, and 2D
  // ones stand for the same span. A mismatch stops the run before window 1.
  std::vector<std::pair<std::string, FrameDeclaration>> declarations;
  for (const auto& name : names_) {
    try {
      declarations.emplace_back(name, FrameDeclaration::from_json(declared[name], name));
    } catch (const std::exception& error) {
      throw Failure(error.what());
    }
  }
  if (const std::string problem = check_declarations(declarations, scene_.world);
      !problem.empty()) {
    throw Failure("participants disagree on the world: " + problem);
  }
}

void Coupler::run_window(ProcessGroup& processes, int64_t index, double time, double dt) {
  next_stable_dt_ = 0.0;
  Collection collection;
  collection.stamp = Stamp{index, time, dt};
  collection.command = window_t::COMMAND_ADVANCE;
  collection.answer = status_t::STATE_DONE;
  collection.during = fmt::format("window {} (t = {:.6g} s)", index, time);
  collection.failed_during = "in " + collection.during;
  collection.accept = [this](const status_t& status) {
    auto& report = reports_[status.header.sender];
    report.windows += 1;
    report.steps += status.steps;
    report.compute_seconds = status.compute_seconds;
    report.cpu_seconds = status.cpu_seconds;
    report.wait_seconds = status.wait_seconds;
    if (status.stable_dt > 0.0) {
      next_stable_dt_ =
          next_stable_dt_ > 0.0 ? std::min(next_stable_dt_, status.stable_dt) : status.stable_dt;
    }
  };
  collect(processes, collection);
  // The coupler records fields but never uses them: keep its memory flat over long runs.
  bus_->forget_fields_before(index);
}

void Coupler::finish(ProcessGroup& processes, int64_t index, double time) {
  Collection collection;
  collection.stamp = Stamp{index, time, 0.0};
  collection.command = window_t::COMMAND_FINISH;
  collection.answer = status_t::STATE_FINISHED;
  collection.during = "the final report";
  collection.failed_during = "while finishing";
  collection.accept = [this](const status_t& status) {
    auto& report = reports_[status.header.sender];
    report.metrics_json = status.message;
    report.compute_seconds = status.compute_seconds;
    report.cpu_seconds = status.cpu_seconds;
    report.wait_seconds = status.wait_seconds;
  };
  collect(processes, collection);
  for (int repeat = 0; repeat < 3; ++repeat) {
    bus_->publish_window(Stamp{index, time, 0.0}, window_t::COMMAND_RELEASE,
                         scene_.total_windows());
    bus_->poll(scene_.coupling.resend_interval);
  }
}

RunResult Coupler::run(ProcessGroup& processes) {
  RunResult result;
  result.total_windows = scene_.total_windows();
  started_ = Clock::now();
  double time = 0.0;
  int64_t index = 0;
  try {
    handshake(processes);
    // Window 0 exchanges initial states (dt = 0), then windows 1..N advance time.
    run_window(processes, 0, 0.0, 0.0);
    for (index = 1; index <= result.total_windows; ++index) {
      double dt = scene_.coupling.window;
      if (scene_.coupling.adaptive_window && next_stable_dt_ > 0.0) {
        dt = std::min(dt, next_stable_dt_);
      }
      // Land on the scene's duration; a remainder within round-off of the window is the window
      // (the window length, not a value 1e-19 shorter, is what the solvers were given before).
      const double remaining = scene_.duration - time;
      if (remaining < dt * (1.0 - 1e-9)) dt = remaining;
      if (dt <= scene_.duration * 1e-12) break;
      run_window(processes, index, time, dt);
      // Fixed windows: no round-off drift over long runs.
      time = scene_.coupling.adaptive_window
                 ? time + dt
                 : std::min(static_cast<double>(index) * scene_.coupling.window, scene_.duration);
      result.windows_completed = index;
      if (scene_.coupling.adaptive_window && index == result.total_windows &&
          time < scene_.duration * (1 - 1e-12)) {
        ++result.total_windows;  // adaptive windows may need more than the nominal count
      }
    }
    finish(processes, result.windows_completed + 1, time);
    result.ok = true;
  } catch (const Failure& failure) {
    result.failure = failure.what();
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
  return result;
}

}  // namespace cosim::coupler

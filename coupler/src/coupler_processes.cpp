// The coupler's dealings with the processes as a group, around the windows: the start
// handshake, collecting answers with the silence and exit checks, the checkpoints' answers
// and the end of the run (the windows themselves are in coupler.cpp).
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "cosim/coupler/coupler.hpp"
#include "cosim/coupler/frame.hpp"
#include "steady_clock.hpp"

namespace cosim::coupler {

namespace {
using cosim_msgs::status_t;
using cosim_msgs::window_t;
}  // namespace

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
      if (collection.broadcast) {
        collection.broadcast();
      } else {
        bus_->publish_window(collection.stamp, collection.command, scene_.total_windows());
      }
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
      if (status.state == status_t::STATE_CHECKPOINTED) {
        book_.answer(status);
        continue;
      }
      if (status.state != collection.answer) continue;
      if (collection.answer == status_t::STATE_DONE &&
          (status.header.window != collection.stamp.window ||
           status.header.iteration != collection.stamp.iteration)) {
        continue;
      }
      if (std::find(pending.begin(), pending.end(), sender) == pending.end()) continue;
      std::erase(pending, sender);
      if (collection.accept) collection.accept(status);
    }
    for (const auto& exit : processes.poll_exits()) {
      if (exit.interrupted && collection.on_interrupt) collection.on_interrupt();
      throw Failure(fmt::format("{} during {} (see logs/{}.log)", exit.describe(),
                                collection.during, exit.name));
    }
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
  for (const auto& [name, declaration] : declarations) {
    if (declaration.limits_window) limiting_.insert(name);
  }
}

void Coupler::await_checkpoints(ProcessGroup& processes, int64_t granted, bool interrupted) {
  auto last_broadcast = Clock::now() - std::chrono::hours(1);
  const double resend = scene_.coupling.resend_interval;
  book_.forget_after(granted);  // planned, but the run stops before them
  while (book_.outstanding()) {
    if (seconds_since(last_broadcast) >= resend) {
      const auto windows = book_.pending(granted);
      bus_->publish_window(Stamp{windows.front(), end_of(windows.front()), 0.0},
                           window_t::COMMAND_CHECKPOINT, scene_.total_windows(), "", {}, windows);
      last_broadcast = Clock::now();
    }
    bus_->poll(resend);
    auto& statuses = bus_->statuses();
    try {
      while (!statuses.empty()) {
        const status_t status = std::move(statuses.front());
        statuses.pop_front();
        if (status.state == status_t::STATE_CHECKPOINTED) book_.answer(status);
        if (status.state == status_t::STATE_FAILED) {
          throw Failure(fmt::format("'{}' failed while writing a checkpoint: {}",
                                    status.header.sender, status.message));
        }
      }
      if (!interrupted) check_processes(processes, "a checkpoint");
      // Stopped from outside, the run must end at once: a participant whose heartbeat (every
      // timeout / 10, at most 0.5 s) has stopped for 2.5 s is hung, and the run ends without
      // a checkpoint.
      const double limit =
          interrupted ? std::min(2.5, scene_.coupling.timeout) : scene_.coupling.timeout;
      for (const auto& name : book_.waiting_for()) {
        const auto heard = bus_->last_heard(name);
        if (heard && std::chrono::duration<double>(Clock::now() - *heard).count() > limit) {
          throw Failure(fmt::format("'{}' stopped answering during a checkpoint", name));
        }
      }
    } catch (const Failure& failure) {
      if (!interrupted) throw;
      spdlog::error("no checkpoint of the interrupted run: {}", failure.what());
      return;
    }
  }
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
  // One RELEASE, then stay a little to answer requests of anyone who lost it (the beacons show
  // it to them); leave as soon as every process has gone.
  bus_->publish_window(Stamp{index, time, 0.0}, window_t::COMMAND_RELEASE, scene_.total_windows());
  const auto released = Clock::now();
  const double linger = 3.0 * scene_.coupling.resend_interval;
  while (seconds_since(released) < linger) {
    bus_->poll(0.002);
    bool any_running = false;
    for (const auto& entry : scene_.participants) any_running |= processes.running(entry.name);
    if (!any_running) break;
  }
}

}  // namespace cosim::coupler

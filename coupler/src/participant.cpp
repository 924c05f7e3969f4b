#include "cosim/coupler/participant.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <ctime>

namespace cosim::coupler {

namespace {
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}
}  // namespace

Participant::Participant(ParticipantOptions options)
    : options_(std::move(options)), started_(Clock::now()) {
  BusOptions bus_options;
  bus_options.url = options_.url;
  bus_options.run_id = options_.run_id;
  bus_options.name = options_.name;
  bus_options.chunk_values = options_.chunk_values;
  bus_options.loss_probability = options_.loss_probability;
  bus_options.loss_seed = options_.loss_seed;
  bus_ = std::make_unique<Bus>(bus_options);
  current_.index = -1;
  current_done_ = true;
  heartbeat_ = std::thread([this] { heartbeat_loop(); });
}

Participant::~Participant() {
  stop_heartbeat_ = true;
  if (heartbeat_.joinable()) heartbeat_.join();
}

double Participant::cpu_seconds() const {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

double Participant::compute_seconds() const {
  return seconds_since(started_) - wait_seconds_;
}

Stamp Participant::stamp() const {
  return Stamp{current_.index, current_.time, current_.dt};
}

void Participant::publish_state(int8_t state, int steps, double stable_dt,
                                const std::string& message) {
  cosim_msgs::status_t status;
  status.state = state;
  status.steps = steps;
  status.compute_seconds = compute_seconds();
  status.cpu_seconds = cpu_seconds();
  status.wait_seconds = wait_seconds_;
  status.stable_dt = stable_dt;
  status.message = message;
  bus_->publish_status(stamp(), status);
}

void Participant::heartbeat_loop() {
  // A participant busy computing is silent on the bus; the heartbeat tells the coupler it is
  // alive, so only a hung or dead process is reported.
  const auto period = std::chrono::duration<double>(std::clamp(options_.timeout / 10.0, 0.05, 0.5));
  while (!stop_heartbeat_) {
    std::this_thread::sleep_for(period);
    if (stop_heartbeat_) break;
    cosim_msgs::status_t status;
    status.state = cosim_msgs::status_t::STATE_BUSY;
    status.steps = 0;
    status.compute_seconds = 0.0;
    status.cpu_seconds = 0.0;
    status.wait_seconds = 0.0;
    status.stable_dt = 0.0;
    try {
      bus_->publish_status(Stamp{heartbeat_window_.load(), 0.0, 0.0}, status);
    } catch (const std::exception& error) {
      spdlog::warn("heartbeat failed: {}", error.what());
    }
  }
}

void Participant::check_abort() {
  for (const auto& window : bus_->windows()) {
    if (window.command == cosim_msgs::window_t::COMMAND_ABORT) {
      throw CouplingError(fmt::format("the coupler aborted the run: {}", window.reason));
    }
  }
}

Window Participant::next_window() {
  if (!current_done_) {
    throw std::logic_error(fmt::format("window {} was not marked done", current_.index));
  }
  const auto wait_start = Clock::now();
  auto last_coupler_message = wait_start;
  while (true) {
    auto& windows = bus_->windows();
    while (!windows.empty()) {
      const cosim_msgs::window_t message = windows.front();
      windows.pop_front();
      last_coupler_message = Clock::now();
      const int64_t index = message.header.window;
      switch (message.command) {
        case cosim_msgs::window_t::COMMAND_HANDSHAKE:
          // Handshakes queued up while a long initialisation ran need one answer, not one each.
          if (seconds_since(last_ready_) >= options_.resend_interval) {
            publish_state(cosim_msgs::status_t::STATE_READY, 0, 0.0, declaration_);
            last_ready_ = Clock::now();
          }
          break;
        case cosim_msgs::window_t::COMMAND_ABORT:
          throw CouplingError(fmt::format("the coupler aborted the run: {}", message.reason));
        case cosim_msgs::window_t::COMMAND_RELEASE:
          break;
        case cosim_msgs::window_t::COMMAND_ADVANCE:
        case cosim_msgs::window_t::COMMAND_FINISH:
          if (index <= current_.index) {
            // The coupler missed our answer: repeat it.
            if (index == current_.index) {
              publish_state(cosim_msgs::status_t::STATE_DONE, last_steps_, last_stable_dt_, "");
            }
            break;
          }
          if (message.command == cosim_msgs::window_t::COMMAND_ADVANCE &&
              index != current_.index + 1) {
            throw CouplingError(fmt::format(
                "window {} arrived after window {}: a window was skipped", index, current_.index));
          }
          current_.index = index;
          current_.time = message.header.sim_time;
          current_.dt = message.header.dt;
          current_.total_windows = message.total_windows;
          current_.finish = message.command == cosim_msgs::window_t::COMMAND_FINISH;
          current_done_ = false;
          heartbeat_window_ = index;
          wait_seconds_ += seconds_since(wait_start);
          return current_;
      }
    }
    if (seconds_since(last_coupler_message) > options_.timeout) {
      throw CouplingError(
          fmt::format("the coupler has been silent for {:.1f} s while '{}' waited for window {}",
                      options_.timeout, options_.name, current_.index + 1));
    }
    bus_->poll(options_.resend_interval);
  }
}

void Participant::publish(const std::string& field, std::span<const double> values) {
  bus_->publish_field(stamp(), field, values);
}

std::vector<double> Participant::receive(const std::string& sender, const std::string& field,
                                         int64_t window) {
  const FieldKey key{sender, window, field};
  const auto wait_start = Clock::now();
  auto last_request = wait_start;
  while (true) {
    if (auto values = bus_->field_values(key)) {
      wait_seconds_ += seconds_since(wait_start);
      return std::move(*values);
    }
    check_abort();
    const auto heard = bus_->last_heard(sender);
    const auto silent_since = heard && *heard > wait_start ? *heard : wait_start;
    if (seconds_since(silent_since) > options_.timeout) {
      throw CouplingError(fmt::format(
          "'{}' has been silent for {:.1f} s while '{}' waited for its field '{}' of window {}",
          sender, options_.timeout, options_.name, field, window));
    }
    if (seconds_since(last_request) >= options_.resend_interval) {
      // Either some chunks were lost (ask for those) or none arrived yet (ask for all; a sender
      // that has not published yet ignores the request).
      bus_->request_resend(key, bus_->missing_chunks(key));
      last_request = Clock::now();
    }
    bus_->poll(options_.resend_interval);
  }
}

void Participant::done(int steps, double stable_dt) {
  last_steps_ = steps;
  last_stable_dt_ = stable_dt;
  total_steps_ += steps;
  current_done_ = true;
  publish_state(cosim_msgs::status_t::STATE_DONE, steps, stable_dt, "");
  // Partners never ask for fields more than a couple of windows old.
  bus_->forget_fields_before(current_.index - 3);
}

void Participant::finished(const std::string& metrics_json) {
  current_done_ = true;
  publish_state(cosim_msgs::status_t::STATE_FINISHED, 0, 0.0, metrics_json);
  // Stay until the coupler confirms every report arrived, repeating ours when asked again.
  auto last_coupler_message = Clock::now();
  while (seconds_since(last_coupler_message) < options_.timeout) {
    bus_->poll(options_.resend_interval);
    auto& windows = bus_->windows();
    while (!windows.empty()) {
      const auto command = windows.front().command;
      windows.pop_front();
      last_coupler_message = Clock::now();
      if (command == cosim_msgs::window_t::COMMAND_RELEASE ||
          command == cosim_msgs::window_t::COMMAND_ABORT) {
        return;
      }
      if (command == cosim_msgs::window_t::COMMAND_FINISH) {
        publish_state(cosim_msgs::status_t::STATE_FINISHED, 0, 0.0, metrics_json);
      }
    }
  }
}

void Participant::failed(const std::string& message) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    try {
      publish_state(cosim_msgs::status_t::STATE_FAILED, 0, 0.0, message);
    } catch (const std::exception&) {
      return;
    }
    bus_->poll(options_.resend_interval);
  }
}

}  // namespace cosim::coupler

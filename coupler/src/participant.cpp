#include "cosim/coupler/participant.hpp"

#include "steady_clock.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <ctime>

namespace cosim::coupler {

Participant::Participant(ParticipantOptions options)
    : options_(std::move(options)), started_(Clock::now()) {
  BusOptions bus_options;
  bus_options.url = options_.url;
  bus_options.run_id = options_.run_id;
  bus_options.name = options_.name;
  bus_options.chunk_values = options_.chunk_values;
  bus_options.loss_probability = options_.loss_probability;
  bus_options.loss_seed = options_.loss_seed;
  bus_options.resend_interval = options_.resend_interval;
  bus_ = std::make_unique<Bus>(bus_options);
  current_.index = -1;
  current_done_ = true;
  heartbeat_ = std::thread([this] { heartbeat_loop(); });
}

Participant::~Participant() {
  const auto counters = bus_->counters();
  spdlog::info(
      "transport: {} messages accepted, {} lost in injection, {} found missing, {} asked again, "
      "{} resent for others, retransmission timeout {:.2f} ms",
      counters.accepted, counters.dropped_injected, counters.gaps_detected,
      counters.resends_requested, counters.resends_served, 1e3 * bus_->retransmit_timeout());
  stop_heartbeat_ = true;
  bus_->wake();
  if (heartbeat_.joinable()) heartbeat_.join();
}

Participant::ApiTimer::ApiTimer(Participant& owner) : owner_(owner), start_(Clock::now()) {}

Participant::ApiTimer::~ApiTimer() {
  owner_.api_seconds_ += seconds_since(start_);
}

double Participant::physics_seconds() const {
  return seconds_since(started_) - api_seconds_;
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
  return Stamp{current_.index, current_.time, current_.dt, current_.iteration};
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
  status.physics_seconds = physics_seconds();
  bus_->publish_status(stamp(), status);
}

void Participant::heartbeat_loop() {
  // A participant busy computing is silent on the bus; the heartbeat tells the coupler it is
  // alive, so only a hung or dead process is reported.
  const auto period = std::chrono::duration<double>(std::clamp(options_.timeout / 10.0, 0.05, 0.5));
  while (!stop_heartbeat_) {
    // Between heartbeats this thread sends the bus's beacons, so a lost last message is found
    // quickly even while the main thread computes and does not poll.
    bus_->beacon_until(Clock::now() + std::chrono::duration_cast<Clock::duration>(period));
    if (stop_heartbeat_) break;
    cosim_msgs::status_t status;
    status.state = cosim_msgs::status_t::STATE_BUSY;
    status.steps = 0;
    status.compute_seconds = 0.0;
    status.cpu_seconds = 0.0;
    status.wait_seconds = 0.0;
    status.stable_dt = 0.0;
    status.physics_seconds = 0.0;
    try {
      bus_->publish_status(Stamp{heartbeat_window_.load(), 0.0, 0.0}, status);
    } catch (const std::exception& error) {
      spdlog::warn("heartbeat failed: {}", error.what());
    }
  }
}

void Participant::start_at(int64_t window) {
  current_.index = window - 1;
  current_done_ = true;
}

void Participant::take_checkpoint_requests(const cosim_msgs::window_t& message) {
  for (const int64_t window : message.checkpoint_windows) {
    if (const auto written = checkpoints_written_.find(window);
        written != checkpoints_written_.end()) {
      // Asked again: the answer may have been lost.
      if (message.command == cosim_msgs::window_t::COMMAND_CHECKPOINT &&
          seconds_since(last_checkpoint_answer_) >= options_.resend_interval) {
        publish_checkpointed(window, written->second);
        last_checkpoint_answer_ = Clock::now();
      }
      continue;
    }
    // A window already left behind cannot be saved any more; the coupler never asks for one.
    if (window >= current_.index || (options_.rollback && window == current_.index - 1)) {
      checkpoint_requests_.insert(window);
    }
  }
}

void Participant::checkpointed(const std::string& description_json, int64_t window) {
  const ApiTimer timer(*this);
  checkpoints_written_[window] = description_json;
  if (window == current_.index) {
    publish_state(cosim_msgs::status_t::STATE_CHECKPOINTED, 0, 0.0, description_json);
  } else {
    publish_checkpointed(window, description_json);  // of the window before (rolled back)
  }
  last_checkpoint_answer_ = Clock::now();
}

void Participant::publish_checkpointed(int64_t window, const std::string& description_json) {
  cosim_msgs::status_t status{};
  status.state = cosim_msgs::status_t::STATE_CHECKPOINTED;
  status.message = description_json;
  status.field_count = 0;
  bus_->publish_status(Stamp{window, current_.time, 0.0}, status);
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
  const ApiTimer timer(*this);
  const auto wait_start = Clock::now();
  auto last_coupler_message = wait_start;
  if (current_.index < 0 && last_ready_ == Clock::time_point{}) {
    // The coupler is usually up before us: say we are ready at once rather than at its next
    // handshake broadcast.
    publish_state(cosim_msgs::status_t::STATE_READY, 0, 0.0, declaration_);
    last_ready_ = Clock::now();
  }
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
        case cosim_msgs::window_t::COMMAND_CHECKPOINT:
          take_checkpoint_requests(message);
          break;
        case cosim_msgs::window_t::COMMAND_ADVANCE: {
          take_checkpoint_requests(message);
          // A grant of one or more windows; older grants repeat what newer ones say.
          const auto granted = static_cast<std::size_t>(std::max(0, message.window_count));
          // Implicit schemes grant one iteration of one window at a time.
          const int32_t iteration = message.header.iteration;
          auto grant = [&](int64_t window, double time, double dt) {
            if (std::pair(window, iteration) <= std::pair(current_.index, current_.iteration)) {
              return;
            }
            Window granted_window{window, time, dt, message.total_windows, false};
            granted_window.iteration = iteration;
            granted_window.accepted_iteration = message.accepted_iteration;
            granted_.try_emplace({window, iteration}, granted_window);
          };
          if (granted == 0) grant(index, message.header.sim_time, message.header.dt);
          for (std::size_t i = 0;
               i < granted && i < message.window_times.size() && i < message.window_dts.size();
               ++i) {
            grant(index + static_cast<int64_t>(i), message.window_times[i], message.window_dts[i]);
          }
          break;
        }
        case cosim_msgs::window_t::COMMAND_FINISH:
          finish_ = Window{index, message.header.sim_time, message.header.dt, message.total_windows,
                           true};
          break;
      }
    }
    if (current_done_ && checkpoint_requests_.erase(current_.index) > 0) {
      Window checkpoint = current_;
      checkpoint.checkpoint = true;
      wait_seconds_ += seconds_since(wait_start);
      return checkpoint;
    }
    if (current_done_ && options_.rollback && checkpoint_requests_.erase(current_.index - 1) > 0) {
      Window checkpoint = current_;
      checkpoint.index = current_.index - 1;
      checkpoint.checkpoint = true;
      checkpoint.rolled_back = true;
      wait_seconds_ += seconds_since(wait_start);
      return checkpoint;
    }
    std::optional<Window> next;
    if (const auto again = granted_.find({current_.index, current_.iteration + 1});
        again != granted_.end()) {
      next = again->second;
    } else if (const auto found = granted_.find({current_.index + 1, 0}); found != granted_.end()) {
      next = found->second;
    } else if (finish_ && finish_->index == current_.index + 1) {
      next = finish_;
    }
    if (next) {
      std::erase_if(granted_, [&](const auto& item) {
        return item.first <= std::pair(next->index, next->iteration);
      });
      if (options_.rollback && next->index != current_.index) {
        previous_window_fields_ = std::move(window_fields_);
      }
      current_ = *next;
      current_done_ = false;
      window_fields_.clear();
      heartbeat_window_ = current_.index;
      wait_seconds_ += seconds_since(wait_start);
      return current_;
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
  const ApiTimer timer(*this);
  cosim_msgs::field_t entry;
  entry.name = field;
  entry.total_values = static_cast<int64_t>(values.size());
  if (pending_inline_values_ + values.size() <= static_cast<std::size_t>(options_.chunk_values)) {
    entry.chunk_count = 0;
    entry.value_count = static_cast<int32_t>(values.size());
    entry.values.assign(values.begin(), values.end());
    pending_inline_values_ += values.size();
  } else {
    entry.chunk_count = bus_->publish_field(stamp(), field, values);
    entry.value_count = 0;
  }
  pending_fields_.push_back(std::move(entry));
  window_fields_.emplace_back(field, std::vector<double>(values.begin(), values.end()));
}

void Participant::flush_inline_fields() {
  // A solver that waits for a partner after publishing may be what the partner waits for:
  // send what is held for the report now instead.
  for (auto& entry : pending_fields_) {
    if (entry.chunk_count != 0) continue;
    entry.chunk_count = bus_->publish_field(stamp(), entry.name, entry.values);
    entry.values.clear();
    entry.value_count = 0;
  }
  pending_inline_values_ = 0;
}

std::vector<double> Participant::receive(const std::string& sender, const std::string& field,
                                         int64_t window, int32_t iteration) {
  const ApiTimer timer(*this);
  const FieldKey key{sender, window, field, iteration};
  const bool holding = std::any_of(pending_fields_.begin(), pending_fields_.end(),
                                   [](const auto& entry) { return entry.chunk_count == 0; });
  if (holding && !bus_->has_field(key)) flush_inline_fields();
  const auto wait_start = Clock::now();
  auto last_request = wait_start;
  bool warned = false;
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
    if (!warned && seconds_since(wait_start) > std::max(1.0, options_.timeout / 2)) {
      spdlog::warn("still waiting for '{}' field '{}' of window {}: {}", sender, field, window,
                   bus_->describe_peer(sender));
      warned = true;
    }
    // Lost messages are asked for by the bus as soon as a sequence gap or a beacon shows them;
    // a whole resend interval without the field asks for it by name as well.
    if (seconds_since(last_request) >= options_.resend_interval) {
      bus_->request_field(key);
      last_request = Clock::now();
    }
    bus_->poll(options_.resend_interval);
  }
}

void Participant::done(int steps, double stable_dt) {
  const ApiTimer timer(*this);
  last_steps_ = steps;
  last_stable_dt_ = stable_dt;
  total_steps_ += steps;
  current_done_ = true;
  cosim_msgs::status_t status;
  status.state = cosim_msgs::status_t::STATE_DONE;
  status.steps = steps;
  status.compute_seconds = compute_seconds();
  status.cpu_seconds = cpu_seconds();
  status.wait_seconds = wait_seconds_;
  status.stable_dt = stable_dt;
  status.physics_seconds = physics_seconds();
  status.fields = std::move(pending_fields_);
  pending_fields_.clear();
  pending_inline_values_ = 0;
  bus_->publish_status(stamp(), std::move(status));
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

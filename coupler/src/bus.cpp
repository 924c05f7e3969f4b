#include "cosim/coupler/bus.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "cosim/coupler/event_log.hpp"
#include "cosim_msgs/header_t.hpp"
#include "steady_clock.hpp"

namespace cosim::coupler {

namespace {
// Own messages always kept for resends, however old their window.
constexpr std::size_t kCachedMessagesFloor = 256;
// Most sequence numbers one resend request names.
constexpr std::size_t kRequestBatch = 512;
// Bounds of the adaptive retransmission timeout [s].
constexpr double kMinimumTimeout = 0.3e-3;
}  // namespace

int64_t protocol_schema_hash() {
  // Order-dependent mix so that swapping two types' definitions also changes the hash.
  uint64_t hash = 0x9e3779b97f4a7c15ULL;
  for (const int64_t type_hash :
       {cosim_msgs::header_t::getHash(), cosim_msgs::window_t::getHash(),
        cosim_msgs::status_t::getHash(), cosim_msgs::field_chunk_t::getHash(),
        cosim_msgs::resend_request_t::getHash(), cosim_msgs::beacon_t::getHash()}) {
    hash ^= static_cast<uint64_t>(type_hash) + 0x9e3779b97f4a7c15ULL + (hash << 6) + (hash >> 2);
  }
  return static_cast<int64_t>(hash);
}

std::string run_lcm_url(int64_t run_id, int ttl) {
  const uint64_t mixed = static_cast<uint64_t>(run_id) * 0x9e3779b97f4a7c15ULL;
  const int port = 20000 + static_cast<int>(mixed % 40000);
  const int group_low = 1 + static_cast<int>((mixed >> 20) % 250);
  return fmt::format("udpm://239.255.76.{}:{}?ttl={}&recv_buf_size=4194304", group_low, port, ttl);
}

bool peek_header(const void* data, int size, int64_t type_hash, cosim_msgs::header_t& header) {
  // Every message type of the protocol starts with its header, right after the type hash.
  int64_t hash = 0;
  if (__int64_t_decode_array(data, 0, size, &hash, 1) < 0 || hash != type_hash) return false;
  return header._decodeNoHash(data, 8, size - 8) >= 0;
}

RecordMode parse_record_mode(const std::string& text) {
  if (text == "all") return RecordMode::all;
  if (text == "control") return RecordMode::control;
  if (text == "none") return RecordMode::none;
  throw std::runtime_error(fmt::format("--record '{}': expected all, control or none", text));
}

const char* record_mode_name(RecordMode mode) {
  switch (mode) {
    case RecordMode::all:
      return "all";
    case RecordMode::control:
      return "control";
    case RecordMode::none:
      return "none";
  }
  return "all";
}

Bus::Bus(BusOptions options)
    : options_(std::move(options)),
      lcm_(options_.url),
      schema_hash_(protocol_schema_hash()),
      loss_random_(options_.loss_seed) {
  if (!lcm_.good()) {
    throw std::runtime_error(fmt::format(
        "cannot open LCM at '{}' (is there a multicast route? `ip route add 224.0.0.0/4 dev lo`)",
        options_.url));
  }
  own_names_.insert(options_.name);
  if (!options_.record_log.empty() && options_.record_mode != RecordMode::none) {
    recorder_ = std::make_unique<EventRecorder>(options_.record_log, options_.record_mode);
  }
  lcm::Subscription* subscription = lcm_.subscribe(".*", &Bus::on_message, this);
  // Bursts of chunks arrive while a solver computes; never let the queue drop them.
  subscription->setQueueCapacity(100000);
}

Bus::~Bus() = default;

cosim_msgs::header_t Bus::make_header(const Stamp& stamp, const std::string& sender) {
  cosim_msgs::header_t header;
  header.run_id = options_.run_id;
  header.sender = sender;
  header.sequence = next_sequence_[sender]++;
  header.window = stamp.window;
  header.iteration = stamp.iteration;
  header.sim_time = stamp.sim_time;
  header.dt = stamp.dt;
  header.schema_hash = schema_hash_;
  return header;
}

void Bus::send_raw(const std::string& channel, const std::vector<uint8_t>& bytes) {
  if (lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())) != 0) {
    throw std::runtime_error(fmt::format("LCM publish on {} failed ({})", channel, options_.url));
  }
}

// Caller holds publish_mutex_.
template <class Message>
void Bus::publish_sequenced(const std::string& channel, const Message& message) {
  Cached cached;
  cached.channel = channel;
  cached.window = message.header.window;
  cached.bytes.resize(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(cached.bytes.data(), 0, static_cast<int>(cached.bytes.size()));
  send_raw(channel, cached.bytes);
  auto& mine = cache_[message.header.sender];
  const int64_t newest_window = cached.window;
  mine.emplace(message.header.sequence, std::move(cached));
  // Keep the newest windows (partners never ask for older ones) and a floor of messages.
  while (mine.size() > kCachedMessagesFloor &&
         mine.begin()->second.window < newest_window - options_.cached_windows) {
    mine.erase(mine.begin());
  }
  // A lost last message of a burst shows no gap to anyone: beacons name it soon after.
  beacon_step_ = std::clamp(rto_.load(), 0.5e-3, options_.resend_interval);
  const auto due = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(beacon_step_));
  // Wake the heartbeat thread only when it sleeps past the new beacon: a context switch per
  // message would cost more than the message.
  const bool sooner = due < next_beacon_;
  next_beacon_ = due;
  if (sooner) beacon_cv_.notify_all();
}

double Bus::backoff_cap() const {
  // Injected or random loss is not congestion: keep asking at a pace tied to the measured round
  // trip, never slower than the scene's resend interval.
  return std::min(options_.resend_interval, std::max(2e-3, 16.0 * rto_.load()));
}

template <class Message>
void Bus::publish_unsequenced(const std::string& channel, const Message& message) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  send_raw(channel, bytes);
}

void Bus::publish_window(const Stamp& stamp, int8_t command, int64_t total_windows,
                         const std::string& reason,
                         const std::vector<std::pair<double, double>>& windows,
                         const std::vector<int64_t>& checkpoints, int32_t accepted_iteration) {
  std::lock_guard lock(publish_mutex_);
  cosim_msgs::window_t message;
  message.header = make_header(stamp, options_.name);
  message.command = command;
  message.total_windows = total_windows;
  message.reason = reason;
  message.window_count = static_cast<int32_t>(windows.size());
  for (const auto& [time, dt] : windows) {
    message.window_times.push_back(time);
    message.window_dts.push_back(dt);
  }
  message.checkpoint_count = static_cast<int32_t>(checkpoints.size());
  message.checkpoint_windows = checkpoints;
  message.accepted_iteration = accepted_iteration;
  publish_sequenced(kWindowChannel, message);
}

void Bus::publish_status(const Stamp& stamp, cosim_msgs::status_t status) {
  std::lock_guard lock(publish_mutex_);
  status.header = make_header(stamp, options_.name);
  status.field_count = static_cast<int32_t>(status.fields.size());
  for (const auto& field : status.fields) {
    if (field.chunk_count == 0) {
      field_sequences_[FieldKey{status.header.sender, status.header.window, field.name,
                                status.header.iteration}] = {status.header.sequence};
    }
  }
  publish_sequenced(kStatusChannel, status);
  // A report ends a burst: when partners have lately asked us for lost messages, name its
  // sequence number at once in a beacon, so a lost report is found without waiting for the
  // first timed beacon. A loss-free network never pays for this.
  if (last_asked_of_us_ != Clock::time_point{} &&
      seconds_between(last_asked_of_us_, Clock::now()) < 1.0) {
    send_beacon_locked();
  }
}

int32_t Bus::publish_field(const Stamp& stamp, const std::string& field,
                           std::span<const double> values, const std::string& as_sender) {
  std::lock_guard lock(publish_mutex_);
  const std::string sender = as_sender.empty() ? options_.name : as_sender;
  own_names_.insert(sender);
  const auto chunk_values = static_cast<std::size_t>(options_.chunk_values);
  const auto chunk_count = static_cast<int32_t>(
      std::max<std::size_t>(1, (values.size() + chunk_values - 1) / chunk_values));
  cosim_msgs::field_chunk_t chunk;
  for (int32_t index = 0; index < chunk_count; ++index) {
    const std::size_t begin = index * chunk_values;
    const std::size_t end = std::min(values.size(), begin + chunk_values);
    chunk.header = make_header(stamp, sender);
    chunk.field = field;
    chunk.chunk_index = index;
    chunk.chunk_count = chunk_count;
    chunk.total_values = static_cast<int64_t>(values.size());
    chunk.offset = static_cast<int64_t>(begin);
    chunk.value_count = static_cast<int32_t>(end - begin);
    chunk.values.assign(values.begin() + static_cast<std::ptrdiff_t>(begin),
                        values.begin() + static_cast<std::ptrdiff_t>(end));
    field_sequences_[FieldKey{sender, stamp.window, field, stamp.iteration}].push_back(
        chunk.header.sequence);
    publish_sequenced(kFieldChannel, chunk);
  }
  const int64_t oldest_kept = stamp.window - options_.cached_windows;
  std::erase_if(field_sequences_,
                [&](const auto& item) { return item.first.window < oldest_kept; });
  return chunk_count;
}

// Caller holds publish_mutex_.
void Bus::send_beacon_locked() {
  cosim_msgs::beacon_t beacon;
  beacon.header = cosim_msgs::header_t{};
  beacon.header.run_id = options_.run_id;
  beacon.header.sender = options_.name;
  beacon.header.sequence = -1;
  beacon.header.schema_hash = schema_hash_;
  for (const auto& [name, next] : next_sequence_) {
    beacon.names.push_back(name);
    beacon.last_sequences.push_back(next - 1);
    const auto& mine = cache_[name];
    beacon.oldest_cached.push_back(mine.empty() ? next : mine.begin()->first);
  }
  beacon.count = static_cast<int32_t>(beacon.names.size());
  publish_unsequenced(kBeaconChannel, beacon);
  std::lock_guard counters(counters_mutex_);
  ++counters_.beacons_sent;
}

void Bus::beacon_if_due() {
  std::lock_guard lock(publish_mutex_);
  const auto now = Clock::now();
  if (now < next_beacon_) return;
  send_beacon_locked();
  // Back off: a partner that got everything has nothing to do with more beacons.
  beacon_step_ = std::min(1.5 * beacon_step_, backoff_cap());
  next_beacon_ = now + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(beacon_step_));
}

void Bus::beacon_until(Clock::time_point deadline) {
  std::unique_lock lock(publish_mutex_);
  while (!woken_) {
    const auto now = Clock::now();
    if (now >= next_beacon_) {
      lock.unlock();
      beacon_if_due();
      lock.lock();
      continue;
    }
    if (now >= deadline) break;
    beacon_cv_.wait_until(lock, std::min(deadline, next_beacon_));
  }
}

void Bus::wake() {
  {
    std::lock_guard lock(publish_mutex_);
    woken_ = true;
  }
  beacon_cv_.notify_all();
}

void Bus::rtt_sample(double seconds) {
  // Jacobson/Karels, as TCP: the timeout follows the measured round trip of a resend.
  rttvar_ = 0.75 * rttvar_ + 0.25 * std::abs(seconds - srtt_);
  srtt_ = 0.875 * srtt_ + 0.125 * seconds;
  rto_ = std::clamp(srtt_ + 4.0 * rttvar_, kMinimumTimeout, options_.resend_interval);
}

void Bus::request_missing() {
  if (!missing_pending_) return;
  const auto now = Clock::now();
  if (now < next_request_) return;
  next_request_ = Clock::time_point::max();
  missing_pending_ = false;
  const double give_up = std::max(1.0, 20.0 * options_.resend_interval);
  for (auto& [sender, peer] : peers_) {
    std::vector<int64_t> due;
    for (auto it = peer.missing.begin(); it != peer.missing.end();) {
      Missing& missing = it->second;
      if (seconds_between(missing.first_missed, now) > give_up) {
        // The sender cannot have it any more; its silence is reported elsewhere.
        it = peer.missing.erase(it);
        continue;
      }
      missing_pending_ = true;
      const auto due_at = missing.asked + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(missing.backoff));
      if (missing.asked == Clock::time_point{} || now >= due_at) {
        if (due.size() < kRequestBatch) {
          due.push_back(it->first);
          missing.backoff = missing.asked == Clock::time_point{}
                                ? rto_.load()
                                : std::min(1.5 * missing.backoff, backoff_cap());
          missing.asked = now;
        }
        next_request_ = std::min(next_request_, now);
      } else {
        next_request_ = std::min(next_request_, due_at);
      }
      ++it;
    }
    if (due.empty()) continue;
    cosim_msgs::resend_request_t request;
    request.header.run_id = options_.run_id;
    request.header.sender = options_.name;
    request.header.sequence = -1;
    request.header.schema_hash = schema_hash_;
    request.target = sender;
    request.count = static_cast<int32_t>(due.size());
    request.sequences = std::move(due);
    request.field_window = 0;
    request.field_iteration = 0;
    {
      std::lock_guard lock(publish_mutex_);
      publish_unsequenced(kResendChannel, request);
    }
    std::lock_guard counters(counters_mutex_);
    counters_.resends_requested += request.count;
  }
  // Entries asked just now are due again after their backoff.
  for (auto& [sender, peer] : peers_) {
    for (const auto& [sequence, missing] : peer.missing) {
      next_request_ = std::min(next_request_,
                               missing.asked + std::chrono::duration_cast<Clock::duration>(
                                                   std::chrono::duration<double>(missing.backoff)));
    }
  }
}

void Bus::request_field(const FieldKey& key) {
  cosim_msgs::resend_request_t request;
  request.header.run_id = options_.run_id;
  request.header.sender = options_.name;
  request.header.sequence = -1;
  request.header.schema_hash = schema_hash_;
  request.target = key.sender;
  request.count = 0;
  request.field = key.field;
  request.field_window = key.window;
  request.field_iteration = key.iteration;
  std::lock_guard lock(publish_mutex_);
  publish_unsequenced(kResendChannel, request);
}

bool Bus::poll(double seconds) {
  accepted_since_poll_ = false;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(std::max(0.0, seconds)));
  while (true) {
    // Take everything already queued, then ask at once for what that showed missing.
    while (true) {
      const int handled = lcm_.handleTimeout(0);
      if (handled < 0) throw std::runtime_error("LCM receive failed on " + options_.url);
      if (handled == 0) break;
    }
    request_missing();
    beacon_if_due();
    if (accepted_since_poll_) return true;
    const auto now = Clock::now();
    if (now >= deadline) return false;
    // Sleep in the kernel until a message arrives or a timer is due: no polling sleeps.
    Clock::time_point wake = deadline;
    {
      std::lock_guard lock(publish_mutex_);
      wake = std::min(wake, next_beacon_);
    }
    if (missing_pending_) wake = std::min(wake, next_request_);
    const double wait = std::max(0.0, seconds_between(now, wake));
    timespec timeout{};
    timeout.tv_sec = static_cast<time_t>(wait);
    timeout.tv_nsec = static_cast<long>((wait - std::floor(wait)) * 1e9);
    pollfd descriptor{lcm_.getFileno(), POLLIN, 0};
    ppoll(&descriptor, 1, &timeout, nullptr);
  }
}

}  // namespace cosim::coupler

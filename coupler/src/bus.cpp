#include "cosim/coupler/bus.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "cosim/coupler/event_log.hpp"
#include "cosim_msgs/header_t.hpp"

namespace cosim::coupler {

namespace {
// Gaps wider than this are not a lost message but a sender we started hearing late.
constexpr int64_t kLargestGap = 4096;
// Own messages always kept for resends, however old their window.
constexpr std::size_t kCachedMessagesFloor = 256;
// Most sequence numbers one resend request names.
constexpr std::size_t kRequestBatch = 512;
// Bounds of the adaptive retransmission timeout [s].
constexpr double kMinimumTimeout = 0.3e-3;

double seconds_between(std::chrono::steady_clock::time_point from,
                       std::chrono::steady_clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}
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

void Bus::on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  // The recorder hears everything that reaches this host, before injected loss: the loss
  // stands for this process's network, not for what happened.
  if (recorder_) recorder_->record(channel, buffer->data, buffer->data_size, buffer->recv_utime);
  const bool dropped_on_purpose = drop_next_ > 0;
  if (dropped_on_purpose) --drop_next_;
  if (dropped_on_purpose || (options_.loss_probability > 0.0 &&
                             std::uniform_real_distribution<double>(0.0, 1.0)(loss_random_) <
                                 options_.loss_probability)) {
    std::lock_guard counters(counters_mutex_);
    ++counters_.dropped_injected;
    return;
  }
  const auto size = static_cast<int>(buffer->data_size);
  if (channel == kWindowChannel) {
    cosim_msgs::window_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !accept_sequenced(message.header)) return;
    windows_.push_back(std::move(message));
  } else if (channel == kStatusChannel) {
    cosim_msgs::status_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !check_run(message.header)) return;
    const bool fresh = accept_sequenced(message.header);
    // A repeated report still delivers fields we lack (the fallback request asks for those).
    if (fresh || !message.fields.empty()) on_status(std::move(message), fresh);
  } else if (channel == kFieldChannel) {
    if (!options_.keep_fields) {
      // Only the header matters here (sequence numbers): skip decoding the values.
      cosim_msgs::header_t header;
      if (peek_header(buffer->data, size, cosim_msgs::field_chunk_t::getHash(), header)) {
        accept_sequenced(header);
      }
      return;
    }
    cosim_msgs::field_chunk_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !check_run(message.header)) return;
    accept_sequenced(message.header);
    on_field(message);  // idempotent: a repeated chunk fills only what is missing
  } else if (channel == kResendChannel) {
    cosim_msgs::resend_request_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !check_run(message.header)) return;
    on_resend(message);
  } else if (channel == kBeaconChannel) {
    cosim_msgs::beacon_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !check_run(message.header)) return;
    on_beacon(message);
  }
}

bool Bus::check_run(const cosim_msgs::header_t& header) {
  if (header.run_id != options_.run_id) {
    std::lock_guard counters(counters_mutex_);
    ++counters_.dropped_foreign;
    return false;
  }
  if (header.schema_hash != schema_hash_) {
    {
      std::lock_guard counters(counters_mutex_);
      ++counters_.dropped_foreign;
    }
    spdlog::warn("dropped a message from '{}': its schema hash {} differs from ours {}",
                 header.sender, header.schema_hash, schema_hash_);
    return false;
  }
  return !own_names_.contains(header.sender);
}

void Bus::note_missing(Peer& peer, int64_t from, int64_t to) {
  const auto now = Clock::now();
  for (int64_t sequence = from; sequence <= to; ++sequence) {
    auto [it, inserted] = peer.missing.try_emplace(sequence);
    if (inserted) {
      it->second.first_missed = now;
      std::lock_guard counters(counters_mutex_);
      ++counters_.gaps_detected;
    }
  }
  missing_pending_ = true;
  next_request_ = std::min(next_request_, now);
}

bool Bus::accept_sequenced(const cosim_msgs::header_t& header) {
  if (!check_run(header)) return false;
  Peer& peer = peers_[header.sender];
  const int64_t sequence = header.sequence;
  if (peer.highest < 0 || sequence > peer.highest + kLargestGap) {
    // First contact: what the sender published before we listened is not a gap.
    peer.highest = sequence;
  } else if (sequence > peer.highest) {
    if (sequence > peer.highest + 1) note_missing(peer, peer.highest + 1, sequence - 1);
    peer.highest = sequence;
  } else if (const auto missing = peer.missing.find(sequence); missing != peer.missing.end()) {
    if (missing->second.asked != Clock::time_point{}) {
      rtt_sample(seconds_between(missing->second.asked, Clock::now()));
    }
    peer.missing.erase(missing);
  } else {
    std::lock_guard counters(counters_mutex_);
    ++counters_.dropped_duplicate;
    return false;
  }
  last_heard_[header.sender] = Clock::now();
  {
    std::lock_guard counters(counters_mutex_);
    ++counters_.accepted;
  }
  accepted_since_poll_ = true;
  return true;
}

void Bus::on_status(cosim_msgs::status_t status, bool fresh) {
  if (options_.keep_fields) {
    for (auto& field : status.fields) {
      if (field.chunk_count != 0) continue;  // arrives as chunks
      if (field.value_count != field.total_values) {
        spdlog::warn("dropped a malformed field '{}' from '{}' (window {})", field.name,
                     status.header.sender, status.header.window);
        continue;
      }
      const FieldKey key{status.header.sender, status.header.window, field.name,
                         status.header.iteration};
      completed_.try_emplace(key, std::move(field.values));
    }
  }
  if (!fresh) return;
  // The values now live in the completed fields; the report itself stays small.
  status.fields.clear();
  status.field_count = 0;
  statuses_.push_back(std::move(status));
}

void Bus::on_field(const cosim_msgs::field_chunk_t& chunk) {
  const FieldKey key{chunk.header.sender, chunk.header.window, chunk.field, chunk.header.iteration};
  if (completed_.contains(key)) return;
  if (chunk.chunk_count <= 0 || chunk.chunk_index < 0 || chunk.chunk_index >= chunk.chunk_count ||
      chunk.offset < 0 || chunk.offset + chunk.value_count > chunk.total_values) {
    spdlog::warn("dropped a malformed chunk of field '{}' from '{}' (window {})", chunk.field,
                 chunk.header.sender, chunk.header.window);
    return;
  }
  Assembly& assembly = assemblies_[key];
  if (assembly.chunk_count == 0) {
    assembly.chunk_count = chunk.chunk_count;
    assembly.total_values = chunk.total_values;
    assembly.values.assign(static_cast<std::size_t>(chunk.total_values), 0.0);
    assembly.received.assign(static_cast<std::size_t>(chunk.chunk_count), false);
  }
  if (assembly.chunk_count != chunk.chunk_count || assembly.total_values != chunk.total_values) {
    spdlog::warn("field '{}' from '{}' (window {}) changed shape between chunks; dropped chunk",
                 chunk.field, chunk.header.sender, chunk.header.window);
    return;
  }
  if (assembly.received[chunk.chunk_index]) return;
  std::copy(chunk.values.begin(), chunk.values.end(), assembly.values.begin() + chunk.offset);
  assembly.received[chunk.chunk_index] = true;
  if (++assembly.received_count == assembly.chunk_count) {
    completed_[key] = std::move(assembly.values);
    assemblies_.erase(key);
  }
}

void Bus::on_resend(const cosim_msgs::resend_request_t& request) {
  if (!own_names_.contains(request.target)) return;
  std::lock_guard lock(publish_mutex_);
  last_asked_of_us_ = Clock::now();
  const auto& mine = cache_[request.target];
  bool gone = false;
  int64_t served = 0;
  std::vector<int64_t> sequences = request.sequences;
  if (!request.field.empty()) {
    const auto found = field_sequences_.find(
        FieldKey{request.target, request.field_window, request.field, request.field_iteration});
    if (found != field_sequences_.end()) {
      sequences.insert(sequences.end(), found->second.begin(), found->second.end());
    }
  }
  for (const int64_t sequence : sequences) {
    const auto cached = mine.find(sequence);
    if (cached == mine.end()) {
      gone = true;
      continue;
    }
    send_raw(cached->second.channel, cached->second.bytes);
    ++served;
  }
  // Tell the requester what we still have, so it stops asking for what is gone.
  if (gone) send_beacon_locked();
  std::lock_guard counters(counters_mutex_);
  counters_.resends_served += served;
}

void Bus::on_beacon(const cosim_msgs::beacon_t& beacon) {
  const auto count = std::min<std::size_t>(
      {beacon.names.size(), beacon.last_sequences.size(), beacon.oldest_cached.size()});
  for (std::size_t i = 0; i < count; ++i) {
    if (own_names_.contains(beacon.names[i])) continue;
    const auto found = peers_.find(beacon.names[i]);
    if (found == peers_.end()) continue;  // never heard: nothing of it can be missing
    Peer& peer = found->second;
    std::erase_if(peer.missing,
                  [&](const auto& item) { return item.first < beacon.oldest_cached[i]; });
    const int64_t last = beacon.last_sequences[i];
    if (last > peer.highest && last <= peer.highest + kLargestGap) {
      note_missing(peer, std::max(peer.highest + 1, beacon.oldest_cached[i]), last);
      peer.highest = last;
    }
  }
}

std::optional<std::vector<double>> Bus::field_values(const FieldKey& key) {
  const auto found = completed_.find(key);
  if (found == completed_.end()) return std::nullopt;
  return found->second;
}

bool Bus::has_field(const FieldKey& key) const {
  return completed_.contains(key);
}

std::vector<int32_t> Bus::missing_chunks(const FieldKey& key) const {
  std::vector<int32_t> missing;
  const auto found = assemblies_.find(key);
  if (found == assemblies_.end()) return missing;
  for (int32_t index = 0; index < found->second.chunk_count; ++index) {
    if (!found->second.received[index]) missing.push_back(index);
  }
  return missing;
}

void Bus::forget_fields_before(int64_t window) {
  std::erase_if(completed_, [&](const auto& item) { return item.first.window < window; });
  std::erase_if(assemblies_, [&](const auto& item) { return item.first.window < window; });
}

std::optional<std::chrono::steady_clock::time_point> Bus::last_heard(
    const std::string& sender) const {
  const auto found = last_heard_.find(sender);
  if (found == last_heard_.end()) return std::nullopt;
  return found->second;
}

std::string Bus::describe_peer(const std::string& sender) const {
  const auto found = peers_.find(sender);
  if (found == peers_.end()) return fmt::format("nothing heard from '{}'", sender);
  std::string missing;
  for (const auto& [sequence, entry] : found->second.missing)
    missing += fmt::format(" {}", sequence);
  return fmt::format(
      "'{}': newest sequence number {}, missing [{}], retransmission timeout {:.2f} ms", sender,
      found->second.highest, missing, 1e3 * rto_.load());
}

Bus::Counters Bus::counters() const {
  std::lock_guard counters(counters_mutex_);
  return counters_;
}

}  // namespace cosim::coupler

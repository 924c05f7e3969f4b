#include "cosim/coupler/bus.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <thread>

#include "cosim_msgs/header_t.hpp"

namespace cosim::coupler {

int64_t protocol_schema_hash() {
  // Order-dependent mix so that swapping two types' definitions also changes the hash.
  uint64_t hash = 0x9e3779b97f4a7c15ULL;
  for (const int64_t type_hash :
       {cosim_msgs::header_t::getHash(), cosim_msgs::window_t::getHash(),
        cosim_msgs::status_t::getHash(), cosim_msgs::field_chunk_t::getHash(),
        cosim_msgs::resend_request_t::getHash()}) {
    hash ^= static_cast<uint64_t>(type_hash) + 0x9e3779b97f4a7c15ULL + (hash << 6) + (hash >> 2);
  }
  return static_cast<int64_t>(hash);
}

std::string run_lcm_url(int64_t run_id) {
  const uint64_t mixed = static_cast<uint64_t>(run_id) * 0x9e3779b97f4a7c15ULL;
  const int port = 20000 + static_cast<int>(mixed % 40000);
  const int group_low = 1 + static_cast<int>((mixed >> 20) % 250);
  // ttl=0 keeps the traffic on this host.
  return fmt::format("udpm://239.255.76.{}:{}?ttl=0&recv_buf_size=4194304", group_low, port);
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
  if (!options_.record_log.empty()) {
    log_ = std::make_unique<lcm::LogFile>(options_.record_log.string(), "w");
    if (!log_->good()) {
      throw std::runtime_error("cannot write the event log " + options_.record_log.string());
    }
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
  header.iteration = 0;
  header.sim_time = stamp.sim_time;
  header.dt = stamp.dt;
  header.schema_hash = schema_hash_;
  return header;
}

template <class Message>
void Bus::publish_message(const std::string& channel, const Message& message) {
  if (lcm_.publish(channel, &message) != 0) {
    throw std::runtime_error(fmt::format("LCM publish on {} failed ({})", channel, options_.url));
  }
}

void Bus::publish_window(const Stamp& stamp, int8_t command, int64_t total_windows,
                         const std::string& reason) {
  std::lock_guard lock(publish_mutex_);
  cosim_msgs::window_t message;
  message.header = make_header(stamp, options_.name);
  message.command = command;
  message.total_windows = total_windows;
  message.reason = reason;
  publish_message(kWindowChannel, message);
}

void Bus::publish_status(const Stamp& stamp, cosim_msgs::status_t status) {
  std::lock_guard lock(publish_mutex_);
  status.header = make_header(stamp, options_.name);
  publish_message(kStatusChannel, status);
}

void Bus::publish_field(const Stamp& stamp, const std::string& field,
                        std::span<const double> values, const std::string& as_sender) {
  std::lock_guard lock(publish_mutex_);
  const std::string sender = as_sender.empty() ? options_.name : as_sender;
  const auto chunk_values = static_cast<std::size_t>(options_.chunk_values);
  const auto chunk_count = static_cast<int32_t>(
      std::max<std::size_t>(1, (values.size() + chunk_values - 1) / chunk_values));
  std::vector<cosim_msgs::field_chunk_t> chunks(chunk_count);
  for (int32_t index = 0; index < chunk_count; ++index) {
    auto& chunk = chunks[index];
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
    publish_message(kFieldChannel, chunk);
  }
  sent_[FieldKey{sender, stamp.window, field}] = std::move(chunks);
  // Keep only the newest windows for retransmission.
  const int64_t oldest_kept = stamp.window - options_.cached_windows;
  std::erase_if(sent_, [&](const auto& item) { return item.first.window < oldest_kept; });
}

void Bus::request_resend(const FieldKey& key, const std::vector<int32_t>& missing_chunks) {
  std::lock_guard lock(publish_mutex_);
  cosim_msgs::resend_request_t request;
  request.header = make_header(Stamp{key.window, 0.0, 0.0}, options_.name);
  request.target = key.sender;
  request.field = key.field;
  request.field_window = key.window;
  request.missing_chunks = missing_chunks;
  request.missing_count = static_cast<int32_t>(missing_chunks.size());
  publish_message(kResendChannel, request);
  ++counters_.resends_requested;
}

bool Bus::poll(double seconds) {
  accepted_since_poll_ = false;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(std::max(0.0, seconds));
  do {
    const auto remaining = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    const int wait_ms = static_cast<int>(std::max<int64_t>(0, remaining.count()));
    const int handled = lcm_.handleTimeout(wait_ms);
    if (handled < 0) throw std::runtime_error("LCM receive failed on " + options_.url);
    if (accepted_since_poll_) {
      // Drain whatever else is queued without waiting, then return to the caller.
      while (lcm_.handleTimeout(0) > 0) {
      }
      return true;
    }
  } while (std::chrono::steady_clock::now() < deadline);
  return accepted_since_poll_;
}

void Bus::on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  if (log_) {
    lcm::LogEvent event;
    event.eventnum = log_event_number_++;
    event.timestamp = buffer->recv_utime;
    event.channel = channel;
    event.datalen = static_cast<int32_t>(buffer->data_size);
    event.data = buffer->data;
    log_->writeEvent(&event);
  }
  if (options_.loss_probability > 0.0 &&
      std::uniform_real_distribution<double>(0.0, 1.0)(loss_random_) < options_.loss_probability) {
    ++counters_.dropped_injected;
    return;
  }
  const auto size = static_cast<int>(buffer->data_size);
  if (channel == kWindowChannel) {
    cosim_msgs::window_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !accept_header(message.header)) return;
    windows_.push_back(std::move(message));
  } else if (channel == kStatusChannel) {
    cosim_msgs::status_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !accept_header(message.header)) return;
    statuses_.push_back(std::move(message));
  } else if (channel == kFieldChannel) {
    cosim_msgs::field_chunk_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !accept_header(message.header)) return;
    on_field(message);
  } else if (channel == kResendChannel) {
    cosim_msgs::resend_request_t message;
    if (message.decode(buffer->data, 0, size) < 0 || !accept_header(message.header)) return;
    on_resend(message);
  }
}

bool Bus::accept_header(const cosim_msgs::header_t& header) {
  if (header.run_id != options_.run_id) {
    ++counters_.dropped_foreign;
    return false;
  }
  if (header.schema_hash != schema_hash_) {
    ++counters_.dropped_foreign;
    spdlog::warn("dropped a message from '{}': its schema hash {} differs from ours {}",
                 header.sender, header.schema_hash, schema_hash_);
    return false;
  }
  if (own_names_.contains(header.sender)) return false;
  auto& seen = seen_sequences_[header.sender];
  if (!seen.insert(header.sequence).second) {
    ++counters_.dropped_duplicate;
    return false;
  }
  // Sequence numbers only grow, so old entries can go once the set is large.
  if (seen.size() > 20000) seen.erase(seen.begin(), std::next(seen.begin(), 10000));
  last_heard_[header.sender] = std::chrono::steady_clock::now();
  ++counters_.accepted;
  accepted_since_poll_ = true;
  return true;
}

void Bus::on_field(const cosim_msgs::field_chunk_t& chunk) {
  const FieldKey key{chunk.header.sender, chunk.header.window, chunk.field};
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
  const auto sent = sent_.find(FieldKey{request.target, request.field_window, request.field});
  if (sent == sent_.end()) return;  // too old or never published: the requester will time out
  auto& chunks = sent->second;
  auto resend_one = [&](cosim_msgs::field_chunk_t& chunk) {
    chunk.header.sequence = next_sequence_[chunk.header.sender]++;
    publish_message(kFieldChannel, chunk);
    ++counters_.resends_served;
  };
  if (request.missing_chunks.empty()) {
    for (auto& chunk : chunks) resend_one(chunk);
  } else {
    for (const int32_t index : request.missing_chunks) {
      if (index >= 0 && index < static_cast<int32_t>(chunks.size())) resend_one(chunks[index]);
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

Bus::Counters Bus::counters() const {
  return counters_;
}

}  // namespace cosim::coupler

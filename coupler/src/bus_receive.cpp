// The bus's receiving side: every message LCM hands over is checked (run, sequence, gaps)
// and taken into the status, field and resend books; the queries on those books.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/event_log.hpp"
#include "cosim_msgs/header_t.hpp"
#include "steady_clock.hpp"

namespace cosim::coupler {

void Bus::on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  // The recorder hears everything that reaches this host, before injected loss: the loss
  // stands for this process's network, not for what happened.
  if (recorder_) recorder_->record(channel, buffer->data, buffer->data_size, buffer->recv_utime);
  // A test's drop_next loses data from this run's partners only: a beacon, a resend request or
  // another run's message arriving first would otherwise take the loss meant for the data.
  const bool dropped_on_purpose = drop_next_ > 0 && carries_partner_data(buffer, channel);
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

bool Bus::carries_partner_data(const lcm::ReceiveBuffer* buffer, const std::string& channel) const {
  int64_t type_hash = 0;
  if (channel == kWindowChannel) {
    type_hash = cosim_msgs::window_t::getHash();
  } else if (channel == kStatusChannel) {
    type_hash = cosim_msgs::status_t::getHash();
  } else if (channel == kFieldChannel) {
    type_hash = cosim_msgs::field_chunk_t::getHash();
  } else {
    return false;
  }
  cosim_msgs::header_t header;
  return peek_header(buffer->data, static_cast<int>(buffer->data_size), type_hash, header) &&
         header.run_id == options_.run_id && !own_names_.contains(header.sender);
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

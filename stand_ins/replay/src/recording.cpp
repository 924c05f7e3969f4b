#include "cosim/replay/recording.hpp"

#include <fmt/format.h>
#include <cstring>
#include <fstream>
#include <set>
#include <stdexcept>

#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/event_log_file.hpp"
#include "cosim_msgs/field_chunk_t.hpp"
#include "cosim_msgs/status_t.hpp"
#include "cosim_msgs/window_t.hpp"

namespace cosim::replay {

namespace {

struct Assembly {
  std::vector<double> values;
  std::vector<bool> received;
  int32_t received_count = 0;
};

// One record of an LCM event log file as stored, with where it was found.
struct StoredEvent {
  int64_t record = 0;   // position in the file, from 0
  uint64_t offset = 0;  // byte offset of its header
  std::string channel;
  std::vector<uint8_t> data;
};

constexpr uint32_t kRecordMarker = 0xEDA1DA01;  // LCM's per-record magic number
constexpr std::size_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;
constexpr int32_t kMaxChannelBytes = 256;  // LCM allows 63; anything larger is damage

uint64_t big_endian(const uint8_t* bytes, int count) {
  uint64_t value = 0;
  for (int i = 0; i < count; ++i) value = (value << 8) | bytes[i];
  return value;
}

[[noreturn]] void damaged(const std::filesystem::path& log, int64_t record, uint64_t offset,
                          const std::string& problem) {
  throw std::runtime_error(
      fmt::format("{}: damaged at byte {} (record {}): {}", log.string(), offset, record, problem));
}

// Reads the log record by record. LCM's own reader skips garbage silently, hunting for the next
// marker, and stops quietly at a truncated record; a replay must not compare against a
// recording with holes in it, so every inconsistency is an error naming the byte and record.
template <class Visitor>
void for_each_event(const std::filesystem::path& event_log, Visitor&& visit) {
  if (coupler::EventLogReader probe(event_log); probe.compressed()) {
    // zstd blocks: the reader checks each block's checksum and names damage by byte offset.
    StoredEvent event;
    for (int64_t record = 0;; ++record) {
      auto next = probe.next();
      if (!next) return;
      if (next->number != record) {
        damaged(event_log, record, probe.block_offset(),
                fmt::format("event number {} where {} was expected (records missing or out of "
                            "order)",
                            next->number, record));
      }
      event.record = record;
      event.offset = probe.block_offset();
      event.channel = std::move(next->channel);
      event.data = std::move(next->data);
      visit(event);
    }
  }
  std::error_code error;
  const auto size = std::filesystem::file_size(event_log, error);
  if (error) {
    throw std::runtime_error(
        fmt::format("{}: no such event log ({})", event_log.string(), error.message()));
  }
  std::ifstream in(event_log, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read", event_log.string()));
  uint64_t offset = 0;
  StoredEvent event;
  for (int64_t record = 0; offset < size; ++record) {
    const uint64_t left = size - offset;
    if (left < kHeaderBytes) {
      damaged(event_log, record, offset,
              fmt::format("the file ends {} bytes into a {}-byte record header (truncated)", left,
                          kHeaderBytes));
    }
    uint8_t header[kHeaderBytes];
    in.read(reinterpret_cast<char*>(header), kHeaderBytes);
    if (!in) damaged(event_log, record, offset, "read failed");
    const auto marker = static_cast<uint32_t>(big_endian(header, 4));
    if (marker != kRecordMarker) {
      damaged(event_log, record, offset,
              fmt::format("expected the record marker 0x{:08X}, found 0x{:08X}", kRecordMarker,
                          marker));
    }
    const auto number = static_cast<int64_t>(big_endian(header + 4, 8));
    const auto channel_bytes = static_cast<int32_t>(big_endian(header + 20, 4));
    const auto data_bytes = static_cast<int32_t>(big_endian(header + 24, 4));
    if (number != record) {
      damaged(event_log, record, offset,
              fmt::format("event number {} where {} was expected (records missing or out of "
                          "order)",
                          number, record));
    }
    if (channel_bytes <= 0 || channel_bytes > kMaxChannelBytes || data_bytes < 0) {
      damaged(event_log, record, offset,
              fmt::format("impossible lengths in the record header (channel {} bytes, data {} "
                          "bytes)",
                          channel_bytes, data_bytes));
    }
    const uint64_t body = static_cast<uint64_t>(channel_bytes) + static_cast<uint64_t>(data_bytes);
    if (body > left - kHeaderBytes) {
      damaged(event_log, record, offset,
              fmt::format("the header announces {} bytes of channel and data, the file has {} "
                          "left (truncated)",
                          body, left - kHeaderBytes));
    }
    event.record = record;
    event.offset = offset;
    event.channel.resize(static_cast<std::size_t>(channel_bytes));
    event.data.resize(static_cast<std::size_t>(data_bytes));
    in.read(event.channel.data(), channel_bytes);
    in.read(reinterpret_cast<char*>(event.data.data()), data_bytes);
    if (!in) damaged(event_log, record, offset, "read failed");
    offset += kHeaderBytes + body;
    visit(event);
  }
}

// A message that does not decode is damage too (or a log written with other definitions).
template <class Message>
bool decodes(Message& message, const StoredEvent& event, const std::filesystem::path& log,
             const char* type) {
  if (message.decode(event.data.data(), 0, static_cast<int>(event.data.size())) >= 0) return true;
  damaged(log, event.record, event.offset,
          fmt::format("the {}-byte message on {} does not decode as {} (damaged, or recorded "
                      "with other message definitions)",
                      event.data.size(), event.channel, type));
}

int64_t coupler_run_id(const std::filesystem::path& event_log) {
  int64_t run_id = 0;
  bool found = false;
  for_each_event(event_log, [&](const StoredEvent& event) {
    if (found || event.channel != coupler::kWindowChannel) return;
    cosim_msgs::window_t window;
    decodes(window, event, event_log, "window_t");
    if (window.header.sender == "coupler") {
      run_id = window.header.run_id;
      found = true;
    }
  });
  if (!found) {
    throw std::runtime_error(
        fmt::format("{}: the log holds no message from the coupler", event_log.string()));
  }
  return run_id;
}

}  // namespace

Recording read_recording(const std::filesystem::path& event_log, const std::string& participant) {
  Recording recording;
  recording.participant = participant;
  recording.run_id = coupler_run_id(event_log);
  std::map<std::pair<int64_t, std::string>, Assembly> assemblies;
  for_each_event(event_log, [&](const StoredEvent& event) {
    if (event.channel == coupler::kFieldChannel) {
      cosim_msgs::field_chunk_t chunk;
      decodes(chunk, event, event_log, "field_chunk_t");
      if (chunk.header.run_id != recording.run_id || chunk.header.sender != participant) return;
      if (chunk.chunk_index < 0 || chunk.chunk_index >= chunk.chunk_count || chunk.offset < 0 ||
          chunk.offset + chunk.value_count > chunk.total_values) {
        damaged(event_log, event.record, event.offset,
                fmt::format("chunk {} of {} of field '{}' covers values {}..{} of {}",
                            chunk.chunk_index, chunk.chunk_count, chunk.field, chunk.offset,
                            chunk.offset + chunk.value_count, chunk.total_values));
      }
      Assembly& assembly = assemblies[{chunk.header.window, chunk.field}];
      if (assembly.received.empty()) {
        assembly.values.assign(static_cast<std::size_t>(chunk.total_values), 0.0);
        assembly.received.assign(static_cast<std::size_t>(chunk.chunk_count), false);
      }
      if (assembly.received.size() != static_cast<std::size_t>(chunk.chunk_count)) return;
      if (assembly.received[chunk.chunk_index]) return;
      std::copy(chunk.values.begin(), chunk.values.end(), assembly.values.begin() + chunk.offset);
      assembly.received[chunk.chunk_index] = true;
      ++assembly.received_count;
    } else if (event.channel == coupler::kStatusChannel) {
      cosim_msgs::status_t status;
      decodes(status, event, event_log, "status_t");
      if (status.header.run_id != recording.run_id || status.header.sender != participant) return;
      if (status.state == cosim_msgs::status_t::STATE_READY) {
        recording.declaration = status.message;
      } else if (status.state == cosim_msgs::status_t::STATE_DONE) {
        auto& window = recording.windows[status.header.window];
        window.done = true;
        window.steps = status.steps;
        window.stable_dt = status.stable_dt;
      } else if (status.state == cosim_msgs::status_t::STATE_FINISHED) {
        recording.finished = true;
        recording.metrics_json = status.message;
      }
    }
  });
  for (auto& [key, assembly] : assemblies) {
    if (assembly.received_count != static_cast<int32_t>(assembly.received.size())) {
      throw std::runtime_error(fmt::format(
          "{}: field '{}' of '{}' in window {} is incomplete in the log ({} of {} chunks)",
          event_log.string(), key.second, participant, key.first, assembly.received_count,
          assembly.received.size()));
    }
    recording.windows[key.first].fields[key.second] = std::move(assembly.values);
  }
  return recording;
}

std::vector<std::string> recorded_participants(const std::filesystem::path& event_log) {
  std::set<std::string> names;
  for_each_event(event_log, [&](const StoredEvent& event) {
    if (event.channel != coupler::kFieldChannel) return;
    cosim_msgs::field_chunk_t chunk;
    if (decodes(chunk, event, event_log, "field_chunk_t")) names.insert(chunk.header.sender);
  });
  return {names.begin(), names.end()};
}

std::vector<Mismatch> compare_fields(const Recording& expected, const Recording& actual) {
  std::vector<Mismatch> mismatches;
  for (const auto& [index, window] : expected.windows) {
    const auto other = actual.windows.find(index);
    for (const auto& [field, values] : window.fields) {
      if (other == actual.windows.end() || !other->second.fields.contains(field)) {
        mismatches.push_back({index, field, "missing from the replayed run"});
        continue;
      }
      const auto& replayed = other->second.fields.at(field);
      if (replayed.size() != values.size()) {
        mismatches.push_back(
            {index, field,
             fmt::format("{} values recorded, {} replayed", values.size(), replayed.size())});
        continue;
      }
      for (std::size_t i = 0; i < values.size(); ++i) {
        if (std::memcmp(&values[i], &replayed[i], sizeof(double)) != 0) {
          mismatches.push_back({index, field,
                                fmt::format("value {} differs: recorded {:.17g}, replayed {:.17g}",
                                            i, values[i], replayed[i])});
          break;
        }
      }
    }
  }
  for (const auto& [index, window] : actual.windows) {
    const auto other = expected.windows.find(index);
    for (const auto& [field, values] : window.fields) {
      if (other == expected.windows.end() || !other->second.fields.contains(field)) {
        mismatches.push_back({index, field, "not in the recorded run"});
      }
    }
  }
  return mismatches;
}

}  // namespace cosim::replay

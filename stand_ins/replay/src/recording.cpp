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

// One event of the log, with where it was found.
struct StoredEvent {
  int64_t record = 0;   // position in the file, from 0
  uint64_t offset = 0;  // byte offset of its header
  std::string channel;
  std::vector<uint8_t> data;
};

[[noreturn]] void damaged(const std::filesystem::path& log, int64_t record, uint64_t offset,
                          const std::string& problem) {
  throw std::runtime_error(
      fmt::format("{}: damaged at byte {} (record {}): {}", log.string(), offset, record, problem));
}

// Every event of the log, compressed or plain. The reader checks each block's checksum, every
// record header and the event numbers, and names damage by byte offset (EventLogError).
template <class Visitor>
void for_each_event(const std::filesystem::path& event_log, Visitor&& visit) {
  if (!std::filesystem::exists(event_log)) {
    throw std::runtime_error(fmt::format("{}: no such event log", event_log.string()));
  }
  coupler::EventLogReader reader(event_log);
  StoredEvent event;
  while (auto next = reader.next()) {
    event.record = next->number;
    event.offset = reader.event_offset();
    event.channel = std::move(next->channel);
    event.data = std::move(next->data);
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
  std::map<std::pair<WindowKey, std::string>, Assembly> assemblies;
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
      Assembly& assembly =
          assemblies[{WindowKey{chunk.header.window, chunk.header.iteration}, chunk.field}];
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
        auto& window = recording.windows[{status.header.window, status.header.iteration}];
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
      throw std::runtime_error(
          fmt::format("{}: field '{}' of '{}' in {} is incomplete in the log ({} of {} chunks)",
                      event_log.string(), key.second, participant, describe(key.first),
                      assembly.received_count, assembly.received.size()));
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

std::string describe(const WindowKey& key) {
  return key.iteration == 0 ? fmt::format("window {}", key.window)
                            : fmt::format("window {}, iteration {}", key.window, key.iteration);
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

#include "cosim/coupler/event_log.hpp"

#include <lcm/lcm-cpp.hpp>

#include <stdexcept>
#include <vector>

#include "cosim/coupler/bus.hpp"

namespace cosim::coupler {

EventRecorder::EventRecorder(const std::filesystem::path& file, RecordMode mode)
    : mode_(mode), file_(file.string()) {
  log_ = std::make_unique<lcm::LogFile>(file_, "w");
  if (!log_->good()) throw std::runtime_error("cannot write the event log " + file_);
}

EventRecorder::~EventRecorder() = default;

bool EventRecorder::first_time(const std::string& sender, int64_t sequence) {
  auto& seen = recorded_[sender];
  if (!seen.insert(sequence).second) return false;
  // Sequence numbers only grow, so old entries can go once the set is large.
  if (seen.size() > 20000) seen.erase(seen.begin(), std::next(seen.begin(), 10000));
  return true;
}

void EventRecorder::write(const std::string& channel, const void* data, std::size_t size,
                          int64_t utime) {
  lcm::LogEvent event;
  event.eventnum = event_number_++;
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(size);
  event.data = const_cast<void*>(data);
  if (log_->writeEvent(&event) != 0) throw std::runtime_error("cannot write " + file_);
}

void EventRecorder::record(const std::string& channel, const void* data, std::size_t size,
                           int64_t utime) {
  const int length = static_cast<int>(size);
  if (channel == kWindowChannel) {
    cosim_msgs::window_t message;
    if (message.decode(data, 0, length) < 0) return;
    if (!first_time(message.header.sender, message.header.sequence)) return;
    write(channel, data, size, utime);
  } else if (channel == kStatusChannel) {
    cosim_msgs::status_t status;
    if (status.decode(data, 0, length) < 0) return;
    if (!first_time(status.header.sender, status.header.sequence)) return;
    if (status.fields.empty()) {
      write(channel, data, size, utime);
      return;
    }
    if (mode_ == RecordMode::all) {
      for (const auto& field : status.fields) {
        if (field.chunk_count != 0) continue;  // recorded from its chunks
        cosim_msgs::field_chunk_t chunk;
        chunk.header = status.header;
        chunk.field = field.name;
        chunk.chunk_index = 0;
        chunk.chunk_count = 1;
        chunk.total_values = field.total_values;
        chunk.offset = 0;
        chunk.value_count = field.value_count;
        chunk.values = field.values;
        std::vector<uint8_t> bytes(static_cast<std::size_t>(chunk.getEncodedSize()));
        chunk.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
        write(kFieldChannel, bytes.data(), bytes.size(), utime);
      }
    }
    status.fields.clear();
    status.field_count = 0;
    std::vector<uint8_t> bytes(static_cast<std::size_t>(status.getEncodedSize()));
    status.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    write(channel, bytes.data(), bytes.size(), utime);
  } else if (channel == kFieldChannel) {
    if (mode_ != RecordMode::all) return;
    cosim_msgs::header_t header;
    if (!peek_header(data, length, cosim_msgs::field_chunk_t::getHash(), header)) return;
    if (!first_time(header.sender, header.sequence)) return;
    write(channel, data, size, utime);
  }
  // Beacons and resend requests are transport housekeeping: a replay needs none of them.
}

}  // namespace cosim::coupler

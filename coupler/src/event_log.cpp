#include "cosim/coupler/event_log.hpp"

#include <mutex>
#include <stdexcept>
#include <vector>

#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/event_log_file.hpp"

namespace cosim::coupler {

EventRecorder::EventRecorder(const std::filesystem::path& file, RecordMode mode)
    : mode_(mode), file_(file.string()) {
  log_ = std::make_unique<EventLogWriter>(file);  // throws naming the file and the cause
}

namespace {
std::mutex failures_mutex;
std::map<std::string, std::string>& failures() {
  static std::map<std::string, std::string> by_file;
  return by_file;
}
}  // namespace

EventRecorder::~EventRecorder() {
  close();
}

std::string EventRecorder::write_failure(const std::filesystem::path& file) {
  std::lock_guard lock(failures_mutex);
  const auto found = failures().find(file.string());
  return found == failures().end() ? std::string() : found->second;
}

void EventRecorder::fail(const std::string& message) {
  if (!error_.empty()) return;
  error_ = message;
  std::lock_guard lock(failures_mutex);
  failures()[file_] = error_;
}

void EventRecorder::close() {
  if (!log_) return;
  // The pending block and the index are written here: a full disk often shows only now.
  if (error_.empty()) {
    try {
      log_->close();
    } catch (const std::exception& error) {
      fail(error.what());
    }
  }
  log_.reset();
}

bool EventRecorder::first_time(const std::string& sender, int64_t sequence) {
  auto& seen = recorded_[sender];
  if (!seen.insert(sequence).second) return false;
  // Sequence numbers only grow, so old entries can go once the set is large.
  if (seen.size() > 20000) seen.erase(seen.begin(), std::next(seen.begin(), 10000));
  return true;
}

void EventRecorder::write(const std::string& channel, const void* data, std::size_t size,
                          int64_t utime, int64_t window) {
  if (!log_) return;
  try {
    log_->append(channel, data, size, utime, window);
  } catch (const std::exception& error) {
    fail(error.what());
    log_.reset();  // nothing more is written after a gap: a reader would trust the rest
  }
}

void EventRecorder::record(const std::string& channel, const void* data, std::size_t size,
                           int64_t utime) {
  if (!log_) return;  // closed, or stopped by a write error
  const int length = static_cast<int>(size);
  if (channel == kWindowChannel) {
    cosim_msgs::window_t message;
    if (message.decode(data, 0, length) < 0) return;
    if (!first_time(message.header.sender, message.header.sequence)) return;
    write(channel, data, size, utime, message.header.window);
  } else if (channel == kStatusChannel) {
    cosim_msgs::status_t status;
    if (status.decode(data, 0, length) < 0) return;
    if (!first_time(status.header.sender, status.header.sequence)) return;
    const int64_t window = status.header.window;
    if (status.fields.empty()) {
      write(channel, data, size, utime, window);
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
        write(kFieldChannel, bytes.data(), bytes.size(), utime, window);
      }
    }
    status.fields.clear();
    status.field_count = 0;
    std::vector<uint8_t> bytes(static_cast<std::size_t>(status.getEncodedSize()));
    status.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    write(channel, bytes.data(), bytes.size(), utime, window);
  } else if (channel == kFieldChannel) {
    if (mode_ != RecordMode::all) return;
    cosim_msgs::header_t header;
    if (!peek_header(data, length, cosim_msgs::field_chunk_t::getHash(), header)) return;
    if (!first_time(header.sender, header.sequence)) return;
    write(channel, data, size, utime, header.window);
  }
  // Beacons and resend requests are transport housekeeping: a replay needs none of them.
}

}  // namespace cosim::coupler

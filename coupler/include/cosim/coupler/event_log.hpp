// The run's event log. The coupler hears every message, but writes each one once and in one
// canonical form, whatever the wire did: retransmissions are left out (same sender and sequence
// number), beacons and resend requests are not recorded, and the fields a report carried
// inline are written as single-chunk field messages, so a reader sees the fields of a window
// exactly as it would have had they been sent one by one.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>

namespace lcm {
class LogFile;
}

namespace cosim::coupler {

enum class RecordMode;

class EventRecorder {
 public:
  EventRecorder(const std::filesystem::path& file, RecordMode mode);
  ~EventRecorder();
  EventRecorder(const EventRecorder&) = delete;
  EventRecorder& operator=(const EventRecorder&) = delete;

  // One message as heard on `channel`.
  void record(const std::string& channel, const void* data, std::size_t size, int64_t utime);

 private:
  void write(const std::string& channel, const void* data, std::size_t size, int64_t utime);
  bool first_time(const std::string& sender, int64_t sequence);

  RecordMode mode_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t event_number_ = 0;
  std::map<std::string, std::set<int64_t>> recorded_;
  std::string file_;
};

}  // namespace cosim::coupler

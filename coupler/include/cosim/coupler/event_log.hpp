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

namespace cosim::coupler {

enum class RecordMode;
class EventLogWriter;

class EventRecorder {
 public:
  EventRecorder(const std::filesystem::path& file, RecordMode mode);
  ~EventRecorder();
  EventRecorder(const EventRecorder&) = delete;
  EventRecorder& operator=(const EventRecorder&) = delete;

  // One message as heard on `channel`. Never throws for a write error (it runs inside LCM's C
  // callback, which an exception must not cross): the first error stops the recording and is
  // kept, see error() and write_failure().
  void record(const std::string& channel, const void* data, std::size_t size, int64_t utime);
  // Flushes and closes the log; a failure (disk full) is kept like a write error. Idempotent.
  void close();
  // The first write error, "cannot write the event log <file>: <strerror>", or empty.
  const std::string& error() const { return error_; }

  // The error a recorder of `file` met in this process, or empty: for the launcher, which sees
  // the log only as a file name of its run (the recorder lives inside the coupler's bus).
  static std::string write_failure(const std::filesystem::path& file);

 private:
  void fail(const std::string& message);
  void write(const std::string& channel, const void* data, std::size_t size, int64_t utime,
             int64_t window);
  bool first_time(const std::string& sender, int64_t sequence);

  RecordMode mode_;
  std::unique_ptr<EventLogWriter> log_;  // zstd-compressed blocks (event_log_file.hpp)
  std::map<std::string, std::set<int64_t>> recorded_;
  std::string file_;
  std::string error_;
};

}  // namespace cosim::coupler

// The event log on disk: LCM log events (the byte format of lcm-logger) in zstd-compressed
// blocks, with the values of the field chunks taken out into predicted, byte-planed columns
// (field_columns.hpp), so a run's traffic takes a fraction of its raw size. write_lcm_log()
// (`cosim export-log`) turns it back into a plain .lcmlog that LCM's own tools read.
//
// Layout (every part a zstd frame, so `zstd -t` checks the file):
//   per block: a skippable frame "block header" (tag, format version, compressed and raw size,
//              first and last coupling window, first event number) followed by one zstd frame
//              with a content checksum holding whole events: in format 1 plain LCM events, in
//              format 2 the size of the events section, the events (each led by a kind byte,
//              and a column number when its values are in the columns), then the columns;
//   at the end: a skippable frame "index" listing each block's file offset and windows.
// A reader streams block by block from the headers alone (a run cut short, without its index,
// stays readable up to its last whole block), and seeks to a window through the index.
// Plain .lcmlog files (runs recorded before compression, or exported ones) are read too.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cosim::coupler {

// A file that cannot be read as an event log, with what and where (byte offset) it is damaged.
class EventLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LoggedEvent {
  int64_t number = 0;     // event number, from 0 in file order
  int64_t timestamp = 0;  // [us] when the coupler heard it
  std::string channel;
  std::vector<uint8_t> data;
};

struct EventLogBlock {
  uint64_t offset = 0;  // file offset of the block header
  uint64_t compressed_size = 0;
  uint64_t raw_size = 0;
  int64_t first_window = 0, last_window = 0;
  int64_t first_event = 0;
};

class FieldColumnWriter;
class FieldColumnReader;

class EventLogWriter {
 public:
  // Raw bytes gathered before a block is compressed and written; larger blocks compress better,
  // smaller ones lose less if the writer is killed.
  static constexpr std::size_t kBlockBytes = std::size_t{1} << 20;

  explicit EventLogWriter(const std::filesystem::path& file, int compression_level = 3);
  ~EventLogWriter();  // closes if close() was not called; errors are then only logged
  EventLogWriter(const EventLogWriter&) = delete;
  EventLogWriter& operator=(const EventLogWriter&) = delete;

  // One event of coupling window `window` (windows only grow over a run).
  void append(const std::string& channel, const void* data, std::size_t size, int64_t utime,
              int64_t window);
  // Writes the pending block and the index and closes the file. Throws naming the file and the
  // cause (e.g. "No space left on device").
  void close();

  int64_t events() const { return event_number_; }
  uint64_t raw_bytes() const { return raw_bytes_; }
  uint64_t file_bytes() const { return file_offset_; }

 private:
  void flush_block();
  void write_bytes(const void* data, std::size_t size);

  std::filesystem::path file_;
  int level_;
  std::FILE* out_ = nullptr;
  std::vector<uint8_t> block_;
  std::vector<EventLogBlock> index_;
  std::unique_ptr<FieldColumnWriter> columns_;  // the field chunks' values of the block
  EventLogBlock pending_;
  int64_t event_number_ = 0;
  uint64_t raw_bytes_ = 0, file_offset_ = 0;
};

class EventLogReader {
 public:
  explicit EventLogReader(const std::filesystem::path& file);
  ~EventLogReader();
  EventLogReader(const EventLogReader&) = delete;
  EventLogReader& operator=(const EventLogReader&) = delete;

  // The next event in file order, or nothing at the clean end. Throws EventLogError naming the
  // file, the byte offset and what is wrong when the file is damaged.
  std::optional<LoggedEvent> next();
  // Continue from the first block that may hold `window` (the index, or a scan of the block
  // headers when the index is missing). Events of earlier windows in that block still come.
  void seek_window(int64_t window);

  bool compressed() const { return compressed_; }
  // File offset of the compressed data of the block the last event came from.
  uint64_t block_offset() const { return block_offset_; }
  // Where the last event was found: its record's offset in a plain log, its block's data
  // offset in a compressed one (for messages that name damage found in the event itself).
  uint64_t event_offset() const { return event_offset_; }
  // The blocks of a compressed log (from the index, else from a scan); empty for plain logs.
  const std::vector<EventLogBlock>& blocks();

 private:
  bool load_block(uint64_t offset);
  std::optional<LoggedEvent> next_plain();
  std::optional<LoggedEvent> next_compressed();
  void scan_blocks();
  [[noreturn]] void damaged(uint64_t offset, const std::string& what) const;

  std::filesystem::path file_;
  std::FILE* in_ = nullptr;
  uint64_t file_size_ = 0;
  bool compressed_ = false;
  std::vector<uint8_t> block_;                    // the current block, decompressed
  std::size_t block_cursor_ = 0, block_end_ = 0;  // next event, end of the events section
  int block_version_ = 0;
  std::unique_ptr<FieldColumnReader> columns_;
  uint64_t block_offset_ = 0, next_block_offset_ = 0;
  std::vector<EventLogBlock> blocks_;
  bool blocks_known_ = false;
  uint64_t plain_offset_ = 0;
  int64_t plain_record_ = 0;
  uint64_t event_offset_ = 0;
  int64_t expected_number_ = 0;  // the number the next event must carry
};

// Writes every event of `log` (from where it stands) to `file` as a plain LCM log, the format of
// lcm-logger; returns the number of events. Throws naming the file and the cause.
int64_t write_lcm_log(EventLogReader& log, const std::filesystem::path& file);

// The run's event log file in `run_dir`: events.lcmlog.zst, or events.lcmlog for runs recorded
// before compression; nothing when neither exists.
std::optional<std::filesystem::path> find_event_log(const std::filesystem::path& run_dir);

}  // namespace cosim::coupler

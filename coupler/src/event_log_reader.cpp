#include "cosim/coupler/event_log_file.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "cosim/coupler/bus.hpp"
#include "event_log_format.hpp"
#include "field_columns.hpp"

namespace cosim::coupler {
using namespace event_log_format;

EventLogReader::EventLogReader(const std::filesystem::path& file)
    : file_(file), columns_(std::make_unique<FieldColumnReader>()) {
  in_ = std::fopen(file.c_str(), "rb");
  if (!in_) {
    throw EventLogError(
        fmt::format("cannot read the event log {}: {}", file.string(), std::strerror(errno)));
  }
  std::error_code error;
  file_size_ = std::filesystem::file_size(file, error);
  std::array<uint8_t, 4> magic{};
  if (file_size_ < 4 || std::fread(magic.data(), 1, 4, in_) != 4) {
    damaged(0, "too short for an event log");
  }
  const uint32_t little = static_cast<uint32_t>(get_le(magic.data(), 4));
  if (little == kBlockHeaderMagic || little == kZstdMagic) {
    compressed_ = true;
    next_block_offset_ = 0;
  } else if (get_be(magic.data(), 4) == kLcmSync) {
    plain_offset_ = 0;
  } else {
    damaged(0, "neither a compressed event log nor an LCM log (unknown leading bytes)");
  }
}

EventLogReader::~EventLogReader() {
  if (in_) std::fclose(in_);
}

void EventLogReader::damaged(uint64_t offset, const std::string& what) const {
  throw EventLogError(
      fmt::format("event log {} is damaged at byte {}: {}", file_.string(), offset, what));
}

// Reads the block whose header starts at `offset` into block_; false at the clean end (end of
// file, or the index frame).
bool EventLogReader::load_block(uint64_t offset) {
  if (offset == file_size_) return false;
  std::array<uint8_t, 8> frame{};
  if (std::fseek(in_, static_cast<long>(offset), SEEK_SET) != 0 ||
      std::fread(frame.data(), 1, 8, in_) != 8) {
    damaged(offset, "the file ends inside a block header (the run was cut short?)");
  }
  const uint32_t magic = static_cast<uint32_t>(get_le(frame.data(), 4));
  const uint64_t size = get_le(frame.data() + 4, 4);
  if (magic == kIndexMagic) return false;
  if (magic != kBlockHeaderMagic || size != kBlockPayload) {
    damaged(offset, fmt::format("expected a block header, found bytes {:08x}", magic));
  }
  std::array<uint8_t, kBlockPayload> payload{};
  if (std::fread(payload.data(), 1, payload.size(), in_) != payload.size()) {
    damaged(offset, "the file ends inside a block header (the run was cut short?)");
  }
  const uint64_t version = get_le(payload.data() + 4, 4);
  if (!has_tag(payload.data(), kBlockTag) || version < 1 || version > kFormatVersion) {
    damaged(offset, fmt::format("block header of an unknown format version ({}; this build reads "
                                "1-{})",
                                version, kFormatVersion));
  }
  const EventLogBlock block = get_block_fields(payload.data() + 8, false);
  const uint64_t data_offset = offset + 8 + kBlockPayload;
  if (data_offset + block.compressed_size > file_size_) {
    damaged(data_offset, fmt::format("block of windows {}-{} needs {} bytes, the file has {} left "
                                     "(the run was cut short?)",
                                     block.first_window, block.last_window, block.compressed_size,
                                     file_size_ - data_offset));
  }
  std::vector<uint8_t> compressed(block.compressed_size);
  if (std::fread(compressed.data(), 1, compressed.size(), in_) != compressed.size()) {
    damaged(data_offset, "read error");
  }
  block_.resize(block.raw_size);
  const std::size_t got =
      ZSTD_decompress(block_.data(), block_.size(), compressed.data(), compressed.size());
  if (ZSTD_isError(got) || got != block.raw_size) {
    damaged(data_offset, fmt::format("block of windows {}-{} does not decompress ({})",
                                     block.first_window, block.last_window,
                                     ZSTD_isError(got) ? ZSTD_getErrorName(got) : "wrong length"));
  }
  block_cursor_ = 0;
  block_offset_ = data_offset;
  next_block_offset_ = data_offset + block.compressed_size;
  block_version_ = static_cast<int>(version);
  columns_->clear();
  if (block_version_ >= 2) {
    // The events section, then the field columns of its chunks.
    const std::size_t events = block_.size() < 4 ? SIZE_MAX : get_le(block_.data(), 4);
    if (events > block_.size() - 4) {
      damaged(data_offset, fmt::format("block of windows {}-{}: its events section overruns it",
                                       block.first_window, block.last_window));
    }
    try {
      columns_->decode(block_.data() + 4 + events, block_.size() - 4 - events);
    } catch (const std::runtime_error& error) {
      damaged(data_offset, fmt::format("block of windows {}-{}: {}", block.first_window,
                                       block.last_window, error.what()));
    }
    block_cursor_ = 4;
    block_end_ = 4 + events;
  } else {
    block_end_ = block_.size();
  }
  return true;
}

std::optional<LoggedEvent> EventLogReader::next() {
  auto event = compressed_ ? next_compressed() : next_plain();
  // Events are numbered from 0 in file order: a gap is a lost record, not a quiet skip.
  if (event && event->number != expected_number_) {
    const std::string record =
        compressed_ ? std::string() : fmt::format(" (record {})", plain_record_ - 1);
    throw EventLogError(
        fmt::format("event log {} is damaged at byte {}{}: event number {} where "
                    "{} was expected (records missing or out of order)",
                    file_.string(), event_offset_, record, event->number, expected_number_));
  }
  if (event) expected_number_ = event->number + 1;
  return event;
}

std::optional<LoggedEvent> EventLogReader::next_compressed() {
  while (block_cursor_ >= block_end_) {
    if (!load_block(next_block_offset_)) return std::nullopt;
  }
  // damaged() names the block's byte offset; say how far into its events the damage lies.
  const auto at = [&](const std::string& what) {
    damaged(block_offset_,
            fmt::format("{} bytes into the block's events: {}", block_cursor_, what));
  };
  std::optional<uint32_t> column;
  if (block_version_ >= 2) {
    const uint8_t kind = block_[block_cursor_];
    if (kind == kColumnEvent) {
      if (block_end_ - block_cursor_ < 5) at("a cut event");
      column = static_cast<uint32_t>(get_le(block_.data() + block_cursor_ + 1, 4));
      block_cursor_ += 5;
    } else if (kind == kVerbatimEvent) {
      block_cursor_ += 1;
    } else {
      at(fmt::format("unknown event kind {}", kind));
    }
  }
  if (block_end_ - block_cursor_ < kLcmEventHeader) {
    at("a cut event");
  }
  const uint8_t* p = block_.data() + block_cursor_;
  if (get_be(p, 4) != kLcmSync) {
    at("no event sync word");
  }
  LoggedEvent event;
  event.number = static_cast<int64_t>(get_be(p + 4, 8));
  event.timestamp = static_cast<int64_t>(get_be(p + 12, 8));
  const std::size_t channel_length = get_be(p + 20, 4);
  const std::size_t data_length = get_be(p + 24, 4);
  if (block_end_ - block_cursor_ - kLcmEventHeader < channel_length + data_length) {
    at("a cut event");
  }
  p += kLcmEventHeader;
  event.channel.assign(reinterpret_cast<const char*>(p), channel_length);
  event.data.assign(p + channel_length, p + channel_length + data_length);
  if (column) {
    try {
      columns_->restore(*column, event.data);
    } catch (const std::runtime_error& error) {
      at(error.what());
    }
  }
  block_cursor_ += kLcmEventHeader + channel_length + data_length;
  event_offset_ = block_offset_;
  return event;
}

// Record by record. LCM's own reader skips garbage silently, hunting for the next marker, and
// stops quietly at a truncated record; a replay must not compare against a recording with holes
// in it, so every inconsistency is an error naming the byte and the record.
std::optional<LoggedEvent> EventLogReader::next_plain() {
  if (plain_offset_ == file_size_) return std::nullopt;
  const auto at = [&](const std::string& what) {
    throw EventLogError(fmt::format("event log {} is damaged at byte {} (record {}): {}",
                                    file_.string(), plain_offset_, plain_record_, what));
  };
  const uint64_t left = file_size_ - plain_offset_;
  if (left < kLcmEventHeader) {
    at(fmt::format("the file ends {} bytes into a {}-byte record header (truncated)", left,
                   kLcmEventHeader));
  }
  std::array<uint8_t, kLcmEventHeader> header{};
  std::fseek(in_, static_cast<long>(plain_offset_), SEEK_SET);
  if (std::fread(header.data(), 1, header.size(), in_) != header.size()) at("read error");
  const auto marker = static_cast<uint32_t>(get_be(header.data(), 4));
  if (marker != kLcmSync) {
    at(fmt::format("expected the record marker 0x{:08X}, found 0x{:08X}", kLcmSync, marker));
  }
  LoggedEvent event;
  event.number = static_cast<int64_t>(get_be(header.data() + 4, 8));
  event.timestamp = static_cast<int64_t>(get_be(header.data() + 12, 8));
  const std::size_t channel_length = get_be(header.data() + 20, 4);
  const std::size_t data_length = get_be(header.data() + 24, 4);
  if (channel_length == 0 || channel_length > kMaxChannelBytes || data_length > INT32_MAX) {
    at(fmt::format("impossible lengths in the record header (channel {} bytes, data {} bytes)",
                   channel_length, data_length));
  }
  if (left - kLcmEventHeader < channel_length + data_length) {
    at(
        fmt::format("the header announces {} bytes of channel and data, the file has {} left "
                    "(truncated)",
                    channel_length + data_length, left - kLcmEventHeader));
  }
  std::vector<uint8_t> body(channel_length + data_length);
  if (std::fread(body.data(), 1, body.size(), in_) != body.size()) at("read error");
  event.channel.assign(body.begin(), body.begin() + static_cast<long>(channel_length));
  event.data.assign(body.begin() + static_cast<long>(channel_length), body.end());
  event_offset_ = plain_offset_;
  plain_offset_ += kLcmEventHeader + body.size();
  ++plain_record_;
  return event;
}

void EventLogReader::scan_blocks() {
  blocks_.clear();
  blocks_known_ = true;
  if (!compressed_) return;
  // The index, found from the file's last 12 bytes (its size and tag).
  if (file_size_ >= 20) {
    std::array<uint8_t, 12> tail{};
    std::fseek(in_, static_cast<long>(file_size_ - 12), SEEK_SET);
    if (std::fread(tail.data(), 1, 12, in_) == 12 && has_tag(tail.data() + 8, kIndexTag)) {
      const uint64_t frame_size = get_le(tail.data(), 8);
      if (frame_size >= 28 && frame_size <= file_size_) {
        std::vector<uint8_t> frame(frame_size);
        std::fseek(in_, static_cast<long>(file_size_ - frame_size), SEEK_SET);
        if (std::fread(frame.data(), 1, frame.size(), in_) == frame.size() &&
            get_le(frame.data(), 4) == kIndexMagic && has_tag(frame.data() + 8, kIndexTag)) {
          const uint64_t count = get_le(frame.data() + 16, 8);
          if (24 + count * kIndexEntry + 12 == frame_size) {
            for (uint64_t b = 0; b < count; ++b) {
              blocks_.push_back(get_block_fields(frame.data() + 24 + b * kIndexEntry, true));
            }
            return;
          }
        }
      }
    }
  }
  // No index (a run cut short): walk the block headers.
  uint64_t offset = 0;
  while (offset + 8 + kBlockPayload <= file_size_) {
    std::array<uint8_t, 8 + kBlockPayload> header{};
    std::fseek(in_, static_cast<long>(offset), SEEK_SET);
    if (std::fread(header.data(), 1, header.size(), in_) != header.size()) break;
    if (get_le(header.data(), 4) != kBlockHeaderMagic) break;
    EventLogBlock block = get_block_fields(header.data() + 16, false);
    block.offset = offset;
    blocks_.push_back(block);
    offset += 8 + kBlockPayload + block.compressed_size;
  }
}

const std::vector<EventLogBlock>& EventLogReader::blocks() {
  if (!blocks_known_) scan_blocks();
  return blocks_;
}

void EventLogReader::seek_window(int64_t window) {
  if (!compressed_) {
    plain_offset_ = 0;  // plain logs have no index: read from the start
    plain_record_ = 0;
    expected_number_ = 0;
    return;
  }
  // The first block reaching `window`, else the last one.
  const auto& all = blocks();
  const auto found = std::find_if(all.begin(), all.end(),
                                  [&](const EventLogBlock& b) { return b.last_window >= window; });
  const uint64_t offset = all.empty() ? 0 : (found != all.end() ? found : all.end() - 1)->offset;
  block_.clear();
  block_cursor_ = 0;
  block_end_ = 0;
  next_block_offset_ = offset;
  // The block's first event comes next (or the first one, without blocks).
  expected_number_ = all.empty() ? 0 : (found != all.end() ? found : all.end() - 1)->first_event;
}

int64_t write_lcm_log(EventLogReader& log, const std::filesystem::path& file) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> out(std::fopen(file.c_str(), "wb"),
                                                            &std::fclose);
  const auto fail = [&](int cause) {
    throw std::runtime_error(
        fmt::format("cannot write {}: {}", file.string(), std::strerror(cause ? cause : EIO)));
  };
  if (!out) fail(errno);
  int64_t count = 0;
  std::vector<uint8_t> record;
  while (const auto event = log.next()) {  // a damaged log throws EventLogError from here
    record.clear();
    put_be(record, kLcmSync, 4);
    put_be(record, static_cast<uint64_t>(event->number), 8);
    put_be(record, static_cast<uint64_t>(event->timestamp), 8);
    put_be(record, event->channel.size(), 4);
    put_be(record, event->data.size(), 4);
    record.insert(record.end(), event->channel.begin(), event->channel.end());
    record.insert(record.end(), event->data.begin(), event->data.end());
    if (std::fwrite(record.data(), 1, record.size(), out.get()) != record.size()) fail(errno);
    ++count;
  }
  if (std::fflush(out.get()) != 0) fail(errno);
  return count;
}

std::optional<std::filesystem::path> find_event_log(const std::filesystem::path& run_dir) {
  for (const char* name : {"events.lcmlog.zst", "events.lcmlog"}) {
    if (std::filesystem::exists(run_dir / name)) return run_dir / name;
  }
  return std::nullopt;
}

}  // namespace cosim::coupler

#include "cosim/coupler/event_log_file.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "cosim/coupler/bus.hpp"
#include "field_columns.hpp"

namespace cosim::coupler {
namespace {

// lcm-logger's event record (LCM eventlog.c): big-endian sync word, event number, timestamp,
// channel and data lengths, then the channel name and the data.
constexpr uint32_t kLcmSync = 0xEDA1DA01u;
constexpr std::size_t kLcmEventHeader = 4 + 8 + 8 + 4 + 4;
constexpr std::size_t kMaxChannelBytes = 256;  // LCM allows 63; anything larger is damage
// zstd skippable frames: magic 0x184D2A5? (little-endian), payload size, payload. Decoders that
// do not know them skip them, so `zstd -d` leaves only the events.
constexpr uint32_t kBlockHeaderMagic = 0x184D2A50u;
constexpr uint32_t kIndexMagic = 0x184D2A51u;
constexpr uint32_t kZstdMagic = 0xFD2FB528u;
constexpr std::array<char, 4> kBlockTag{'C', 'S', 'L', 'B'};
constexpr std::array<char, 4> kIndexTag{'C', 'S', 'L', 'I'};
// Version 1: a block holds plain LCM events. Version 2: a block holds the size of its events
// section, the events (each led by a byte: 0 verbatim, 1 a field chunk whose values are in
// column u32 that follows), then the field columns (field_columns.hpp).
constexpr uint32_t kFormatVersion = 2;
constexpr uint8_t kVerbatimEvent = 0;
constexpr uint8_t kColumnEvent = 1;
constexpr std::size_t kBlockPayload = 4 + 4 + 5 * 8;  // tag, version, five 64-bit fields
constexpr std::size_t kIndexEntry = 6 * 8;

void put_be(std::vector<uint8_t>& out, uint64_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
}
uint64_t get_be(const uint8_t* in, int bytes) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | in[i];
  return value;
}
void put_le(std::vector<uint8_t>& out, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
}
uint64_t get_le(const uint8_t* in, int bytes) {
  uint64_t value = 0;
  for (int i = bytes - 1; i >= 0; --i) value = (value << 8) | in[i];
  return value;
}
void put_tag(std::vector<uint8_t>& out, const std::array<char, 4>& tag) {
  out.insert(out.end(), tag.begin(), tag.end());
}
bool has_tag(const uint8_t* in, const std::array<char, 4>& tag) {
  return std::memcmp(in, tag.data(), tag.size()) == 0;
}

void put_block_fields(std::vector<uint8_t>& out, const EventLogBlock& b, bool with_offset) {
  if (with_offset) put_le(out, b.offset, 8);
  put_le(out, b.compressed_size, 8);
  put_le(out, b.raw_size, 8);
  put_le(out, static_cast<uint64_t>(b.first_window), 8);
  put_le(out, static_cast<uint64_t>(b.last_window), 8);
  put_le(out, static_cast<uint64_t>(b.first_event), 8);
}
EventLogBlock get_block_fields(const uint8_t* in, bool with_offset) {
  EventLogBlock b;
  if (with_offset) {
    b.offset = get_le(in, 8);
    in += 8;
  }
  b.compressed_size = get_le(in, 8);
  b.raw_size = get_le(in + 8, 8);
  b.first_window = static_cast<int64_t>(get_le(in + 16, 8));
  b.last_window = static_cast<int64_t>(get_le(in + 24, 8));
  b.first_event = static_cast<int64_t>(get_le(in + 32, 8));
  return b;
}

}  // namespace

// ---- writer ----

EventLogWriter::EventLogWriter(const std::filesystem::path& file, int compression_level)
    : file_(file), level_(compression_level), columns_(std::make_unique<FieldColumnWriter>()) {
  out_ = std::fopen(file.c_str(), "wb");
  if (!out_) {
    throw std::runtime_error(
        fmt::format("cannot write the event log {}: {}", file.string(), std::strerror(errno)));
  }
  block_.reserve(kBlockBytes + (kBlockBytes >> 2));
}

EventLogWriter::~EventLogWriter() {
  if (!out_) return;
  try {
    close();
  } catch (const std::exception& error) {
    spdlog::error("{}", error.what());
  }
}

void EventLogWriter::write_bytes(const void* data, std::size_t size) {
  if (std::fwrite(data, 1, size, out_) != size) {
    const int cause = errno;
    std::fclose(out_);
    out_ = nullptr;
    throw std::runtime_error(fmt::format("cannot write the event log {}: {}", file_.string(),
                                         std::strerror(cause ? cause : EIO)));
  }
  file_offset_ += size;
}

void EventLogWriter::append(const std::string& channel, const void* data, std::size_t size,
                            int64_t utime, int64_t window) {
  if (!out_) throw std::runtime_error("event log " + file_.string() + " is closed");
  if (block_.empty()) {
    pending_ = EventLogBlock{};
    pending_.first_window = window;
    pending_.first_event = event_number_;
  }
  pending_.last_window = std::max(pending_.last_window, window);
  const auto* bytes = static_cast<const uint8_t*>(data);
  std::size_t kept = size;
  const std::optional<uint32_t> column =
      channel == kFieldChannel ? columns_->take(bytes, size, kept) : std::nullopt;
  block_.push_back(column ? kColumnEvent : kVerbatimEvent);
  if (column) put_le(block_, *column, 4);
  put_be(block_, kLcmSync, 4);
  put_be(block_, static_cast<uint64_t>(event_number_++), 8);
  put_be(block_, static_cast<uint64_t>(utime), 8);
  put_be(block_, channel.size(), 4);
  put_be(block_, kept, 4);
  block_.insert(block_.end(), channel.begin(), channel.end());
  block_.insert(block_.end(), bytes, bytes + kept);
  raw_bytes_ += kLcmEventHeader + channel.size() + size;
  if (block_.size() + columns_->value_bytes() >= kBlockBytes) flush_block();
}

void EventLogWriter::flush_block() {
  if (block_.empty()) return;
  std::vector<uint8_t> raw;
  raw.reserve(4 + block_.size() + columns_->value_bytes() + 1024);
  put_le(raw, block_.size(), 4);
  raw.insert(raw.end(), block_.begin(), block_.end());
  columns_->encode(raw);
  std::vector<uint8_t> compressed(ZSTD_compressBound(raw.size()));
  ZSTD_CCtx* context = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(context, ZSTD_c_compressionLevel, level_);
  ZSTD_CCtx_setParameter(context, ZSTD_c_checksumFlag, 1);  // damage shows as a checksum error
  const std::size_t written =
      ZSTD_compress2(context, compressed.data(), compressed.size(), raw.data(), raw.size());
  ZSTD_freeCCtx(context);
  if (ZSTD_isError(written)) {
    throw std::runtime_error(fmt::format("cannot compress the event log {}: {}", file_.string(),
                                         ZSTD_getErrorName(written)));
  }
  pending_.offset = file_offset_;
  pending_.compressed_size = written;
  pending_.raw_size = raw.size();
  std::vector<uint8_t> header;
  put_le(header, kBlockHeaderMagic, 4);
  put_le(header, kBlockPayload, 4);
  put_tag(header, kBlockTag);
  put_le(header, kFormatVersion, 4);
  put_block_fields(header, pending_, false);
  write_bytes(header.data(), header.size());
  write_bytes(compressed.data(), written);
  index_.push_back(pending_);
  block_.clear();
}

void EventLogWriter::close() {
  if (!out_) return;
  flush_block();
  // Index: tag, version, count, entries, then its own total size and tag again so a reader finds
  // it from the end of the file.
  std::vector<uint8_t> payload;
  put_tag(payload, kIndexTag);
  put_le(payload, kFormatVersion, 4);
  put_le(payload, index_.size(), 8);
  for (const auto& block : index_) put_block_fields(payload, block, true);
  const std::size_t frame_size = 8 + payload.size() + 12;
  put_le(payload, frame_size, 8);
  put_tag(payload, kIndexTag);
  std::vector<uint8_t> frame;
  put_le(frame, kIndexMagic, 4);
  put_le(frame, payload.size(), 4);
  frame.insert(frame.end(), payload.begin(), payload.end());
  write_bytes(frame.data(), frame.size());
  const bool flushed = std::fflush(out_) == 0;
  const int cause = errno;
  const bool closed = std::fclose(out_) == 0;
  out_ = nullptr;
  if (!flushed || !closed) {
    throw std::runtime_error(fmt::format("cannot write the event log {}: {}", file_.string(),
                                         std::strerror(cause ? cause : EIO)));
  }
}

// ---- reader ----

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

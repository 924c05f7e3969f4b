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

}  // namespace cosim::coupler

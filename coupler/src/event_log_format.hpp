// The on-disk format of events.lcmlog.zst, shared by its writer (event_log_writer.cpp) and
// reader (event_log_reader.cpp): LCM event records in zstd frames, each led by a skippable block
// header, and an index frame at the end (docs/architecture.md, "The event log").
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include "cosim/coupler/event_log_file.hpp"

namespace cosim::coupler::event_log_format {

// lcm-logger's event record (LCM eventlog.c): big-endian sync word, event number, timestamp,
// channel and data lengths, then the channel name and the data.
inline constexpr uint32_t kLcmSync = 0xEDA1DA01u;
inline constexpr std::size_t kLcmEventHeader = 4 + 8 + 8 + 4 + 4;
inline constexpr std::size_t kMaxChannelBytes = 256;  // LCM allows 63; anything larger is damage
// zstd skippable frames: magic 0x184D2A5? (little-endian), payload size, payload. Decoders that
// do not know them skip them, so `zstd -d` leaves only the events.
inline constexpr uint32_t kBlockHeaderMagic = 0x184D2A50u;
inline constexpr uint32_t kIndexMagic = 0x184D2A51u;
inline constexpr uint32_t kZstdMagic = 0xFD2FB528u;
inline constexpr std::array<char, 4> kBlockTag{'C', 'S', 'L', 'B'};
inline constexpr std::array<char, 4> kIndexTag{'C', 'S', 'L', 'I'};
// Version 1: a block holds plain LCM events. Version 2: a block holds the size of its events
// section, the events (each led by a byte: 0 verbatim, 1 a field chunk whose values are in
// column u32 that follows), then the field columns (field_columns.hpp).
inline constexpr uint32_t kFormatVersion = 2;
inline constexpr uint8_t kVerbatimEvent = 0;
inline constexpr uint8_t kColumnEvent = 1;
inline constexpr std::size_t kBlockPayload = 4 + 4 + 5 * 8;  // tag, version, five 64-bit fields
inline constexpr std::size_t kIndexEntry = 6 * 8;

inline void put_be(std::vector<uint8_t>& out, uint64_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
}
inline uint64_t get_be(const uint8_t* in, int bytes) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | in[i];
  return value;
}
inline void put_le(std::vector<uint8_t>& out, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
}
inline uint64_t get_le(const uint8_t* in, int bytes) {
  uint64_t value = 0;
  for (int i = bytes - 1; i >= 0; --i) value = (value << 8) | in[i];
  return value;
}
inline void put_tag(std::vector<uint8_t>& out, const std::array<char, 4>& tag) {
  out.insert(out.end(), tag.begin(), tag.end());
}
inline bool has_tag(const uint8_t* in, const std::array<char, 4>& tag) {
  return std::memcmp(in, tag.data(), tag.size()) == 0;
}

inline void put_block_fields(std::vector<uint8_t>& out, const EventLogBlock& b, bool with_offset) {
  if (with_offset) put_le(out, b.offset, 8);
  put_le(out, b.compressed_size, 8);
  put_le(out, b.raw_size, 8);
  put_le(out, static_cast<uint64_t>(b.first_window), 8);
  put_le(out, static_cast<uint64_t>(b.last_window), 8);
  put_le(out, static_cast<uint64_t>(b.first_event), 8);
}
inline EventLogBlock get_block_fields(const uint8_t* in, bool with_offset) {
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

}  // namespace cosim::coupler::event_log_format

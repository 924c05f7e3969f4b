#include "field_columns.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "cosim_msgs/field_chunk_t.hpp"

namespace cosim::coupler {
namespace {

uint64_t big_endian_64(const uint8_t* in) {
  uint64_t value = 0;
  for (int i = 0; i < 8; ++i) value = (value << 8) | in[i];
  return value;
}
void put_u32(std::vector<uint8_t>& out, uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
}
uint32_t get_u32(const uint8_t* in) {
  return static_cast<uint32_t>(in[0]) | static_cast<uint32_t>(in[1]) << 8 |
         static_cast<uint32_t>(in[2]) << 16 | static_cast<uint32_t>(in[3]) << 24;
}

// The value expected in `row` from the two rows before it (wrapping 64-bit arithmetic).
uint64_t predicted(const std::vector<uint64_t>& rows, std::size_t n, std::size_t row,
                   std::size_t j) {
  if (row == 0) return 0;
  const uint64_t last = rows[(row - 1) * n + j];
  if (row == 1) return last;
  return 2 * last - rows[(row - 2) * n + j];
}
uint64_t zigzag(uint64_t difference) {
  return (difference << 1) ^ (0 - (difference >> 63));
}
uint64_t unzigzag(uint64_t code) {
  return (code >> 1) ^ (0 - (code & 1));
}

}  // namespace

std::optional<uint32_t> FieldColumnWriter::take(const uint8_t* data, std::size_t size,
                                                std::size_t& kept) {
  cosim_msgs::field_chunk_t chunk;
  if (size > static_cast<std::size_t>(INT32_MAX) ||
      chunk.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) {
    return std::nullopt;
  }
  const auto n = static_cast<std::size_t>(chunk.value_count);
  if (n == 0 || 8 * n > size) return std::nullopt;
  kept = size - 8 * n;  // the values are the message's last member
  const std::string key = fmt::format("{}\n{}\n{}\n{}", chunk.header.sender, chunk.field,
                                      chunk.offset, chunk.value_count);
  const auto [found, added] = ids_.try_emplace(key, static_cast<uint32_t>(streams_.size()));
  if (added) streams_.push_back(Stream{static_cast<uint32_t>(n), {}});
  auto& rows = streams_[found->second].rows;
  for (std::size_t j = 0; j < n; ++j) rows.push_back(big_endian_64(data + kept + 8 * j));
  value_bytes_ += 8 * n;
  return found->second;
}

void FieldColumnWriter::encode(std::vector<uint8_t>& out) {
  put_u32(out, static_cast<uint32_t>(streams_.size()));
  std::vector<uint64_t> codes;
  for (const auto& stream : streams_) {
    const std::size_t n = stream.values, rows = stream.rows.size() / n;
    put_u32(out, stream.values);
    put_u32(out, static_cast<uint32_t>(rows));
    codes.resize(stream.rows.size());
    for (std::size_t row = 0; row < rows; ++row) {
      for (std::size_t j = 0; j < n; ++j) {
        codes[row * n + j] = zigzag(stream.rows[row * n + j] - predicted(stream.rows, n, row, j));
      }
    }
    for (int byte = 7; byte >= 0; --byte) {
      for (std::size_t j = 0; j < n; ++j) {
        for (std::size_t row = 0; row < rows; ++row) {
          out.push_back(static_cast<uint8_t>(codes[row * n + j] >> (8 * byte)));
        }
      }
    }
  }
  ids_.clear();
  streams_.clear();
  value_bytes_ = 0;
}

void FieldColumnReader::decode(const uint8_t* data, std::size_t size) {
  streams_.clear();
  const auto fail = [](const std::string& what) {
    throw std::runtime_error("field columns: " + what);
  };
  if (size < 4) fail("the section is cut");
  const uint32_t count = get_u32(data);
  std::size_t at = 4;
  for (uint32_t s = 0; s < count; ++s) {
    if (size - at < 8) fail(fmt::format("stream {} of {} is cut", s, count));
    Stream stream;
    stream.values = get_u32(data + at);
    stream.row_count = get_u32(data + at + 4);
    at += 8;
    const std::size_t n = stream.values, rows = stream.row_count, bytes = 8 * n * rows;
    if (n == 0 || bytes / 8 / n != rows || size - at < bytes) {
      fail(fmt::format("stream {} claims {} values x {} rows, {} bytes are left", s, n, rows,
                       size - at));
    }
    std::vector<uint64_t> codes(n * rows, 0);
    for (int byte = 7; byte >= 0; --byte) {
      for (std::size_t j = 0; j < n; ++j) {
        for (std::size_t row = 0; row < rows; ++row) {
          codes[row * n + j] |= static_cast<uint64_t>(data[at++]) << (8 * byte);
        }
      }
    }
    stream.rows.resize(n * rows);
    for (std::size_t row = 0; row < rows; ++row) {
      for (std::size_t j = 0; j < n; ++j) {
        stream.rows[row * n + j] = predicted(stream.rows, n, row, j) + unzigzag(codes[row * n + j]);
      }
    }
    streams_.push_back(std::move(stream));
  }
  if (at != size) fail(fmt::format("{} bytes follow the last stream", size - at));
}

void FieldColumnReader::restore(uint32_t stream, std::vector<uint8_t>& out) {
  if (stream >= streams_.size()) {
    throw std::runtime_error(
        fmt::format("field columns: an event names stream {} of {}", stream, streams_.size()));
  }
  Stream& s = streams_[stream];
  if (s.next_row >= s.row_count) {
    throw std::runtime_error(
        fmt::format("field columns: stream {} has only {} rows", stream, s.row_count));
  }
  for (std::size_t j = 0; j < s.values; ++j) {
    const uint64_t bits = s.rows[s.next_row * s.values + j];
    for (int i = 7; i >= 0; --i) out.push_back(static_cast<uint8_t>(bits >> (8 * i)));
  }
  ++s.next_row;
}

}  // namespace cosim::coupler

// The values of the logged field chunks, stored apart from the rest of the events: one column
// per stream (a sender's field at one offset and length), in each block of the event log.
//
// A solver's field changes a little from one window to the next, but its doubles differ in
// their low mantissa bytes every time, which zstd's matching cannot use (a block of a blade's
// positions compressed 1.7 times). Here each value is predicted from the same value in the
// stream's two previous rows (linear extrapolation on the 64-bit patterns, which for doubles of
// one sign and binade is linear extrapolation of the value), the residual is zigzag-coded, and
// the bytes are written as planes: most significant byte of every value and row first. Small
// residuals then give long runs of zero bytes. The same idea as the time-series codecs of
// Gorilla (Pelkonen et al. 2015, VLDB) and the byte shuffle of Blosc; the integer arithmetic is
// exact, so decoding gives the doubles back bit for bit on any machine.
//
// Layout of a column section: stream count (u32), then per stream its value count n (u32), row
// count r (u32) and 8 n r bytes of planes [byte][value][row]. All integers little-endian.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace cosim::coupler {

class FieldColumnWriter {
 public:
  // If `data` is a field_chunk_t (cosim_msgs), takes its values into their stream's column and
  // returns the stream number; the event keeps the first `kept` bytes (all but the values).
  // Anything else (another message, a chunk that does not decode) returns nothing.
  std::optional<uint32_t> take(const uint8_t* data, std::size_t size, std::size_t& kept);
  // Bytes of values taken since the last encode().
  std::size_t value_bytes() const { return value_bytes_; }
  // Appends the column section of everything taken and starts a new, empty one.
  void encode(std::vector<uint8_t>& out);

 private:
  struct Stream {
    uint32_t values = 0;
    std::vector<uint64_t> rows;  // row-major bit patterns of the doubles
  };
  std::map<std::string, uint32_t> ids_;
  std::vector<Stream> streams_;
  std::size_t value_bytes_ = 0;
};

class FieldColumnReader {
 public:
  // Reads a column section; throws std::runtime_error saying what is inconsistent.
  void decode(const uint8_t* data, std::size_t size);
  // Appends the next row of `stream` (its doubles, big-endian as LCM encodes them) to `out`.
  void restore(uint32_t stream, std::vector<uint8_t>& out);
  void clear() { streams_.clear(); }

 private:
  struct Stream {
    uint32_t values = 0;
    std::size_t next_row = 0, row_count = 0;
    std::vector<uint64_t> rows;
  };
  std::vector<Stream> streams_;
};

}  // namespace cosim::coupler

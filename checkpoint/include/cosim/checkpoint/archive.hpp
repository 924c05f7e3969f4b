// Checkpoint files: one participant's full state at a window boundary, as named records of raw
// values, so a restarted run continues with the same bits as an uninterrupted one.
//
// Layout (little-endian host byte order, as every value is stored bit for bit):
//   "COSIMCKP"                      8 bytes magic
//   u32 format version              kFormatVersion; another version is refused
//   u32 n, n bytes                  kind: who wrote it ("vegetation_beam", "debris_dem", ...)
//   u64 record count
//   per record: u32 n, n bytes name; u64 element size; u64 element count; size * count bytes
//   u32 CRC-32 (IEEE) of every byte before it
// Records are raw copies of doubles, integers and fixed-layout structs (Eigen vectors): the
// element size is stored and checked, so a file of a build with another layout is refused by
// name instead of read wrongly. Files are written to a temporary name and renamed, so a
// checkpoint is either whole or absent.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace cosim::checkpoint {

inline constexpr std::uint32_t kFormatVersion = 1;

// A checkpoint that cannot be used: the message names the file and, where it applies, the record.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Writer {
 public:
  explicit Writer(std::string kind) : kind_(std::move(kind)) {}

  void bytes(std::string_view name, const void* data, std::size_t element_size, std::size_t count);
  template <class T>
  void value(std::string_view name, const T& v) {
    bytes(name, &v, sizeof(T), 1);
  }
  template <class T>
  void vector(std::string_view name, const std::vector<T>& v) {
    bytes(name, v.data(), sizeof(T), v.size());
  }
  void text(std::string_view name, std::string_view s) { bytes(name, s.data(), 1, s.size()); }

  // Writes the file (temporary name, then rename); returns its size in bytes. Throws Error
  // naming the file when it cannot be written (disk full).
  std::uint64_t save(const std::filesystem::path& path) const;
  // The bytes save() would write, kept in memory (implicit coupling rolls every participant back
  // to its window-start state between iterations without touching the disk).
  std::string encode() const;

 private:
  std::string kind_;
  std::uint64_t records_ = 0;
  std::string body_;
};

class Reader {
 public:
  // Reads and checks the whole file: magic, format version, checksum, and the kind when
  // `expected_kind` is not empty.
  explicit Reader(const std::filesystem::path& path, std::string_view expected_kind = {});
  // The same checks on bytes from Writer::encode(); `label` names them in messages.
  Reader(std::string bytes, const std::filesystem::path& label, std::string_view expected_kind);

  const std::filesystem::path& file() const { return file_; }
  const std::string& kind() const { return kind_; }
  bool has(std::string_view name) const { return records_.contains(std::string(name)); }

  template <class T>
  T value(std::string_view name) const {
    T v{};
    copy(name, reinterpret_cast<char*>(&v), sizeof(T), 1, true);
    return v;
  }
  template <class T>
  std::vector<T> vector(std::string_view name) const {
    std::vector<T> v(count(name, sizeof(T)));
    copy(name, reinterpret_cast<char*>(v.data()), sizeof(T), v.size(), false);
    return v;
  }
  // Into an existing vector of the same length (`what` names it in the error otherwise).
  template <class T>
  void vector_into(std::string_view name, std::vector<T>& v) const {
    if (count(name, sizeof(T)) != v.size()) {
      fail(name, "holds " + std::to_string(count(name, sizeof(T))) + " values where this run has " +
                     std::to_string(v.size()) + " (a checkpoint of another scene?)");
    }
    copy(name, reinterpret_cast<char*>(v.data()), sizeof(T), v.size(), false);
  }
  std::string text(std::string_view name) const;

  [[noreturn]] void fail(std::string_view name, const std::string& problem) const;

 private:
  struct Record {
    std::uint64_t element_size = 0;
    std::uint64_t count = 0;
    std::size_t offset = 0;
  };
  void parse(std::string_view expected_kind);
  const Record& find(std::string_view name) const;
  std::size_t count(std::string_view name, std::size_t element_size) const;
  void copy(std::string_view name, char* out, std::size_t element_size, std::size_t count,
            bool exact) const;

  std::filesystem::path file_;
  std::string kind_;
  std::string data_;
  std::map<std::string, Record> records_;
};

// Checks a file without reading its records (the launcher, before any process starts): throws
// Error naming the file when it is missing, cut, damaged or of another format version.
struct FileInfo {
  std::string kind;
  std::uint64_t bytes = 0;
  std::uint32_t checksum = 0;
};
FileInfo verify(const std::filesystem::path& path);

// CRC-32 (IEEE 802.3, as zlib's crc32) of `data`, continuing from `crc`.
std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace cosim::checkpoint

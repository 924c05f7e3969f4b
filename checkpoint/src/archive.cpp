#include "cosim/checkpoint/archive.hpp"

#include <zlib.h>

#include <cerrno>
#include <fstream>
#include <system_error>

namespace cosim::checkpoint {

namespace {

constexpr char kMagic[8] = {'C', 'O', 'S', 'I', 'M', 'C', 'K', 'P'};

template <class T>
void append(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// Reads the file whole; the checks below then work on memory.
std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open the checkpoint file (missing?)");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(path.string() + ": read error");
  return data;
}

// A cursor over the file's bytes that names the file and the byte offset when the file ends
// early.
class Cursor {
 public:
  Cursor(const std::filesystem::path& path, const std::string& data, std::size_t end)
      : path_(path), data_(data), end_(end) {}
  template <class T>
  T take(const char* what) {
    T value{};
    need(sizeof(T), what);
    std::memcpy(&value, data_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  std::string take_text(const char* what) {
    const auto size = take<std::uint32_t>(what);
    need(size, what);
    std::string text(data_.data() + at_, size);
    at_ += size;
    return text;
  }
  void skip(std::uint64_t size, const char* what) {
    need(size, what);
    at_ += static_cast<std::size_t>(size);
  }
  std::size_t at() const { return at_; }

 private:
  void need(std::uint64_t size, const char* what) const {
    if (size > end_ - at_) {
      throw Error(path_.string() + ": damaged checkpoint: " + what + " at byte " +
                  std::to_string(at_) + " runs past the end of the records");
    }
  }
  const std::filesystem::path& path_;
  const std::string& data_;
  std::size_t end_;
  std::size_t at_ = 0;
};

// Magic, version and checksum; returns the cursor after the kind, with the kind.
std::pair<std::string, std::size_t> check_envelope(const std::filesystem::path& path,
                                                   const std::string& data,
                                                   std::uint32_t* checksum) {
  const std::string name = path.string();
  if (data.size() < sizeof(kMagic) + 4 + 4 + 8 + 4 ||
      std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0) {
    throw Error(name + ": not a checkpoint file (no COSIMCKP header, " +
                std::to_string(data.size()) + " bytes)");
  }
  std::uint32_t stored = 0;
  std::memcpy(&stored, data.data() + data.size() - 4, 4);
  const std::uint32_t computed = crc32(data.data(), data.size() - 4);
  Cursor cursor(path, data, data.size() - 4);
  cursor.skip(sizeof(kMagic), "magic");
  const auto version = cursor.take<std::uint32_t>("format version");
  if (version != kFormatVersion) {
    throw Error(name + ": checkpoint format version " + std::to_string(version) +
                " where this build reads version " + std::to_string(kFormatVersion));
  }
  if (stored != computed) {
    throw Error(name + ": damaged checkpoint: checksum mismatch (stored " + std::to_string(stored) +
                ", computed " + std::to_string(computed) + ")");
  }
  if (checksum) *checksum = stored;
  std::string kind = cursor.take_text("kind");
  return {std::move(kind), cursor.at()};
}

}  // namespace

std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc) {
  // zlib's crc32_z takes a size_t length (crc32 takes 32 bits: a checkpoint may exceed 4 GB).
  return static_cast<std::uint32_t>(
      ::crc32_z(crc, static_cast<const Bytef*>(data), static_cast<z_size_t>(size)));
}

void Writer::bytes(std::string_view name, const void* data, std::size_t element_size,
                   std::size_t count) {
  append(body_, static_cast<std::uint32_t>(name.size()));
  body_.append(name);
  append(body_, static_cast<std::uint64_t>(element_size));
  append(body_, static_cast<std::uint64_t>(count));
  if (count > 0) body_.append(static_cast<const char*>(data), element_size * count);
  ++records_;
}

std::string Writer::encode() const {
  std::string data(kMagic, sizeof(kMagic));
  append(data, kFormatVersion);
  append(data, static_cast<std::uint32_t>(kind_.size()));
  data.append(kind_);
  append(data, records_);
  data.append(body_);
  append(data, crc32(data.data(), data.size()));
  return data;
}

std::uint64_t Writer::save(const std::filesystem::path& path) const {
  std::string head(kMagic, sizeof(kMagic));
  append(head, kFormatVersion);
  append(head, static_cast<std::uint32_t>(kind_.size()));
  head.append(kind_);
  append(head, records_);
  const std::uint32_t crc = crc32(body_.data(), body_.size(), crc32(head.data(), head.size()));
  auto temporary = path;
  temporary += ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw Error(path.string() + ": cannot write the checkpoint: " +
                  std::error_code(errno, std::generic_category()).message());
    }
    out.write(head.data(), static_cast<std::streamsize>(head.size()));
    out.write(body_.data(), static_cast<std::streamsize>(body_.size()));
    out.write(reinterpret_cast<const char*>(&crc), sizeof(crc));
    out.flush();
    if (!out) {
      const auto cause = std::error_code(errno, std::generic_category()).message();
      out.close();
      std::filesystem::remove(temporary);
      throw Error(path.string() + ": cannot write the checkpoint: " + cause);
    }
  }
  std::filesystem::rename(temporary, path);
  return head.size() + body_.size() + sizeof(crc);
}

Reader::Reader(const std::filesystem::path& path, std::string_view expected_kind)
    : file_(path), data_(read_file(path)) {
  parse(expected_kind);
}

Reader::Reader(std::string bytes, const std::filesystem::path& label,
               std::string_view expected_kind)
    : file_(label), data_(std::move(bytes)) {
  parse(expected_kind);
}

void Reader::parse(std::string_view expected_kind) {
  const std::filesystem::path& path = file_;
  auto [kind, start] = check_envelope(path, data_, nullptr);
  kind_ = std::move(kind);
  if (!expected_kind.empty() && kind_ != expected_kind) {
    throw Error(path.string() + ": a checkpoint of '" + kind_ + "', not of '" +
                std::string(expected_kind) + "'");
  }
  Cursor cursor(path, data_, data_.size() - 4);
  cursor.skip(start, "header");
  const auto records = cursor.take<std::uint64_t>("record count");
  for (std::uint64_t r = 0; r < records; ++r) {
    const std::string name = cursor.take_text("record name");
    Record record;
    record.element_size = cursor.take<std::uint64_t>("element size");
    record.count = cursor.take<std::uint64_t>("element count");
    record.offset = cursor.at();
    if (record.element_size != 0 && record.count > data_.size() / record.element_size) {
      fail(name, "claims more values than the file holds");
    }
    cursor.skip(record.element_size * record.count, "record values");
    records_[name] = record;
  }
  if (cursor.at() != data_.size() - 4) {
    throw Error(path.string() + ": damaged checkpoint: " +
                std::to_string(data_.size() - 4 - cursor.at()) + " bytes after the last record");
  }
}

void Reader::fail(std::string_view name, const std::string& problem) const {
  throw Error(file_.string() + ": record '" + std::string(name) + "' " + problem);
}

const Reader::Record& Reader::find(std::string_view name) const {
  const auto found = records_.find(std::string(name));
  if (found == records_.end()) {
    fail(name, "is missing (a checkpoint of another build or participant?)");
  }
  return found->second;
}

std::size_t Reader::count(std::string_view name, std::size_t element_size) const {
  const Record& record = find(name);
  if (record.element_size != element_size) {
    fail(name, "has " + std::to_string(record.element_size) + "-byte values where this build has " +
                   std::to_string(element_size));
  }
  return static_cast<std::size_t>(record.count);
}

void Reader::copy(std::string_view name, char* out, std::size_t element_size, std::size_t n,
                  bool exact) const {
  const Record& record = find(name);
  if (record.element_size != element_size || (exact && record.count != n)) {
    fail(name, "has " + std::to_string(record.count) + " values of " +
                   std::to_string(record.element_size) + " bytes where " + std::to_string(n) +
                   " of " + std::to_string(element_size) + " were expected");
  }
  if (n > 0) std::memcpy(out, data_.data() + record.offset, element_size * n);
}

std::string Reader::text(std::string_view name) const {
  const Record& record = find(name);
  if (record.element_size != 1) fail(name, "is not text");
  return std::string(data_.data() + record.offset, static_cast<std::size_t>(record.count));
}

FileInfo verify(const std::filesystem::path& path) {
  const std::string data = read_file(path);
  FileInfo info;
  info.kind = check_envelope(path, data, &info.checksum).first;
  info.bytes = data.size();
  return info;
}

}  // namespace cosim::checkpoint

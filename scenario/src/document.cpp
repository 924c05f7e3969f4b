#include "cosim/scenario/document.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <string>

#include "cosim/scenario/section.hpp"

namespace cosim::scenario {

namespace {

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string describe_size(std::uintmax_t bytes) {
  if (bytes >= 1024u * 1024u) {
    return fmt::format("{:.1f} MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  }
  return fmt::format("{} bytes", bytes);
}

void check_file_kind(const std::filesystem::path& file, const struct stat& info,
                     std::uintmax_t max_bytes) {
  if (!S_ISREG(info.st_mode)) {
    throw ScenarioError(fmt::format("{}: is {}, not a scenario file (a regular file is needed)",
                                    file.string(), kind_of(info.st_mode)));
  }
  const auto size = static_cast<std::uintmax_t>(info.st_size);
  if (size > max_bytes) {
    throw ScenarioError(fmt::format("{}: is {} ({} bytes); scenario files are limited to {}",
                                    file.string(), describe_size(size), size,
                                    describe_size(max_bytes)));
  }
}

// Reads the whole file. The checks before and after open() keep a FIFO or device from blocking
// the command: stat() refuses it before opening, O_NONBLOCK keeps open() from waiting if the
// path was swapped in between, and fstat() checks what was actually opened.
std::string read_regular_file(const std::filesystem::path& file, std::uintmax_t max_bytes) {
  struct stat info {};
  if (::stat(file.c_str(), &info) != 0) {
    if (errno == ENOENT) throw ScenarioError(fmt::format("{}: file not found", file.string()));
    throw ScenarioError(fmt::format("{}: cannot read: {}", file.string(), std::strerror(errno)));
  }
  check_file_kind(file, info, max_bytes);
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    throw ScenarioError(fmt::format("{}: cannot open: {}", file.string(), std::strerror(errno)));
  }
  std::string content;
  try {
    if (::fstat(fd, &info) != 0) {
      throw ScenarioError(fmt::format("{}: cannot read: {}", file.string(), std::strerror(errno)));
    }
    check_file_kind(file, info, max_bytes);
    content.reserve(static_cast<std::size_t>(info.st_size));
    char buffer[65536];
    while (true) {
      const ssize_t got = ::read(fd, buffer, sizeof buffer);
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) {
        throw ScenarioError(
            fmt::format("{}: read failed: {}", file.string(), std::strerror(errno)));
      }
      if (got == 0) break;
      content.append(buffer, static_cast<std::size_t>(got));
      // A file that grows while being read is held to the same limit.
      if (content.size() > max_bytes) {
        throw ScenarioError(
            fmt::format("{}: grew beyond {} while being read; scenario files are "
                        "limited to {}",
                        file.string(), describe_size(content.size()), describe_size(max_bytes)));
      }
    }
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  return content;
}

std::string key_text(const YAML::Node& key) {
  if (key.IsScalar()) return key.Scalar();
  YAML::Emitter emitter;
  emitter << YAML::Flow << key;
  return emitter.c_str();
}

void check_node(const YAML::Node& node, const std::string& path,
                const std::filesystem::path& file) {
  if (node.IsSequence()) {
    for (std::size_t index = 0; index < node.size(); ++index) {
      check_node(node[index], fmt::format("{}[{}]", path, index), file);
    }
    return;
  }
  if (!node.IsMap()) return;
  std::map<std::string, int> first_line;  // key -> its line (1-based)
  for (const auto& entry : node) {
    const std::string key = key_text(entry.first);
    const std::string dotted = path.empty() ? key : path + "." + key;
    const int line = entry.first.Mark().line + 1;
    const auto [found, inserted] = first_line.emplace(key, line);
    if (!inserted) {
      throw ScenarioError(fmt::format("{}:{}: key '{}': appears twice (first at line {})",
                                      file.string(), line, dotted, found->second));
    }
    check_node(entry.second, dotted, file);
  }
}

}  // namespace

void check_duplicate_keys(const YAML::Node& document, const std::filesystem::path& file) {
  check_node(document, "", file);
}

YAML::Node load_document(const std::filesystem::path& file, std::uintmax_t max_bytes) {
  const std::string content = read_regular_file(file, max_bytes);
  YAML::Node document;
  try {
    document = YAML::Load(content);
  } catch (const YAML::Exception& error) {
    throw ScenarioError(
        fmt::format("{}:{}: YAML syntax error: {}", file.string(), error.mark.line + 1, error.msg));
  }
  check_duplicate_keys(document, file);
  return document;
}

}  // namespace cosim::scenario

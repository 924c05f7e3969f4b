#include "cosim/output/files.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace cosim::output {

namespace {

// Writes everything or returns the errno of the failing call (0 on success). POSIX calls rather
// than a stream, because a stream only says that something failed, not what.
int write_all(const std::filesystem::path& file, const std::string& content) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return errno;
  std::size_t written = 0;
  int error = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      error = errno;
      break;
    }
    written += static_cast<std::size_t>(n);
  }
  // close() reports errors of delayed writes (NFS, some quota setups): it counts too.
  if (::close(fd) != 0 && error == 0) error = errno;
  return error;
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path, const std::string& content) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  if (const int error = write_all(tmp, content); error != 0) {
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write '" + path.string() + "': " + std::strerror(error));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write '" + path.string() + "' (renaming '" + tmp.string() +
                             "' over it): " + std::strerror(error));
  }
}

}  // namespace cosim::output

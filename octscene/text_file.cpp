#include "text_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace octbake::scene {

Result<std::string> read_text_file(const std::string& path, size_t max_bytes) {
  // stat before open: opening a FIFO blocks until a writer comes, and a
  // device (/dev/zero) never ends. A pipe is accepted, as `cat` would.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    return Error{err == ENOENT ? ErrorCode::not_found : ErrorCode::io_error,
                 path + ": cannot open: " + std::strerror(err)};
  }
  if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode))
    return Error{ErrorCode::io_error, path + ": not a regular file or a pipe"};
  const std::string too_large = path + ": larger than " + std::to_string(max_bytes) + " bytes";
  if (S_ISREG(st.st_mode) && static_cast<unsigned long long>(st.st_size) > max_bytes)
    return Error{ErrorCode::io_error, too_large};

  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    return Error{ErrorCode::io_error, path + ": cannot open: " + std::strerror(err)};
  }
  std::string text;
  if (S_ISREG(st.st_mode)) text.reserve(static_cast<size_t>(st.st_size));
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      return Error{ErrorCode::io_error, path + ": read failed: " + std::strerror(err)};
    }
    if (text.size() + static_cast<size_t>(n) > max_bytes) {
      ::close(fd);
      return Error{ErrorCode::io_error, too_large};
    }
    text.append(buffer, static_cast<size_t>(n));
  }
  ::close(fd);
  return text;
}

}  // namespace octbake::scene

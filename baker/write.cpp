#include "write.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <utility>
#include <vector>

// Header-only use of libxxhash-dev: no link dependency for the baker.
#define XXH_INLINE_ALL
#include <xxhash.h>

namespace octbake {
namespace {

Error errno_error(const char* what) {
  const int e = errno;
  return Error{e == ENOENT ? ErrorCode::not_found : ErrorCode::io_error, std::string(what) + std::strerror(e)};
}

// Closes a descriptor on scope exit unless released.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

std::atomic<uint64_t> temp_counter{0};

// Canonical (big endian) lowercase hex of a hash: the same on every machine.
std::string hex_of(XXH128_hash_t hash) {
  XXH128_canonical_t canon;
  XXH128_canonicalFromHash(&canon, hash);
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned char b : canon.digest) {
    hex += kHex[b >> 4];
    hex += kHex[b & 15];
  }
  return hex;
}

}  // namespace

Result<std::string> hash_file(const std::string& path) {
  // O_NONBLOCK: a FIFO would block the open until a writer came; it is then
  // refused with every other file that is not regular (a device such as
  // /dev/zero would be read forever).
  Fd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (fd.get() < 0) return errno_error("cannot open: ");
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) return errno_error("cannot stat: ");
  if (S_ISDIR(st.st_mode)) return Error{ErrorCode::io_error, "is a directory, not a mesh file"};
  if (!S_ISREG(st.st_mode)) return Error{ErrorCode::io_error, "not a regular file"};

  XXH3_state_t* state = XXH3_createState();
  if (state == nullptr || XXH3_128bits_reset(state) == XXH_ERROR) {
    XXH3_freeState(state);
    return Error{ErrorCode::io_error, "cannot initialise the hash"};
  }
  std::vector<char> buf(1 << 16);
  for (;;) {
    const ssize_t n = ::read(fd.get(), buf.data(), buf.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      XXH3_freeState(state);
      return errno_error("cannot read: ");
    }
    if (n == 0) break;
    XXH3_128bits_update(state, buf.data(), static_cast<size_t>(n));
  }
  const XXH128_hash_t digest = XXH3_128bits_digest(state);
  XXH3_freeState(state);
  return hex_of(digest);
}

std::string hash_bytes(std::span<const uint8_t> bytes) { return hex_of(XXH3_128bits(bytes.data(), bytes.size())); }

Result<uint64_t> write_file_atomic(const std::string& path, std::span<const uint8_t> bytes) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  // .<name>.tmp.<pid>.<n>; <name> is cut so the temp name stays within the
  // 255 bytes a file name may have, or a long output name could not be
  // written although it fits itself (pid and counter keep it unique).
  const std::string suffix = ".tmp." + std::to_string(::getpid()) + "." + std::to_string(temp_counter.fetch_add(1));
  constexpr size_t kMaxFileName = 255;
  const std::string temp_name =
      "." + target.filename().string().substr(0, kMaxFileName - 1 - suffix.size()) + suffix;
  const std::string temp = (dir / temp_name).string();

  Fd fd(::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666));
  if (fd.get() < 0) return errno_error("cannot create temp file: ");
  auto fail = [&](const char* what) {
    Error err = errno_error(what);
    ::unlink(temp.c_str());
    return err;
  };
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd.get(), bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return fail("cannot write: ");
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd.get()) != 0) return fail("cannot fsync: ");
  if (::close(fd.release()) != 0) return fail("cannot close: ");
  if (::rename(temp.c_str(), path.c_str()) != 0) return fail("cannot rename into place: ");
  // Make the rename itself durable; a failure here leaves a complete file.
  Fd dir_fd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir_fd.get() >= 0) ::fsync(dir_fd.get());
  return static_cast<uint64_t>(bytes.size());
}

bool is_temp_name(const std::string& file_name, long* pid) {
  // .<name>.tmp.<pid>.<n>, name non-empty, pid and n decimal.
  if (file_name.size() < 2 || file_name[0] != '.') return false;
  const size_t last_dot = file_name.rfind('.');
  if (last_dot == std::string::npos || last_dot + 1 == file_name.size()) return false;
  const size_t pid_dot = file_name.rfind('.', last_dot - 1);
  if (pid_dot == std::string::npos || pid_dot + 1 == last_dot) return false;
  auto digits = [&](size_t from, size_t to) {
    for (size_t i = from; i < to; ++i)
      if (file_name[i] < '0' || file_name[i] > '9') return false;
    return to - from <= 9;
  };
  if (!digits(last_dot + 1, file_name.size()) || !digits(pid_dot + 1, last_dot)) return false;
  constexpr std::string_view kTmp = ".tmp";
  if (pid_dot < 1 + 1 + kTmp.size() || file_name.compare(pid_dot - kTmp.size(), kTmp.size(), kTmp) != 0) return false;
  if (pid != nullptr) *pid = std::stol(file_name.substr(pid_dot + 1, last_dot - pid_dot - 1));
  return true;
}

int remove_stale_temps(const std::string& dir) {
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return 0;
  int removed = 0;
  while (const dirent* e = ::readdir(d)) {
    long pid = 0;
    const std::string name = e->d_name;
    if (!is_temp_name(name, &pid) || pid == ::getpid()) continue;
    // Only when the writer is certainly gone (ESRCH); EPERM means it lives.
    if (pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH &&
        ::unlink((std::filesystem::path(dir) / name).c_str()) == 0)
      ++removed;
  }
  ::closedir(d);
  return removed;
}

}  // namespace octbake

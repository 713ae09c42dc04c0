#include "import_child.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <type_traits>

extern char** environ;

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define OCTBAKE_HAS_SANITIZER 1
#endif
#endif
#ifndef OCTBAKE_HAS_SANITIZER
#define OCTBAKE_HAS_SANITIZER 0
#endif

namespace octbake {
namespace {

// The child's answer on its stdout: magic, the files read, then the mesh
// or the error. Native byte order: the child is this same executable.
constexpr const char* kParentVariable = "OCTBAKE_IMPORT_PARENT";
constexpr char kMagic[8] = {'O', 'C', 'T', 'B', 'I', 'M', 'P', '1'};
static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
static_assert(sizeof(std::array<uint32_t, 3>) == 3 * sizeof(uint32_t));

void put_bytes(std::string& out, const void* data, size_t size) { out.append(static_cast<const char*>(data), size); }
template <class T>
void put(std::string& out, const T& value) {
  static_assert(std::is_trivially_copyable_v<T>);
  put_bytes(out, &value, sizeof value);
}
void put_string(std::string& out, const std::string& s) {
  put(out, uint64_t{s.size()});
  put_bytes(out, s.data(), s.size());
}

std::string encode(const Result<Mesh>& mesh, const std::vector<std::string>& files_read) {
  std::string out(kMagic, sizeof kMagic);
  put(out, uint64_t{files_read.size()});
  for (const std::string& f : files_read) put_string(out, f);
  put(out, uint8_t{mesh.ok()});
  if (mesh.ok()) {
    put(out, uint64_t{mesh->positions.size()});
    put_bytes(out, mesh->positions.data(), mesh->positions.size() * sizeof(Eigen::Vector3d));
    put(out, uint64_t{mesh->triangles.size()});
    put_bytes(out, mesh->triangles.data(), mesh->triangles.size() * sizeof(mesh->triangles[0]));
  } else {
    put(out, static_cast<uint32_t>(mesh.error().code));
    put_string(out, mesh.error().message);
  }
  return out;
}

// Reads what encode() wrote; every count is checked against the bytes
// left before anything is allocated, so a truncated answer is refused.
class Decoder {
 public:
  explicit Decoder(const std::string& bytes) : bytes_(bytes) {}
  bool take(void* out, uint64_t size) {
    if (size > bytes_.size() - at_) return false;
    std::memcpy(out, bytes_.data() + at_, size);
    at_ += size;
    return true;
  }
  template <class T>
  bool get(T& value) { return take(&value, sizeof value); }
  bool get_string(std::string& s) {
    uint64_t size = 0;
    if (!get(size) || size > bytes_.size() - at_) return false;
    s.assign(bytes_.data() + at_, size);
    at_ += size;
    return true;
  }
  template <class T>
  bool get_array(std::vector<T>& items) {
    uint64_t count = 0;
    if (!get(count) || count > (bytes_.size() - at_) / sizeof(T)) return false;
    items.resize(count);
    return take(items.data(), count * sizeof(T));
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  const std::string& bytes_;
  size_t at_ = 0;
};

std::optional<Result<Mesh>> decode(const std::string& bytes, std::vector<std::string>* files_read) {
  Decoder in(bytes);
  char magic[sizeof kMagic];
  uint64_t file_count = 0;
  if (!in.take(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0 || !in.get(file_count) ||
      file_count > bytes.size())
    return std::nullopt;
  std::vector<std::string> files(file_count);
  for (std::string& f : files)
    if (!in.get_string(f)) return std::nullopt;
  uint8_t ok = 0;
  if (!in.get(ok) || ok > 1) return std::nullopt;
  std::optional<Result<Mesh>> result;
  if (ok == 1) {
    Mesh mesh;
    if (!in.get_array(mesh.positions) || !in.get_array(mesh.triangles)) return std::nullopt;
    result.emplace(std::move(mesh));
  } else {
    uint32_t code = 0;
    std::string message;
    if (!in.get(code) || code > uint32_t(ErrorCode::invalid_argument) || !in.get_string(message)) return std::nullopt;
    result.emplace(Error{ErrorCode(code), std::move(message)});
  }
  if (!in.done()) return std::nullopt;
  if (files_read != nullptr) files_read->insert(files_read->end(), files.begin(), files.end());
  return result;
}

const char* signal_name(int sig) {
  switch (sig) {
    case SIGSEGV: return "SIGSEGV";
    case SIGABRT: return "SIGABRT";
    case SIGBUS: return "SIGBUS";
    case SIGFPE: return "SIGFPE";
    case SIGILL: return "SIGILL";
    case SIGKILL: return "SIGKILL";
    case SIGTERM: return "SIGTERM";
    default: return nullptr;
  }
}

Error failed(const std::string& path, const std::string& reason) {
  return Error{ErrorCode::invalid_argument, path + ": " + reason};
}

// A child started with its stdout on a pipe and its stderr on /dev/null
// (an assimp assert prints there: the parent's error line is the one line).
struct Child {
  pid_t pid = -1;
  int out = -1;  // read end of the child's stdout
};

// The child's environment: this one, with glibc's malloc asked to back big
// blocks with huge pages. assimp's OBJ reader zeroes a 16 MB buffer; in a
// fresh process its 4,096 page faults were most of an import's cost (19 ->
// 8 ms a one-triangle OBJ here). Other C libraries ignore the setting.
// It also names this process (kParentVariable), so the child can tell
// whether it outlived it.
std::vector<std::string> child_environment() {
  std::vector<std::string> env;
  std::string tunables = "GLIBC_TUNABLES=glibc.malloc.hugetlb=1";
  const std::string parent_prefix = std::string(kParentVariable) + "=";
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::strncmp(*e, "GLIBC_TUNABLES=", 15) == 0) tunables = std::string(*e) + ":glibc.malloc.hugetlb=1";
    else if (std::strncmp(*e, parent_prefix.c_str(), parent_prefix.size()) != 0) env.emplace_back(*e);
  }
  env.push_back(tunables);
  env.push_back(parent_prefix + std::to_string(::getpid()));
  return env;
}

std::optional<Child> spawn(const std::string& helper, const std::string& path) {
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) return std::nullopt;  // close-on-exec: no other child inherits it
  posix_spawn_file_actions_t actions;
  posix_spawnattr_t attr;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawnattr_init(&attr);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  std::string flag = kImportChildFlag, helper_arg = helper, path_arg = path;
  char* argv[] = {helper_arg.data(), flag.data(), path_arg.data(), nullptr};
  std::vector<std::string> env = child_environment();
  std::vector<char*> envp;
  for (std::string& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  Child child;
  int rc = ::posix_spawn(&child.pid, helper.c_str(), &actions, &attr, argv, envp.data());
  // A process limit reached for a moment (many jobs): wait a little, up to ~1 s.
  for (int pause_ms = 5; rc == EAGAIN && pause_ms <= 320; pause_ms *= 2) {
    ::usleep(static_cast<useconds_t>(1000 * pause_ms));
    rc = ::posix_spawn(&child.pid, helper.c_str(), &actions, &attr, argv, envp.data());
  }
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(pipe_fds[1]);
  if (rc != 0) {
    ::close(pipe_fds[0]);
    return std::nullopt;
  }
  child.out = pipe_fds[0];
  return child;
}

using Clock = std::chrono::steady_clock;

// Reads the child's stdout to its end, then waits for it to exit; false
// when the deadline (none when `timeout_s` is 0) passed first. A child
// can close its stdout and go on running, so the wait has the deadline too.
bool read_all_and_wait(const Child& child, double timeout_s, std::string& bytes, int& status) {
  // Past a century is no limit at all, and would overflow the clock.
  if (timeout_s > 3e9) timeout_s = 0;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  auto ms_left = [&]() -> long long {
    if (timeout_s <= 0) return -1;
    return std::max<long long>(0, std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count());
  };
  char chunk[1 << 16];
  for (;;) {
    const long long left = ms_left();
    if (left == 0) return false;
    pollfd p{child.out, POLLIN, 0};
    const int ready = ::poll(&p, 1, left < 0 ? -1 : static_cast<int>(std::min<long long>(left, 1 << 30)));
    if (ready < 0 && errno != EINTR) break;  // cannot wait: take what came
    if (ready <= 0) continue;
    const ssize_t n = ::read(child.out, chunk, sizeof chunk);
    if (n > 0) bytes.append(chunk, size_t(n));
    else if (n == 0 || (errno != EINTR && errno != EAGAIN)) break;
  }
  for (int pause_ms = 1;; pause_ms = std::min(pause_ms * 2, 50)) {
    const pid_t done = ::waitpid(child.pid, &status, WNOHANG);
    if (done == child.pid || (done < 0 && errno != EINTR)) return true;
    const long long left = ms_left();
    if (left == 0) return false;
    ::usleep(static_cast<useconds_t>(1000 * (left < 0 ? pause_ms : std::min<long long>(pause_ms, left))));
  }
}

// A malformed file can make assimp allocate without end (a PLY face that
// claims 2^31 indices took 16 GB in 5 s). The child caps its address space
// at half the machine's memory, so such an import fails with bad_alloc, and
// asks the kernel to kill it first should memory still run out. Sanitizer
// builds reserve terabytes of address space up front: no cap there.
void limit_memory() {
  if (std::FILE* f = std::fopen("/proc/self/oom_score_adj", "w")) {
    std::fputs("1000", f);
    std::fclose(f);
  }
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__) && !OCTBAKE_HAS_SANITIZER
  const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGE_SIZE);
  rlimit limit{};
  if (pages > 0 && page_size > 0 && ::getrlimit(RLIMIT_AS, &limit) == 0) {
    // Lower only: a limit the user set (ulimit -v) stays as it is.
    limit.rlim_cur = std::min<rlim_t>(limit.rlim_cur, rlim_t(pages) / 2 * rlim_t(page_size));
    ::setrlimit(RLIMIT_AS, &limit);
  }
#endif
}

// A child whose octbake was killed (SIGKILL, so nothing could stop it) must
// not import on, a hang for ever: the kernel kills it with its parent. The
// parent may have died before that was asked: then it is no longer our
// parent, and the child stops at once.
void die_with_parent() {
#ifdef __linux__
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
  const char* parent = std::getenv(kParentVariable);
  if (parent != nullptr && *parent != '\0' && std::to_string(::getppid()) != parent) ::_exit(1);
}

}  // namespace

int run_import_child(const char* path, int out_fd) {
  die_with_parent();
  limit_memory();
  std::vector<std::string> files_read;
  const std::string bytes = encode(load_mesh(path, &files_read), files_read);
  for (size_t at = 0; at < bytes.size();) {
    const ssize_t n = ::write(out_fd, bytes.data() + at, bytes.size() - at);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return 1;
    at += size_t(n);
  }
  return 0;
}

Result<Mesh> load_mesh_in_child(const std::string& helper, const std::string& path,
                                std::vector<std::string>* files_read, double timeout_s) {
  std::optional<Child> child = spawn(helper, path);
  if (!child) return load_mesh(path, files_read);
  std::string bytes;
  int status = 0;
  const bool finished = read_all_and_wait(*child, timeout_s, bytes, status);
  ::close(child->out);
  if (!finished) {
    ::kill(child->pid, SIGKILL);
    while (::waitpid(child->pid, &status, 0) < 0 && errno == EINTR) {
    }
    char limit[32];
    std::snprintf(limit, sizeof limit, "%g", timeout_s);
    return failed(path, std::string("the importer did not finish within ") + limit + " s (see --import-timeout)");
  }
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = signal_name(sig);
    return failed(path, "the importer crashed on this file (" + (name ? std::string(name) : "signal " + std::to_string(sig)) + ")");
  }
  // 127 and no answer: the helper could not be run (where posix_spawn
  // reports a failed exec only this way: qemu-user, fork-based C libraries).
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127 && bytes.empty()) return load_mesh(path, files_read);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    if (std::optional<Result<Mesh>> result = decode(bytes, files_read)) return std::move(*result);
    return failed(path, "the importer gave a malformed answer");
  }
  return failed(path, "the importer stopped without a result (exit status " +
                          std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
}

}  // namespace octbake

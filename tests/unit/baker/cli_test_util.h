// Helpers for the tests that run the `octbake` binary: temp folders, spawning
// with captured output, seeded mesh files.
#pragma once
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "unit/runtime/baked_test_util.h"  // unit(), wide_tree()

namespace octbake::test {

namespace fs = std::filesystem;

// A fresh folder per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "octbake_cli_XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) std::abort();
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& rel) const { return (path_ / rel).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

struct RunResult {
  int exit_code = -1;  // -1: killed by a signal
  std::string out, err;
  // Lines of `err`, without the newline.
  std::vector<std::string> err_lines() const {
    std::vector<std::string> lines;
    std::istringstream in(err);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  }
};

inline pid_t spawn(const std::vector<std::string>& args, int out_fd, int err_fd) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(out_fd, 1);
    ::dup2(err_fd, 2);
    ::close(0);
    std::vector<char*> argv;
    std::string bin = OCTBAKE_BIN;
    argv.push_back(bin.data());
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(bin.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

// Runs `octbake args...`, capturing stdout, stderr and the exit status.
inline RunResult run_octbake(const std::vector<std::string>& args) {
  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0 || ::pipe(err_pipe) != 0) std::abort();
  const pid_t pid = spawn(args, out_pipe[1], err_pipe[1]);
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  RunResult r;
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&r.out, &r.err};
  for (int open_fds = 2; open_fds > 0;) {
    if (::poll(fds, 2, -1) < 0) continue;
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buf[4096];
      const ssize_t n = ::read(fds[k].fd, buf, sizeof buf);
      if (n > 0) {
        sinks[k]->append(buf, static_cast<size_t>(n));
      } else {
        ::close(fds[k].fd);
        fds[k].fd = -1;
        --open_fds;
      }
    }
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline std::vector<uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// `n` random triangles, each near a random centre in [-1, 1]^3 with edges up
// to `size`, as OBJ text.
inline std::string random_obj(uint32_t seed, int n, double size) {
  std::mt19937 rng(seed);
  std::ostringstream s;
  s.precision(17);
  for (int t = 0; t < n; ++t) {
    double c[3];
    for (double& v : c) v = 2 * unit(rng) - 1;
    for (int k = 0; k < 3; ++k)
      s << "v " << c[0] + size * (unit(rng) - 0.5) << ' ' << c[1] + size * (unit(rng) - 0.5) << ' '
        << c[2] + size * (unit(rng) - 0.5) << '\n';
  }
  for (int t = 0; t < n; ++t) s << "f " << 3 * t + 1 << ' ' << 3 * t + 2 << ' ' << 3 * t + 3 << '\n';
  return s.str();
}

// A closed UV sphere of about 2 * rings * segments triangles, as OBJ text.
inline std::string sphere_obj(int rings, int segments) {
  std::ostringstream s;
  s.precision(17);
  const double pi = 3.14159265358979323846;
  s << "v 0 0 1\n";
  for (int r = 1; r < rings; ++r)
    for (int g = 0; g < segments; ++g) {
      const double th = pi * r / rings, ph = 2 * pi * g / segments;
      s << "v " << std::sin(th) * std::cos(ph) << ' ' << std::sin(th) * std::sin(ph) << ' ' << std::cos(th) << '\n';
    }
  s << "v 0 0 -1\n";
  auto ring_vertex = [&](int r, int g) { return 2 + (r - 1) * segments + (g % segments); };
  const int south = 2 + (rings - 1) * segments;
  for (int g = 0; g < segments; ++g) s << "f 1 " << ring_vertex(1, g) << ' ' << ring_vertex(1, g + 1) << '\n';
  for (int r = 1; r + 1 < rings; ++r)
    for (int g = 0; g < segments; ++g) {
      s << "f " << ring_vertex(r, g) << ' ' << ring_vertex(r + 1, g) << ' ' << ring_vertex(r + 1, g + 1) << '\n';
      s << "f " << ring_vertex(r, g) << ' ' << ring_vertex(r + 1, g + 1) << ' ' << ring_vertex(r, g + 1) << '\n';
    }
  for (int g = 0; g < segments; ++g)
    s << "f " << south << ' ' << ring_vertex(rings - 1, g + 1) << ' ' << ring_vertex(rings - 1, g) << '\n';
  return s.str();
}

// Identity of a file's current inode and modification time: a rename over
// the file changes it.
inline std::pair<ino_t, int64_t> file_identity(const std::string& path) {
  struct stat st {};
  ::stat(path.c_str(), &st);
  return {st.st_ino, static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
}

}  // namespace octbake::test

// Shared by the octscene tests: a scratch folder with baked trees, and a way
// to run the command-line tools.
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace octbake::scene::testing {

namespace fs = std::filesystem;

inline std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

struct Command {
  int status = -1;
  std::string out, err;
};

// Runs `command` through the shell, capturing stdout and stderr.
inline Command run_command(const std::string& command, const fs::path& scratch) {
  const fs::path out = scratch / "cmd.out", err = scratch / "cmd.err";
  const std::string line = command + " >" + out.string() + " 2>" + err.string();
  const int raw = std::system(line.c_str());
  Command c;
  c.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  c.out = read_text(out);
  c.err = read_text(err);
  return c;
}

// An axis-aligned box mesh [lo, hi] as OBJ text (12 triangles).
inline std::string box_obj(double lx, double ly, double lz, double hx, double hy, double hz) {
  std::ostringstream s;
  for (int i = 0; i < 8; ++i)
    s << "v " << ((i & 1) ? hx : lx) << ' ' << ((i & 2) ? hy : ly) << ' ' << ((i & 4) ? hz : lz) << '\n';
  // Vertex i has x = bit 0, y = bit 1, z = bit 2 (1-based in OBJ).
  s << "f 1 3 2\nf 2 3 4\nf 5 6 7\nf 6 8 7\nf 1 2 5\nf 2 6 5\n"
       "f 3 7 4\nf 4 7 8\nf 1 5 3\nf 3 5 7\nf 2 4 6\nf 4 8 6\n";
  return s.str();
}

// A scratch folder holding baked/cube.oct ([-1, 1]^3) and baked/slab.oct
// ([0, 4] x [0, 0.5] x [-1, 1], origin off centre), baked once per process and
// removed at exit.
inline const fs::path& scratch_with_trees() {
  struct Scratch {
    fs::path dir = fs::temp_directory_path() / ("octscene_test_" + std::to_string(getpid()));
    Scratch() {
      fs::remove_all(dir);
      fs::create_directories(dir);
      write_text(dir / "cube.obj", box_obj(-1, -1, -1, 1, 1, 1));
      write_text(dir / "slab.obj", box_obj(0, 0, -1, 4, 0.5, 1));
      Command c = run_command(std::string(OCTBAKE_BIN) + " -q -d 4 -o " + (dir / "baked").string() + " " +
                                  (dir / "cube.obj").string() + " " + (dir / "slab.obj").string(),
                              dir);
      if (c.status != 0) ADD_FAILURE() << "baking the test trees failed: " << c.err;
    }
    ~Scratch() {
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  };
  static const Scratch scratch;
  return scratch.dir;
}

}  // namespace octbake::scene::testing

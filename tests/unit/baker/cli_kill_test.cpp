// A baker killed at any moment leaves the old output or the complete new one,
// never a half-written target; its temp files are cleaned up by the next run.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "cli_test_util.h"
#include "octbake/baked_file.h"
#include "write.h"

namespace octbake {
namespace {

using test::TempDir;
using test::read_bytes;
using test::run_octbake;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

bool loads_completely(const std::string& path) {
  auto file = BakedFile::open(path);
  if (!file || file->trees().size() != 1) return false;
  return file->load(0, file->trees()[0].depth).ok();
}

std::vector<std::string> temp_files(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir))
    if (is_temp_name(e.path().filename().string(), nullptr)) names.push_back(e.path().filename().string());
  return names;
}

TEST(CliKill, TargetIsAlwaysTheOldOrTheNewCompleteFile) {
  TempDir t;
  const std::string in = t / "big.obj", target = t / "out/big.oct";
  // ~304k triangles at depth 10 (a 3 s bake); smaller under the sanitizers,
  // which are ~10x slower, so the suite stays within minutes.
#if defined(__SANITIZE_ADDRESS__)
  const int rings = 110, depth = 8;
#else
  const int rings = 390, depth = 10;
#endif
  test::write_text(in, test::sphere_obj(rings, /*segments=*/rings));
  const std::string d = std::to_string(depth);
  const std::vector<std::string> fresh = {"-q", "-d", d, "-o", t / "out", in};
  const std::vector<std::string> forced = {"-q", "--force", "-d", d, "-o", t / "out", in};

  // The new file, baked to completion once, timed; then the old one.
  const auto start = Clock::now();
  ASSERT_EQ(run_octbake(fresh).exit_code, 0);
  const double full_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  const auto new_bytes = read_bytes(target);
  ASSERT_EQ(run_octbake({"-q", "-d", "3", "-o", t / "out", in}).exit_code, 0);
  const auto old_bytes = read_bytes(target);
  ASSERT_NE(old_bytes, new_bytes);

  // Early (import), middle (build), late (encode, write, rename) kills.
  const double kill_ms[] = {5, 50, 200, 0.6 * full_ms, 0.9 * full_ms, 0.98 * full_ms};
  int saw_old = 0, saw_new = 0;
  for (double ms : kill_ms) {
    const pid_t pid = test::spawn(forced, 1, 2);
    std::this_thread::sleep_for(std::chrono::microseconds(static_cast<int64_t>(ms * 1000)));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    const auto bytes = read_bytes(target);
    const bool is_old = bytes == old_bytes, is_new = bytes == new_bytes;
    EXPECT_TRUE(is_old || is_new) << "kill after " << ms << " ms left " << bytes.size() << " bytes";
    EXPECT_TRUE(loads_completely(target)) << "kill after " << ms << " ms";
    saw_old += is_old;
    saw_new += is_new;
    // Start every attempt from the old file.
    if (is_new) {
      ASSERT_EQ(run_octbake({"-q", "-d", "3", "-o", t / "out", in}).exit_code, 0);
    }
  }
  EXPECT_GT(saw_old, 0) << "no kill landed before the rename (full bake " << full_ms << " ms)";
  RecordProperty("full_bake_ms", std::to_string(full_ms));
  RecordProperty("kills_old_new", std::to_string(saw_old) + "/" + std::to_string(saw_new));

  // Temp files left by the killed runs are ours and are cleaned by the next run.
  ASSERT_EQ(run_octbake({"-q", "-d", "3", "-o", t / "out", in}).exit_code, 0);
  EXPECT_TRUE(temp_files(t / "out").empty());
  EXPECT_EQ(read_bytes(target), old_bytes);
}

}  // namespace
}  // namespace octbake

// baker/write.h and the option parsers of baker/cli.h, in process.
#include <gtest/gtest.h>

#include "cli.h"
#include "cli_test_util.h"
#include "write.h"

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace octbake {
namespace {

using test::TempDir;
using test::read_bytes;
namespace fs = std::filesystem;

// Oracle: the one-shot library call on the whole buffer, canonical bytes.
std::string xxh3_hex(const std::string& bytes) {
  XXH128_canonical_t c;
  XXH128_canonicalFromHash(&c, XXH3_128bits(bytes.data(), bytes.size()));
  std::string hex;
  char buf[3];
  for (unsigned char b : c.digest) {
    std::snprintf(buf, sizeof buf, "%02x", b);
    hex += buf;
  }
  return hex;
}

TEST(CliWrite, HashMatchesTheLibraryOnRandomFilesOfManySizes) {
  TempDir t;
  std::mt19937 rng(11);
  // Sizes around the 64 KiB read buffer and XXH3's internal block sizes.
  for (size_t size : {0u, 1u, 16u, 17u, 128u, 129u, 240u, 241u, 1024u, 65535u, 65536u, 65537u, 300001u}) {
    std::string bytes(size, '\0');
    for (char& c : bytes) c = static_cast<char>(rng() >> 24);
    test::write_text(t / "f", bytes);
    auto h = hash_file(t / "f");
    ASSERT_TRUE(h.ok());
    EXPECT_EQ(*h, xxh3_hex(bytes)) << size;
    EXPECT_EQ(h->size(), 32u);
  }
  EXPECT_EQ(hash_file(t / "missing").error().code, ErrorCode::not_found);
  EXPECT_FALSE(hash_file(t.path().string()).ok());  // a directory
}

TEST(CliWrite, AtomicWriteReplacesAndLeavesNoTemp) {
  TempDir t;
  const std::string path = t / "x.oct";
  const std::vector<uint8_t> a(1000, 7), b(5, 9);
  ASSERT_EQ(*write_file_atomic(path, a), a.size());
  EXPECT_EQ(read_bytes(path), a);
  ASSERT_EQ(*write_file_atomic(path, b), b.size());
  EXPECT_EQ(read_bytes(path), b);
  EXPECT_EQ(std::distance(fs::directory_iterator(t.path()), fs::directory_iterator()), 1);

  // A target that is a folder: the rename fails, the temp is removed.
  fs::create_directories(t / "dir.oct/inner");
  EXPECT_FALSE(write_file_atomic(t / "dir.oct", a).ok());
  EXPECT_EQ(std::distance(fs::directory_iterator(t.path()), fs::directory_iterator()), 2);
  EXPECT_FALSE(write_file_atomic(t / "no/such/dir/x.oct", a).ok());

  // Names up to the 255 bytes a file name may have: the temp name is cut to
  // fit, still a temp name, and the output gets its whole name.
  for (size_t length : {200u, 240u, 250u, 255u}) {
    TempDir u;
    const std::string name = std::string(length - 4, 'y') + ".oct";
    const auto written = write_file_atomic(u / name, a);
    ASSERT_TRUE(written.ok()) << length << ": " << written.error().message;
    EXPECT_EQ(read_bytes(u / name), a);
    EXPECT_EQ(std::distance(fs::directory_iterator(u.path()), fs::directory_iterator()), 1);
  }
}

TEST(CliWrite, TempNamesAndStaleCleanup) {
  long pid = 0;
  EXPECT_TRUE(is_temp_name(".x.oct.tmp.123.0", &pid));
  EXPECT_EQ(pid, 123);
  EXPECT_TRUE(is_temp_name(".a.b.obj.tmp.9.42", nullptr));
  for (const char* name : {"x.oct", ".x.oct", ".tmp.1.2", "x.oct.tmp.1.2", ".x.oct.tmp.1.", ".x.oct.tmp..2",
                           ".x.oct.tmp.a.2", ".x.oct.tmpx.1.2", ".x.oct.tmp.1.2.oct"})
    EXPECT_FALSE(is_temp_name(name, nullptr)) << name;

  TempDir t;
  // A pid that is certainly gone: a child we started and reaped.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  const std::string dead = ".x.oct.tmp." + std::to_string(child) + ".0";
  const std::string alive = ".y.oct.tmp." + std::to_string(::getppid()) + ".0";
  for (const std::string& name : {dead, alive, std::string("keep.oct")}) test::write_text(t / name, "z");
  EXPECT_EQ(remove_stale_temps(t.path().string()), 1);
  EXPECT_FALSE(fs::exists(t / dead));
  EXPECT_TRUE(fs::exists(t / alive));
  EXPECT_TRUE(fs::exists(t / "keep.oct"));
}

TEST(CliWrite, CompressionAndOccupancyValues) {
  EXPECT_EQ(parse_compression("none"), std::pair(Compression::none, 0));
  EXPECT_EQ(parse_compression("zstd"), std::pair(Compression::zstd, 19));
  for (int level = 1; level <= 22; ++level)
    EXPECT_EQ(parse_compression("zstd:" + std::to_string(level)), std::pair(Compression::zstd, level));
  for (const char* bad : {"", "zstd:", "zstd:0", "zstd:23", "zstd:-1", "zstd:+5", "zstd:05x", "zstd:100", "zstd 3",
                          "ZSTD", "lz4", "none:1"})
    EXPECT_FALSE(parse_compression(bad).has_value()) << bad;
  EXPECT_EQ(parse_occupancy("surface"), Occupancy::surface);
  EXPECT_EQ(parse_occupancy("solid"), Occupancy::solid);
  EXPECT_EQ(parse_occupancy("vertices"), Occupancy::vertices);
  EXPECT_FALSE(parse_occupancy("Surface").has_value());
}

}  // namespace
}  // namespace octbake

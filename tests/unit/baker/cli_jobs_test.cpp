// The `octbake` binary with a thread budget (-j) shared by files and by the
// octants of one large mesh; encode_file's bytes for every thread count; the summary line when stderr is not a terminal;
// the progress line on a terminal (a pseudo-terminal here); --info --json.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <stdlib.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <cstdio>
#include <optional>
#include <random>

#include "build_tree.h"
#include "cli_test_util.h"
#include "import.h"
#include "octbake/baked_file.h"
#include "write.h"

namespace octbake {
namespace {

using test::RunResult;
using test::TempDir;
using test::read_bytes;
using test::run_octbake;
using test::write_text;

#if defined(__SANITIZE_ADDRESS__)
constexpr int kScale = 2, kBigDepth = 7;
const std::vector<std::string> kJobs = {"-j1", "-j3"};
#else
constexpr int kScale = 1, kBigDepth = 8;
const std::vector<std::string> kJobs = {"-j1", "-j2", "-j3", "-j8"};
#endif

std::vector<std::string> with(std::vector<std::string> args, const std::vector<std::string>& more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

OctreeMasks built_alone(const std::string& path, int depth, Occupancy mode) {
  auto mesh = import_mesh(path);
  EXPECT_TRUE(mesh.ok()) << path;
  return mesh ? build_tree(*mesh, depth, mode) : OctreeMasks{};
}

OctreeMasks load_tree(const std::string& path, size_t index = 0) {
  auto file = BakedFile::open(path);
  EXPECT_TRUE(file.ok()) << path;
  if (!file) return {};
  auto tree = file->load(index, file->trees().at(index).depth);
  EXPECT_TRUE(tree.ok()) << path;
  return tree ? tree->masks() : OctreeMasks{};
}

TEST(CliJobs, OneLargeMeshSameBytesForEveryJobCount) {
  TempDir t;
  const std::string big = t / "big.obj", small = t / "small.obj";
  write_text(big, test::sphere_obj(80 / kScale, 160 / kScale));  // about 25k triangles
  write_text(small, test::random_obj(9, 200, 0.2));
  const std::string depth = std::to_string(kBigDepth);
  for (const char* mode : {"surface", "solid"}) {
    SCOPED_TRACE(mode);
    std::vector<uint8_t> first, first_pack;
    for (const std::string& jobs : kJobs) {
      const std::string out = t / (std::string(mode) + jobs);
      const std::vector<std::string> common = {"-q", jobs, "-d", depth, "--occupancy", mode, "--compress", "zstd:1"};
      ASSERT_EQ(run_octbake(with(common, {"-o", out, big})).exit_code, 0) << jobs;
      const auto bytes = read_bytes(out + "/big.oct");
      ASSERT_FALSE(bytes.empty());
      if (first.empty()) first = bytes;
      EXPECT_EQ(bytes, first) << jobs << " differs from -j1";
      // Files in parallel and the large one's octants on the idle threads.
      const std::string pack = out + "/pack.oct";
      ASSERT_EQ(run_octbake(with(common, {"--pack", pack, small, big})).exit_code, 0) << jobs;
      const auto pack_bytes = read_bytes(pack);
      if (first_pack.empty()) first_pack = pack_bytes;
      EXPECT_EQ(pack_bytes, first_pack) << jobs << " pack differs from -j1";
    }
    const Occupancy occupancy = std::string(mode) == "solid" ? Occupancy::solid : Occupancy::surface;
    const OctreeMasks want = built_alone(big, kBigDepth, occupancy);
    EXPECT_EQ(load_tree(t / (mode + kJobs.back() + "/big.oct")), want) << kJobs.back() << " against one thread";
    EXPECT_EQ(load_tree(t / (mode + kJobs.back() + "/pack.oct"), 1), want);
    EXPECT_GT(want.box_count(kBigDepth), 20000u);  // large enough to split into many octants
    EXPECT_GT(want.box_count(3), 40u);
  }
}

// Level 5 for every thread count, level 19 (the default, slow) for 1 and 2.
TEST(EncodeThreads, SameBytesForEveryThreadCount) {
  TreeToEncode tree = test::wide_tree();
  const size_t deepest = tree.masks.masks.back().size();
  EXPECT_GT(deepest, size_t(512) << 10);  // past zstd's single-threaded limit (ZSTDMT_JOBSIZE_MIN)
  EXPECT_GE(encode_threads_useful({&tree, 1}), 4);  // split in jobs: the multithreaded path runs
  for (int level : {5, 19}) {
    SCOPED_TRACE(level);
    tree.options.compression_level = level;
    const std::vector<uint8_t> one = encode_file({&tree, 1}, "v", 1);
    EXPECT_EQ(encode_file({&tree, 1}, "v", 2), one) << "2 threads";
    if (level == 19) continue;
    EXPECT_EQ(encode_file({&tree, 1}, "v"), one) << "the default is one thread";
    for (int threads : {3, 8}) EXPECT_EQ(encode_file({&tree, 1}, "v", threads), one) << threads << " threads";
    EXPECT_EQ(encode_file({&tree, 1}, "v", 2), one) << "run to run";

    auto file = BakedFile::from_bytes(one, "mem");
    ASSERT_TRUE(file.ok()) << file.error().message;
    const TreeInfo& info = file->trees().at(0);
    EXPECT_LT(info.stored_bytes.back(), deepest / 2) << "the deepest level is compressed";
    auto loaded = file->load(0, info.depth);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(loaded->masks(), tree.masks);
  }
}

// "octbake: B baked, U up to date, F failed in S s (R tri/s)"
struct Summary {
  int baked = -1, up_to_date = -1, failed = -1;
};
std::optional<Summary> parse_summary(const std::string& line) {
  Summary s;
  double seconds = 0;
  char rate[32];
  int end = -1;
  if (std::sscanf(line.c_str(), "octbake: %d baked, %d up to date, %d failed in %lf s (%31[0-9.KM] tri/s)%n", &s.baked,
                  &s.up_to_date, &s.failed, &seconds, rate, &end) != 5 ||
      end != static_cast<int>(line.size()))
    return std::nullopt;
  return s;
}

// "baking F/N files, D/K tri[, R tri/s[, ETA ...][, writing 1]]"
bool is_progress_line(const std::string& line) {
  int files = -1, end = -1;
  char done[32], known[32];
  if (std::sscanf(line.c_str(), "baking %d/2 files, %31[0-9.KM]/%31[0-9.KM] tri%n", &files, done, known, &end) != 3 ||
      end < 0)
    return false;
  const std::string rest = line.substr(static_cast<size_t>(end));
  return rest.empty() || (rest.rfind(", ", 0) == 0 && rest.find(" tri/s") != std::string::npos);
}

TEST(CliSummary, OneLineOnStderrWhenNotATerminal) {
  TempDir t;
  const std::string a = t / "a.obj", b = t / "b.obj", bad = t / "bad.obj";
  write_text(a, test::random_obj(1, 50, 0.2));
  write_text(b, test::random_obj(2, 80, 0.2));
  write_text(bad, "v 0 0 0\nv 1 0 0\nthis is not obj\nf 1 2 9\n");
  const std::vector<std::string> inputs = {a, bad, b};

  struct Step {
    std::vector<std::string> args;
    int baked, up_to_date;
  };
  const Step steps[] = {{{}, 2, 0}, {{}, 0, 2}, {{"--force", "-j2"}, 2, 0}};
  for (const Step& step : steps) {
    const RunResult r = run_octbake(with(with({"-d", "4", "-o", t / "out"}, step.args), inputs));
    EXPECT_EQ(r.exit_code, 1);
    const auto lines = r.err_lines();
    ASSERT_EQ(lines.size(), 2u) << r.err;
    EXPECT_EQ(lines[0].rfind("octbake: error: " + bad + ": ", 0), 0u) << lines[0];
    const auto s = parse_summary(lines[1]);
    ASSERT_TRUE(s) << lines[1];
    EXPECT_EQ(s->baked, step.baked) << lines[1];
    EXPECT_EQ(s->up_to_date, step.up_to_date) << lines[1];
    EXPECT_EQ(s->failed, 1) << lines[1];
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << "no progress line off a terminal";
  }

  // A pack that fails to be written counts as a failure too.
  std::filesystem::create_directories(t / "blocked/p.oct");  // a folder where the pack goes
  const RunResult p = run_octbake({"-d", "3", "--pack", t / "blocked/p.oct", a, b});
  EXPECT_EQ(p.exit_code, 1);
  const auto plines = p.err_lines();
  ASSERT_EQ(plines.size(), 2u) << p.err;
  const auto ps = parse_summary(plines[1]);
  ASSERT_TRUE(ps) << plines[1];
  EXPECT_EQ(ps->baked, 2);
  EXPECT_EQ(ps->failed, 1);

  // -q: the error lines only; all good: the summary only, exit 0.
  const RunResult quiet = run_octbake(with({"-q", "-d", "4", "-o", t / "out"}, inputs));
  EXPECT_EQ(quiet.exit_code, 1);
  EXPECT_EQ(quiet.err_lines().size(), 1u) << quiet.err;
  const RunResult good = run_octbake({"-d", "4", "-o", t / "out2", a, b});
  EXPECT_EQ(good.exit_code, 0);
  ASSERT_EQ(good.err_lines().size(), 1u) << good.err;
  const auto gs = parse_summary(good.err_lines()[0]);
  ASSERT_TRUE(gs) << good.err;
  EXPECT_EQ(gs->baked, 2);
  EXPECT_EQ(gs->failed, 0);
}

// Runs octbake with stderr on a pseudo-terminal; returns what it wrote there
// (the terminal turns "\n" into "\r\n").
RunResult run_octbake_on_tty(const std::vector<std::string>& args) {
  RunResult r;
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) return r;
  const int slave = ::open(::ptsname(master), O_RDWR | O_NOCTTY);
  const int devnull = ::open("/dev/null", O_WRONLY);
  if (slave < 0 || devnull < 0) return r;
  const pid_t pid = test::spawn(args, devnull, slave);
  ::close(slave);
  ::close(devnull);
  char buf[4096];
  for (ssize_t n; (n = ::read(master, buf, sizeof buf)) > 0;) r.err.append(buf, size_t(n));  // EIO once it exits
  ::close(master);
  int status = 0;
  ::waitpid(pid, &status, 0);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(CliProgress, OnATerminalShowsAProgressLineThenTheSummary) {
  TempDir t;
  const std::string big = t / "big.obj", bad = t / "bad.obj";
  write_text(big, test::sphere_obj(80, 160));
  write_text(bad, "not a mesh\n");
  const RunResult r = run_octbake_on_tty({"-j2", "-d", "7", "-o", t / "out", bad, big});
  ASSERT_EQ(r.exit_code, 1) << r.err;
  // Split into what the terminal shows: each "\r\033[K" clears the line.
  std::vector<std::string> shown;
  std::string text = r.err;
  for (size_t k; (k = text.find("\r\n")) != std::string::npos;) text.replace(k, 2, "\n");
  const std::string clear = "\r\033[K";
  std::string current;
  for (size_t k = 0; k < text.size();) {
    if (text.compare(k, clear.size(), clear) == 0) {
      if (!current.empty()) shown.push_back(current);
      current.clear();
      k += clear.size();
    } else if (text[k] == '\n') {
      shown.push_back(current + "\n");
      current.clear();
      ++k;
    } else {
      current += text[k++];
    }
  }
  if (!current.empty()) shown.push_back(current);
  ASSERT_GE(shown.size(), 3u) << r.err;
  EXPECT_EQ(shown.front(), "baking 0/2 files, 0/0 tri") << r.err;
  size_t errors = 0, summaries = 0;
  for (size_t k = 0; k < shown.size(); ++k) {
    const std::string& s = shown[k];
    if (s.back() == '\n') {  // a line that stays: the error, then the summary last
      if (s.rfind("octbake: error: " + bad + ": ", 0) == 0) ++errors;
      if (parse_summary(s.substr(0, s.size() - 1))) {
        ++summaries;
        EXPECT_EQ(k, shown.size() - 1) << "the summary comes last";
      }
    } else {
      EXPECT_TRUE(is_progress_line(s)) << s;
    }
  }
  EXPECT_EQ(errors, 1u) << r.err;
  EXPECT_EQ(summaries, 1u) << r.err;
}

TEST(CliInfoJson, OneDocumentMatchingTheDecodedFiles) {
  TempDir t;
  const std::string a = t / "a.obj", b = t / "b.obj";
  write_text(a, test::random_obj(31, 70, 0.3));
  write_text(b, test::sphere_obj(12, 24));
  ASSERT_EQ(run_octbake({"-q", "-d", "5", "-o", t / "out", a}).exit_code, 0);
  ASSERT_EQ(run_octbake({"-q", "-d", "4", "--occupancy", "solid", "--compress", "zstd:5", "--pack", t / "p.oct", a, b})
                .exit_code,
            0);
  const auto good = read_bytes(t / "out/a.oct");
  write_text(t / "cut.oct", std::string(good.begin(), good.begin() + good.size() / 2));
  const std::vector<std::string> files = {t / "out/a.oct", t / "cut.oct", t / "p.oct", t / "missing.oct"};
  const RunResult r = run_octbake(with({"--info"}, with(files, {"--json"})));
  EXPECT_EQ(r.exit_code, 1);
  const auto errors = r.err_lines();
  ASSERT_EQ(errors.size(), 2u) << r.err;
  EXPECT_EQ(errors[0].rfind("octbake: error: " + files[1] + ": ", 0), 0u) << errors[0];
  EXPECT_EQ(errors[1].rfind("octbake: error: " + files[3] + ": ", 0), 0u) << errors[1];

  const nlohmann::json doc = nlohmann::json::parse(r.out);  // throws, failing the test, unless one document
  ASSERT_EQ(doc.at("files").size(), 2u) << r.out;
  const std::string good_paths[] = {files[0], files[2]};
  size_t trees_seen = 0;
  for (size_t f = 0; f < 2; ++f) {
    const nlohmann::json& jf = doc["files"][f];
    auto file = BakedFile::open(good_paths[f]);
    ASSERT_TRUE(file.ok());
    EXPECT_EQ(jf.at("path"), good_paths[f]);
    EXPECT_EQ(jf.at("format_version"), file->format_version());
    EXPECT_EQ(jf.at("baker_version"), file->baker_version());
    EXPECT_EQ(jf.at("baker_version"), OCTBAKE_VERSION);
    ASSERT_EQ(jf.at("trees").size(), file->trees().size());
    for (size_t i = 0; i < file->trees().size(); ++i) {
      const TreeInfo& info = file->trees()[i];
      const nlohmann::json& jt = jf["trees"][i];
      const OctreeMasks masks = file->load(i, info.depth)->masks();
      EXPECT_EQ(jt.at("name"), info.name);
      EXPECT_EQ(jt.at("source_hash"), info.source_hash);
      EXPECT_EQ(jt.at("source_hash"), *hash_file(info.name == "a" ? a : b));
      EXPECT_EQ(jt.at("depth"), info.depth);
      EXPECT_EQ(jt.at("triangles"), info.triangle_count);
      EXPECT_EQ(jt.at("vertices"), info.vertex_count);
      const nlohmann::json& o = jt.at("options");
      EXPECT_EQ(o.at("depth"), info.options.depth);
      EXPECT_EQ(o.at("occupancy"), f == 0 ? "surface" : "solid");
      EXPECT_EQ(o.at("compression"), "zstd");
      EXPECT_EQ(o.at("compression_level"), f == 0 ? 19 : 5);
      for (int axis = 0; axis < 3; ++axis) {  // doubles round-trip exactly
        EXPECT_EQ(jt.at("bounds").at("min")[axis].get<double>(), info.bounds.min[axis]);
        EXPECT_EQ(jt.at("bounds").at("max")[axis].get<double>(), info.bounds.max[axis]);
      }
      const nlohmann::json& levels = jt.at("levels");
      ASSERT_EQ(levels.size(), size_t(info.depth) + 1);
      uint64_t stored = 0, raw = 0;
      for (int d = 0; d <= info.depth; ++d) {
        const nlohmann::json& l = levels[d];
        EXPECT_EQ(l.at("depth"), d);
        EXPECT_EQ(l.at("boxes"), masks.box_count(d));
        EXPECT_EQ(l.at("boxes"), info.box_count[d]);
        EXPECT_EQ(l.at("raw_bytes"), d == 0 ? 0u : masks.masks[d - 1].size());
        EXPECT_EQ(l.at("stored_bytes"), info.stored_bytes[d]);
        const Eigen::Vector3d size = (info.bounds.max - info.bounds.min) / std::ldexp(1.0, d);
        for (int axis = 0; axis < 3; ++axis) EXPECT_EQ(l.at("leaf_size")[axis].get<double>(), size[axis]);
        stored += info.stored_bytes[d];
        raw += info.raw_bytes[d];
      }
      EXPECT_EQ(jt.at("stored_bytes"), stored);
      EXPECT_EQ(jt.at("raw_bytes"), raw);
      ++trees_seen;
    }
  }
  EXPECT_EQ(trees_seen, 3u);

  // Every file bad: still one (empty) document. --json without --info is bad usage.
  const RunResult none = run_octbake({"--json", "--info", files[3]});
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_EQ(nlohmann::json::parse(none.out), nlohmann::json::parse(R"({"files": []})"));
  const RunResult usage = run_octbake({"--json", "-o", t / "x", a});
  EXPECT_EQ(usage.exit_code, 2);
  ASSERT_EQ(usage.err_lines().size(), 1u) << usage.err;
  EXPECT_EQ(usage.err_lines()[0].rfind("octbake: error: ", 0), 0u);
  EXPECT_FALSE(std::filesystem::exists(t / "x"));
}

}  // namespace
}  // namespace octbake

// The `octbake` command line, run as a separate process: determinism, round
// trip against the in-memory build, up-to-date checks, collisions, usage
// errors, --info, --export-obj and --pack.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <sstream>

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

// Writes `count` seeded random meshes into t/in/m<k>.obj.
std::vector<std::string> random_inputs(const TempDir& t, int count, uint32_t seed) {
  std::filesystem::create_directories(t / "in");
  std::vector<std::string> paths;
  for (int k = 0; k < count; ++k) {
    paths.push_back(t / ("in/m" + std::to_string(k) + ".obj"));
    write_text(paths.back(), test::random_obj(seed + k, 50 + 40 * k, 0.05 + 0.3 * k));
  }
  return paths;
}

std::vector<std::string> with(std::vector<std::string> args, const std::vector<std::string>& more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

std::string stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

// The tree the baker should have written for `path`, built in memory.
OctreeMasks expected_masks(const std::string& path, int depth, Occupancy mode) {
  auto mesh = import_mesh(path);
  EXPECT_TRUE(mesh.ok()) << path;
  return build_tree(*mesh, depth, mode);
}

// Opens `path` and loads every level of its only tree.
OctreeMasks load_only_tree(const std::string& path) {
  auto file = BakedFile::open(path);
  EXPECT_TRUE(file.ok()) << path << ": " << (file ? "" : file.error().message);
  if (!file) return {};
  EXPECT_EQ(file->trees().size(), 1u);
  auto tree = file->load(0, file->trees()[0].depth);
  EXPECT_TRUE(tree.ok()) << path;
  return tree ? tree->masks() : OctreeMasks{};
}

TEST(CliDeterminism, SameBytesTwiceAndForAnyJobCount) {
  TempDir t;
  const auto inputs = random_inputs(t, 4, 100);
  ASSERT_EQ(run_octbake(with({"-q", "-j1", "-d", "6", "-o", t / "a"}, inputs)).exit_code, 0);
  ASSERT_EQ(run_octbake(with({"-q", "-j4", "-d", "6", "-o", t / "b"}, inputs)).exit_code, 0);
  std::map<std::string, std::vector<uint8_t>> first;
  for (const auto& in : inputs) first[in] = read_bytes(t / ("a/" + stem(in) + ".oct"));
  ASSERT_EQ(run_octbake(with({"-q", "-j3", "--force", "-d", "6", "-o", t / "a"}, inputs)).exit_code, 0);
  for (const auto& in : inputs) {
    const auto a = read_bytes(t / ("a/" + stem(in) + ".oct"));
    EXPECT_FALSE(a.empty());
    EXPECT_EQ(a, first[in]) << "rebake changed " << in;
    EXPECT_EQ(a, read_bytes(t / ("b/" + stem(in) + ".oct"))) << "-j1 vs -j4 differ for " << in;
  }
  ASSERT_EQ(run_octbake(with({"-q", "-j1", "-d", "6", "--pack", t / "p1.oct"}, inputs)).exit_code, 0);
  ASSERT_EQ(run_octbake(with({"-q", "-j4", "-d", "6", "--pack", t / "p2.oct"}, inputs)).exit_code, 0);
  EXPECT_EQ(read_bytes(t / "p1.oct"), read_bytes(t / "p2.oct"));
}

TEST(CliRoundTrip, LoadedMasksEqualInMemoryBuildAtEveryDepth) {
  TempDir t;
  const auto inputs = random_inputs(t, 3, 200);
  const std::pair<const char*, Occupancy> modes[] = {
      {"surface", Occupancy::surface}, {"solid", Occupancy::solid}, {"vertices", Occupancy::vertices}};
  for (const auto& [name, mode] : modes) {
    for (const char* compress : {"zstd:19", "none"}) {
      const std::string out = t / (std::string(name) + compress);
      ASSERT_EQ(run_octbake(with({"-q", "-d", "6", "--occupancy", name, "--compress", compress, "-o", out}, inputs))
                    .exit_code,
                0);
      for (const auto& in : inputs) {
        const std::string path = out + "/" + stem(in) + ".oct";
        auto file = BakedFile::open(path);
        ASSERT_TRUE(file.ok()) << path;
        const TreeInfo& info = file->trees().at(0);
        EXPECT_EQ(info.name, stem(in));
        EXPECT_EQ(info.source_hash, *hash_file(in));
        EXPECT_EQ(info.options.depth, 6);
        EXPECT_EQ(info.options.occupancy, mode);
        EXPECT_EQ(info.options.compression, std::string(compress) == "none" ? Compression::none : Compression::zstd);
        EXPECT_EQ(file->baker_version(), OCTBAKE_VERSION);
        const OctreeMasks expected = expected_masks(in, 6, mode);
        EXPECT_EQ(load_only_tree(path), expected) << path;
        for (int d = 0; d <= 6; ++d) EXPECT_EQ(info.box_count[d], expected.box_count(d));
        EXPECT_EQ(info.triangle_count, import_mesh(in)->triangles.size());
      }
    }
  }
}

TEST(CliCollision, SameOutputNameFailsBothAndBakesTheRest) {
  TempDir t;
  std::filesystem::create_directories(t / "a");
  std::filesystem::create_directories(t / "b");
  write_text(t / "a/x.obj", test::random_obj(1, 20, 0.3));
  write_text(t / "b/x.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  write_text(t / "y.obj", test::random_obj(2, 20, 0.3));
  const std::vector<std::string> inputs = {t / "a/x.obj", t / "y.obj", t / "b/x.ply"};

  const RunResult r = run_octbake(with({"-q", "-o", t / "out"}, inputs));
  EXPECT_EQ(r.exit_code, 1);
  const auto lines = r.err_lines();
  ASSERT_EQ(lines.size(), 2u) << r.err;
  // Input order; each line names its own path first and the other input.
  EXPECT_EQ(lines[0].rfind("octbake: error: " + inputs[0] + ": ", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find(inputs[2]), std::string::npos) << lines[0];
  EXPECT_EQ(lines[1].rfind("octbake: error: " + inputs[2] + ": ", 0), 0u) << lines[1];
  EXPECT_NE(lines[1].find(inputs[0]), std::string::npos) << lines[1];
  EXPECT_FALSE(std::filesystem::exists(t / "out/x.oct"));
  EXPECT_EQ(load_only_tree(t / "out/y.oct"), expected_masks(inputs[1], 6, Occupancy::surface));

  // Pack: duplicate tree names are the same error; the pack holds the rest.
  const RunResult p = run_octbake(with({"-q", "--pack", t / "all.oct"}, inputs));
  EXPECT_EQ(p.exit_code, 1);
  EXPECT_EQ(p.err_lines().size(), 2u) << p.err;
  auto pack = BakedFile::open(t / "all.oct");
  ASSERT_TRUE(pack.ok());
  ASSERT_EQ(pack->trees().size(), 1u);
  EXPECT_EQ(pack->trees()[0].name, "y");
}

TEST(CliCollision, SameFileTwiceIsBakedOnce) {
  TempDir t;
  write_text(t / "x.obj", test::random_obj(3, 30, 0.2));
  const RunResult r = run_octbake({"-q", "-o", t / "out", t / "x.obj", t / "x.obj", t / "./x.obj"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty());
  EXPECT_EQ(load_only_tree(t / "out/x.oct"), expected_masks(t / "x.obj", 6, Occupancy::surface));
}

TEST(CliUpToDate, SkipsOnlyWhenHashOptionsAndVersionsMatch) {
  TempDir t;
  const std::string in = t / "x.obj", out = t / "out/x.oct";
  write_text(in, test::random_obj(4, 60, 0.2));
  auto bake = [&](std::vector<std::string> args) {
    const RunResult r = run_octbake(with(with({"-q", "-o", t / "out"}, args), {in}));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return test::file_identity(out);
  };
  auto id = bake({});
  EXPECT_EQ(bake({}), id) << "an up-to-date output was rewritten";
  // Each change rebakes once, then is up to date again.
  const std::vector<std::vector<std::string>> changes = {
      {"-d", "5"}, {"--occupancy", "vertices"}, {"--compress", "zstd:3"}, {"--compress", "none"}, {}};
  for (const auto& args : changes) {
    const auto rebaked = bake(args);
    EXPECT_NE(rebaked, id) << "no rebake after an option change, step " << testing::PrintToString(args);
    EXPECT_EQ(bake(args), rebaked) << testing::PrintToString(args);
    id = rebaked;
  }
  const auto forced = bake({"--force"});
  EXPECT_NE(forced, id);
  // Same geometry, other bytes: the source hash changes, so it rebakes.
  std::ofstream(in, std::ios::app) << "# comment\n";
  const auto after_edit = bake({});
  EXPECT_NE(after_edit, forced);
  EXPECT_EQ(load_only_tree(out), expected_masks(in, 6, Occupancy::surface));

  // A corrupt output (bad identifier, then truncated) is rebaked, not trusted.
  const auto good = read_bytes(out);
  for (int variant = 0; variant < 2; ++variant) {
    auto bytes = good;
    if (variant == 0)
      std::fill(bytes.begin(), bytes.begin() + 8, uint8_t{0x5a});
    else
      bytes.resize(bytes.size() / 2);
    write_text(out, std::string(bytes.begin(), bytes.end()));
    ASSERT_FALSE(BakedFile::open(out).ok());
    bake({});
    EXPECT_EQ(read_bytes(out), good) << "variant " << variant;
  }
}

TEST(CliUpToDate, PackSkipsOnlyForTheSameTreeSet) {
  TempDir t;
  const auto inputs = random_inputs(t, 3, 300);
  const std::string pack = t / "p.oct";
  auto bake = [&](const std::vector<std::string>& in) {
    EXPECT_EQ(run_octbake(with({"-q", "--pack", pack}, in)).exit_code, 0);
    return test::file_identity(pack);
  };
  const auto id = bake(inputs);
  EXPECT_EQ(bake(inputs), id);
  const auto fewer = bake({inputs[0], inputs[1]});
  EXPECT_NE(fewer, id);
  EXPECT_EQ(BakedFile::open(pack)->trees().size(), 2u);
  EXPECT_NE(bake(inputs), fewer);
  EXPECT_EQ(BakedFile::open(pack)->trees().size(), 3u);
}

TEST(CliUsage, BadUsageExitsTwoWithOneLine) {
  TempDir t;
  const std::string in = t / "x.obj";
  write_text(in, test::random_obj(5, 10, 0.2));
  const std::vector<std::vector<std::string>> bad = {
      {"-d", "0", in},          {"-d", "13", in},           {"-d", "six", in},
      {"--occupancy", "x", in}, {"--compress", "zstd:0", in}, {"--compress", "zstd:23", in},
      {"--compress", "lz4", in}, {"--compress", "zstd:", in}, {"-j", "0", in},
      {"--bogus", in},          {},                         {"-q"},
      {"--pack", t / "p.oct", in},  // --pack excludes the -o appended below
      {"--export-obj", "", in},   {"--depfile", "", in},    {"--for-scene", "", in},
      {"--import-timeout", "-1", in}, {"--import-timeout", "nan", in}, {"--import-timeout", "soon", in},
  };
  for (const auto& args : bad) {
    const RunResult r = run_octbake(with(args, {"-o", t / "out"}));
    EXPECT_EQ(r.exit_code, 2) << testing::PrintToString(args);
    const auto lines = r.err_lines();
    ASSERT_EQ(lines.size(), 1u) << testing::PrintToString(args) << r.err;
    EXPECT_EQ(lines[0].rfind("octbake: error: ", 0), 0u) << lines[0];
    EXPECT_FALSE(std::filesystem::exists(t / "out")) << testing::PrintToString(args);
  }
  // An empty output path is refused, not taken as the default folder.
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--pack", "", in},
                                               std::vector<std::string>{"-o", "", in}}) {
    const RunResult r = run_octbake(args);
    EXPECT_EQ(r.exit_code, 2) << testing::PrintToString(args);
    EXPECT_EQ(r.err_lines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find("an empty path"), std::string::npos) << r.err;
  }
  const RunResult help = run_octbake({"--help"});
  EXPECT_EQ(help.exit_code, 0);
  for (const char* option : {"--out", "--pack", "--depth", "--occupancy", "--compress", "--jobs", "--force", "--info",
                             "--export-obj", "--quiet"})
    EXPECT_NE(help.out.find(option), std::string::npos) << option;
  // Valid edge values are accepted.
  EXPECT_EQ(run_octbake({"-q", "-d", "1", "--compress", "zstd:22", "-o", t / "ok", in}).exit_code, 0);
  EXPECT_EQ(run_octbake({"-q", "-d", "12", "--compress", "zstd:1", "-o", t / "ok12", in}).exit_code, 0);
  EXPECT_EQ(load_only_tree(t / "ok12/x.oct").depth(), 12);
}

TEST(CliInfo, PrintsEveryLevelAndFailsCleanlyOnCorruptFiles) {
  TempDir t;
  const auto inputs = random_inputs(t, 2, 400);
  ASSERT_EQ(run_octbake(with({"-q", "-d", "5", "-o", t / "out"}, inputs)).exit_code, 0);
  const std::string a = t / "out/m0.oct", b = t / "out/m1.oct";
  const RunResult r = run_octbake({"--info", a, b});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty());
  // Level rows: depth, boxes, stored bytes, raw bytes, leaf size "x x y x z".
  struct Row {
    int depth;
    uint64_t boxes, stored, raw;
    double size[3];
  };
  std::vector<Row> rows;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream s(line);
    Row row;
    std::string x1, x2;
    if (s >> row.depth >> row.boxes >> row.stored >> row.raw >> row.size[0] >> x1 >> row.size[1] >> x2 >>
            row.size[2] &&
        x1 == "x" && x2 == "x" && (s >> std::ws).eof())
      rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 12u) << r.out;
  for (size_t k = 0; k < 2; ++k) {
    const OctreeMasks masks = expected_masks(inputs[k], 5, Occupancy::surface);
    const Eigen::Vector3d extent = masks.bounds.max - masks.bounds.min;
    for (int d = 0; d <= 5; ++d) {
      const Row& row = rows[k * 6 + d];
      EXPECT_EQ(row.depth, d);
      EXPECT_EQ(row.boxes, masks.box_count(d));
      EXPECT_EQ(row.raw, d == 0 ? 0u : masks.masks[d - 1].size());  // one byte per parent box
      for (int axis = 0; axis < 3; ++axis)
        EXPECT_NEAR(row.size[axis], extent[axis] / (1 << d), 1e-5 * extent[axis]);
    }
  }
  for (const std::string& needle : {stem(inputs[0]), *hash_file(inputs[0]), std::string("surface"),
                                    std::string("zstd:19"), std::string(OCTBAKE_VERSION)})
    EXPECT_NE(r.out.find(needle), std::string::npos) << needle;

  auto bytes = read_bytes(a);
  write_text(t / "truncated.oct", std::string(bytes.begin(), bytes.begin() + bytes.size() / 2));
  write_text(t / "garbage.oct", "this is not a baked file at all");
  const RunResult bad = run_octbake({"--info", t / "truncated.oct", b, t / "garbage.oct", t / "missing.oct"});
  EXPECT_EQ(bad.exit_code, 1);
  const auto errors = bad.err_lines();
  ASSERT_EQ(errors.size(), 3u) << bad.err;
  EXPECT_EQ(errors[0].rfind("octbake: error: " + t / "truncated.oct" + ": ", 0), 0u) << errors[0];
  EXPECT_EQ(errors[1].rfind("octbake: error: " + t / "garbage.oct" + ": ", 0), 0u) << errors[1];
  EXPECT_EQ(errors[2].rfind("octbake: error: " + t / "missing.oct" + ": ", 0), 0u) << errors[2];
  EXPECT_NE(bad.out.find(b), std::string::npos) << "the good file is still described";
}

TEST(CliExportObj, OneBoxPerOccupiedCellAtEveryDepth) {
  TempDir t;
  const auto inputs = random_inputs(t, 2, 500);
  ASSERT_EQ(run_octbake(with({"-q", "-d", "4", "-o", t / "out", "--export-obj", t / "obj"}, inputs)).exit_code, 0);
  for (const auto& in : inputs) {
    const OctreeMasks masks = expected_masks(in, 4, Occupancy::surface);
    for (int d = 0; d <= 4; ++d) {
      const std::string path = t / ("obj/" + stem(in) + "_d" + std::to_string(d) + ".obj");
      std::ifstream obj(path);
      ASSERT_TRUE(obj.good()) << path;
      std::vector<Eigen::Vector3d> v;
      size_t faces = 0;
      for (std::string line; std::getline(obj, line);) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
          Eigen::Vector3d p;
          ASSERT_TRUE(s >> p.x() >> p.y() >> p.z()) << line;
          v.push_back(p);
        } else if (tag == "f") {
          int count = 0;
          for (long idx; s >> idx; ++count) ASSERT_TRUE(idx >= 1 && static_cast<size_t>(idx) <= v.size()) << line;
          EXPECT_EQ(count, 4) << line;
          ++faces;
        } else {
          ASSERT_TRUE(tag.empty() || tag[0] == '#') << line;
        }
      }
      const uint64_t n = masks.box_count(d);
      ASSERT_EQ(v.size(), 8 * n) << path;
      EXPECT_EQ(faces, 6 * n) << path;
      // Each group of 8 vertices spans exactly one occupied box.
      std::set<std::array<double, 6>> got, want;
      for (size_t k = 0; k < n; ++k) {
        Eigen::Vector3d lo = v[8 * k], hi = v[8 * k];
        for (int c = 1; c < 8; ++c) {
          lo = lo.cwiseMin(v[8 * k + c]);
          hi = hi.cwiseMax(v[8 * k + c]);
        }
        got.insert({lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z()});
      }
      for (const BoxCoord& c : masks.boxes(d)) {
        const Aabb b = masks.box_bounds(d, c);
        want.insert({b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z()});
      }
      EXPECT_EQ(got, want) << path;
    }
  }
  // Deterministic text: an up-to-date rerun exports the same bytes from the .oct.
  const auto before = read_bytes(t / "obj/m1_d4.obj");
  std::filesystem::remove(t / "obj/m1_d4.obj");
  ASSERT_EQ(run_octbake(with({"-q", "-d", "4", "-o", t / "out", "--export-obj", t / "obj"}, inputs)).exit_code, 0);
  EXPECT_EQ(read_bytes(t / "obj/m1_d4.obj"), before);
}

TEST(CliPack, OneFileWithEveryTreeLoadableByName) {
  TempDir t;
  const auto inputs = random_inputs(t, 4, 600);
  ASSERT_EQ(run_octbake(with({"-q", "-d", "5", "--occupancy", "solid", "--pack", t / "sub/all.oct"}, inputs)).exit_code,
            0);
  auto pack = BakedFile::open(t / "sub/all.oct");
  ASSERT_TRUE(pack.ok());
  ASSERT_EQ(pack->trees().size(), inputs.size());
  for (const auto& in : inputs) {
    auto index = pack->find(stem(in));
    ASSERT_TRUE(index.ok()) << stem(in);
    auto tree = pack->load(*index, 5);
    ASSERT_TRUE(tree.ok());
    EXPECT_EQ(tree->masks(), expected_masks(in, 5, Occupancy::solid)) << in;
    EXPECT_EQ(tree->info().source_hash, *hash_file(in));
  }
}

// A newline in a file name: its error is still one line (the newline
// written as \n), and no depfile names it (Make cannot).
TEST(CliNames, NewlinesInNamesKeepOneLineAndStayOutOfDepfiles) {
  TempDir t;
  const std::string broken = t / "bad\nname.obj", good = t / "good\nname.obj";
  write_text(broken, "garbage\n");
  write_text(good, test::random_obj(3, 20, 0.3));
  RunResult r = run_octbake({"-q", "-o", t / "out", broken});
  EXPECT_EQ(r.exit_code, 1);
  ASSERT_EQ(r.err_lines().size(), 1u) << r.err;
  EXPECT_EQ(r.err_lines()[0].rfind("octbake: error: " + t.path().string() + "/bad\\nname.obj: ", 0), 0u) << r.err;
  r = run_octbake({"-q", "-o", t / "out", "--depfile", t / "d.d", good});
  EXPECT_EQ(r.exit_code, 1);
  ASSERT_EQ(r.err_lines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find("in a depfile: it holds a newline or a backslash"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(t / "d.d"));
}

// Rebaking a pack with a broken input keeps the old pack whole (it holds that
// input's last good tree); with no old pack, the inputs that bake are packed.
TEST(CliPack, AFailedInputKeepsTheOldPack) {
  TempDir t;
  const auto inputs = random_inputs(t, 3, 300);
  const std::string pack = t / "all.oct";
  ASSERT_EQ(run_octbake(with({"-q", "-d", "4", "--pack", pack}, inputs)).exit_code, 0);
  const std::vector<uint8_t> before = read_bytes(pack);
  write_text(inputs[1], "garbage\n");
  RunResult r = run_octbake(with({"-q", "-d", "4", "--pack", pack}, inputs));
  EXPECT_EQ(r.exit_code, 1);
  const auto lines = r.err_lines();
  ASSERT_EQ(lines.size(), 2u) << r.err;
  EXPECT_EQ(lines[0].rfind("octbake: error: " + inputs[1] + ": ", 0), 0u) << r.err;
  EXPECT_EQ(lines[1].rfind("octbake: error: " + pack + ": not rewritten, the old pack is kept: 1 of 3", 0), 0u)
      << r.err;
  EXPECT_EQ(read_bytes(pack), before);
  std::filesystem::remove(pack);
  r = run_octbake(with({"-q", "-d", "4", "--pack", pack}, inputs));
  EXPECT_EQ(r.exit_code, 1);
  auto packed = BakedFile::open(pack);
  ASSERT_TRUE(packed.ok()) << r.err;
  EXPECT_EQ(packed->trees().size(), 2u);
}

}  // namespace
}  // namespace octbake

// The public baking API (octbake/baker.h) through public headers only: the
// same masks and bytes as the `octbake` tool, the files the importer read,
// typed errors. Also the test of the shared-library build (test.sh).
#include <gtest/gtest.h>
#include <octbake.h>
#include <octbake/baker.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using octbake::BakeOptions;
using octbake::ErrorCode;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(OCTBAKE_BINARY_DIR) / "test_api" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

int run(const std::string& args) { return std::system((std::string(OCTBAKE_BIN) + " " + args).c_str()); }

// A seeded random triangle soup plus a closed box, with coordinates k/16:
// exact in float, so assimp's OBJ reader (float) sees the same numbers.
struct Arrays {
  std::vector<double> vertices;
  std::vector<uint32_t> indices;
};
Arrays random_mesh(uint32_t seed, int triangles) {
  std::mt19937 rng(seed);
  Arrays a;
  for (int t = 0; t < triangles; ++t) {
    const double cx = int(rng() % 1024) - 512, cy = int(rng() % 1024) - 512, cz = int(rng() % 1024) - 512;
    for (int k = 0; k < 3; ++k) {
      a.indices.push_back(uint32_t(a.vertices.size() / 3));
      for (double c : {cx, cy, cz}) a.vertices.push_back((c + int(rng() % 129) - 64) / 16.0);
    }
  }
  return a;
}

std::string obj_text(const Arrays& a, const std::string& mtl = "") {
  std::ostringstream s;
  s.precision(17);
  if (!mtl.empty()) s << "mtllib " << mtl << "\nusemtl red\n";
  for (size_t i = 0; i < a.vertices.size(); i += 3)
    s << "v " << a.vertices[i] << ' ' << a.vertices[i + 1] << ' ' << a.vertices[i + 2] << '\n';
  for (size_t i = 0; i < a.indices.size(); i += 3)
    s << "f " << a.indices[i] + 1 << ' ' << a.indices[i + 1] + 1 << ' ' << a.indices[i + 2] + 1 << '\n';
  return s.str();
}

octbake::OctreeMasks masks_of(octbake::Result<octbake::BakedFile> file) {
  EXPECT_TRUE(file.ok()) << file.error().message;
  auto tree = file->load(0, file->trees()[0].depth);
  EXPECT_TRUE(tree.ok()) << tree.error().message;
  return tree->masks();
}

TEST(BakerApi, ArraysToMemoryGiveTheCliMasksAndBytes) {
  const fs::path dir = fresh_dir("cli_match");
  for (auto mode : {octbake::Occupancy::surface, octbake::Occupancy::solid, octbake::Occupancy::vertices}) {
    SCOPED_TRACE(octbake::to_string(mode));
    const Arrays a = random_mesh(7 + uint32_t(mode), 120);
    const fs::path obj = dir / "soup.obj";
    write_text(obj, obj_text(a));
    const fs::path out = dir / to_string(mode);
    ASSERT_EQ(run("-q -d 5 --occupancy " + std::string(octbake::to_string(mode)) + " -o " + out.string() + " " +
                  obj.string()),
              0);
    const octbake::OctreeMasks cli = masks_of(octbake::BakedFile::open((out / "soup.oct").string()));

    BakeOptions options;
    options.depth = 5;
    options.occupancy = mode;
    auto bytes = octbake::bake_to_memory(a.vertices, a.indices, "soup", options);
    ASSERT_TRUE(bytes.ok()) << bytes.error().message;
    const octbake::OctreeMasks api = masks_of(octbake::BakedFile::from_bytes(*bytes, "memory"));
    EXPECT_EQ(api, cli);
    // Not vacuous: some but not all boxes of the deepest level are occupied.
    EXPECT_GT(api.box_count(5), 100u);
    EXPECT_LT(api.box_count(5), api.box_count(4) * 8);

    // float arrays: the same mesh (k/16 is exact in float).
    const std::vector<float> vf(a.vertices.begin(), a.vertices.end());
    auto mesh_f = octbake::mesh_from_arrays(vf, a.indices);
    ASSERT_TRUE(mesh_f.ok());
    auto masks_f = octbake::bake_masks(*mesh_f, options);
    ASSERT_TRUE(masks_f.ok());
    EXPECT_EQ(*masks_f, cli);

    // bake_file writes what the tool writes, byte for byte.
    const fs::path api_out = dir / (std::string("api_") + to_string(mode) + ".oct");
    auto written = octbake::bake_file(obj.string(), api_out.string(), options);
    ASSERT_TRUE(written.ok()) << written.error().message;
    EXPECT_EQ(read_text(api_out), read_text(out / "soup.oct"));
  }
}

TEST(BakerApi, LoadMeshRecordsTheFilesTheImporterRead) {
  const fs::path dir = fresh_dir("files_read");
  write_text(dir / "box.mtl", "newmtl red\nKd 1 0 0\n");
  write_text(dir / "box.obj", obj_text(random_mesh(3, 4), "box.mtl"));
  write_text(dir / "plain.obj", obj_text(random_mesh(4, 4)));
  std::vector<std::string> files;
  ASSERT_TRUE(octbake::load_mesh((dir / "box.obj").string(), &files).ok());
  EXPECT_EQ(files, (std::vector<std::string>{(dir / "box.obj").string(), (dir / "box.mtl").string()}));
  files.clear();
  ASSERT_TRUE(octbake::load_mesh((dir / "plain.obj").string(), &files).ok());
  EXPECT_EQ(files, std::vector<std::string>{(dir / "plain.obj").string()});

  const fs::path gltf = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";
  if (!fs::exists(gltf)) GTEST_SKIP() << "assimp-testmodels not installed";
  files.clear();
  ASSERT_TRUE(octbake::load_mesh(gltf.string(), &files).ok());
  EXPECT_NE(std::find(files.begin(), files.end(), (gltf.parent_path() / "BoxTextured0.bin").string()), files.end());
}

TEST(BakerApi, CliDepfileNamesOutputAndEveryFileRead) {
  const fs::path dir = fresh_dir("depfile");
  fs::create_directories(dir / "with space");
  const fs::path obj = dir / "with space" / "box.obj";
  write_text(dir / "with space" / "box.mtl", "newmtl red\nKd 1 0 0\n");
  write_text(obj, obj_text(random_mesh(5, 4), "box.mtl"));
  const fs::path dep = dir / "deps" / "box.d";
  ASSERT_EQ(run("-q -o '" + (dir / "out").string() + "' --depfile '" + dep.string() + "' '" + obj.string() + "'"), 0);
  auto esc = [](std::string s) {
    for (size_t i = 0; (i = s.find(' ', i)) != std::string::npos; i += 2) s.insert(i, "\\");
    return s;
  };
  EXPECT_EQ(read_text(dep), esc((dir / "out" / "box.oct").string()) + ": \\\n " + esc(obj.string()) + " \\\n " +
                                esc((dir / "with space" / "box.mtl").string()) + "\n");
  // One input only.
  EXPECT_EQ(WEXITSTATUS(run("-q --depfile " + dep.string() + " '" + obj.string() + "' '" + obj.string() + "' 2>/dev/null")), 2);
}

TEST(BakerApi, BadInputIsATypedError) {
  const std::vector<double> tri{0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<uint32_t> ok{0, 1, 2}, out_of_range{0, 1, 3}, short_list{0, 1};
  EXPECT_TRUE(octbake::mesh_from_arrays(tri, ok).ok());
  auto e1 = octbake::mesh_from_arrays(tri, out_of_range);
  ASSERT_FALSE(e1.ok());
  EXPECT_EQ(e1.error().code, ErrorCode::invalid_argument);
  EXPECT_NE(e1.error().message.find("out of range"), std::string::npos) << e1.error().message;
  EXPECT_FALSE(octbake::mesh_from_arrays(tri, short_list).ok());
  EXPECT_FALSE(octbake::mesh_from_arrays(std::vector<double>{0, 0}, ok).ok());
  std::vector<double> nan = tri;
  nan[4] = std::nan("");
  EXPECT_EQ(octbake::mesh_from_arrays(nan, ok).error().code, ErrorCode::invalid_argument);

  auto mesh = octbake::mesh_from_arrays(tri, ok);
  for (int depth : {0, 13}) {
    BakeOptions o;
    o.depth = depth;
    auto r = octbake::bake_masks(*mesh, o);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("depth"), std::string::npos) << r.error().message;
  }
  BakeOptions o;
  EXPECT_FALSE(octbake::bake_to_memory(*mesh, "", o).ok());
  auto missing = octbake::load_mesh("/nonexistent/x.obj");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::not_found);
  EXPECT_NE(missing.error().message.find("/nonexistent/x.obj"), std::string::npos);
}

TEST(BakerApi, ToolPrintsTheLibraryVersion) {
  const fs::path dir = fresh_dir("version");
  ASSERT_EQ(run("--version > " + (dir / "v.txt").string()), 0);
  EXPECT_EQ(read_text(dir / "v.txt"), std::string("octbake ") + octbake::kLibraryVersion + "\n");
  EXPECT_STREQ(octbake::baker_version(), octbake::kLibraryVersion);
}

}  // namespace

// import_mesh: real models of many formats, node transforms, and refusals
// (each with a reason, never a crash).
#include "import.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

namespace octbake {
namespace {

namespace fs = std::filesystem;
const fs::path kModels = "/usr/share/assimp/models";

class ImportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("octbake_import_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& bytes) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p.string();
  }

  fs::path dir_;
};

void expect_refused(const std::string& path) {
  const Result<Mesh> r = import_mesh(path);
  ASSERT_FALSE(r.ok()) << path << " was accepted";
  EXPECT_FALSE(r.error().message.empty()) << path;
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << path;
}

void expect_refused_with(const std::string& path, const std::string& reason) {
  const Result<Mesh> r = import_mesh(path);
  ASSERT_FALSE(r.ok()) << path << " was accepted";
  EXPECT_NE(r.error().message.find(reason), std::string::npos) << path << ": " << r.error().message;
}

void expect_valid_mesh(const Mesh& m) {
  ASSERT_FALSE(m.triangles.empty());
  for (const Eigen::Vector3d& p : m.positions) ASSERT_TRUE(p.allFinite());
  for (const auto& t : m.triangles)
    for (uint32_t i : t) ASSERT_LT(i, m.positions.size());
}

TEST_F(ImportTest, ReadsRealModelsOfManyFormats) {
  for (const char* rel : {"OBJ/spider.obj", "OBJ/WusonOBJ.obj", "Collada/duck.dae",
                          "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", "STL/Spider_binary.stl",
                          "STL/Spider_ascii.stl", "PLY/Wuson.ply", "PLY/cube_binary.ply", "OFF/Wuson.off",
                          "OFF/Cube.off", "glTF2/BoxTextured-glTF/BoxTextured.gltf"}) {
    SCOPED_TRACE(rel);
    const fs::path p = kModels / rel;
    if (!fs::exists(p)) GTEST_SKIP() << p << " not installed (assimp-testmodels)";
    const Result<Mesh> r = import_mesh(p.string());
    ASSERT_TRUE(r.ok()) << r.error().message;
    expect_valid_mesh(*r);
  }
}

TEST_F(ImportTest, KeepsTriangleCountOfSimpleModels) {
  // An OFF cube of 6 quads, triangulated.
  const Result<Mesh> off = import_mesh((kModels / "OFF/Cube.off").string());
  ASSERT_TRUE(off.ok()) << off.error().message;
  EXPECT_EQ(off->triangles.size(), 12u);
  EXPECT_EQ(off->positions.size(), 8u);  // identical vertices joined
}

TEST_F(ImportTest, AppliesNestedNodeTransforms) {
  // One triangle (0,0,0) (1,0,0) (0,1,0) instanced twice: under
  // translate(10,20,30) * scale(2,3,4), and under translate(-5,0,0).
  const std::string dae = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="tri" name="tri"><mesh>
      <source id="tri-pos">
        <float_array id="tri-pos-array" count="9">0 0 0 1 0 0 0 1 0</float_array>
        <technique_common><accessor source="#tri-pos-array" count="3" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="parent"><translate>10 20 30</translate>
        <node id="child"><scale>2 3 4</scale><instance_geometry url="#tri"/></node>
      </node>
      <node id="other"><translate>-5 0 0</translate><instance_geometry url="#tri"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
  const Result<Mesh> r = import_mesh(write("nodes.dae", dae));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->triangles.size(), 2u);
  Eigen::Vector3d lo = r->positions[0], hi = r->positions[0];
  for (const auto& p : r->positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  // Child: (10,20,30) (12,20,30) (10,23,30); other: (-5,0,0) (-4,0,0) (-5,1,0).
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3d(-5, 0, 0))) << lo.transpose();
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3d(12, 23, 30))) << hi.transpose();
  bool found_scaled = false;
  for (const auto& p : r->positions) found_scaled |= (p - Eigen::Vector3d(10, 23, 30)).norm() < 1e-9;
  EXPECT_TRUE(found_scaled) << "parent * child order";
}

TEST_F(ImportTest, KeepsDegenerateTriangles) {
  const Result<Mesh> r = import_mesh(write("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->triangles.size(), 2u);
}

TEST_F(ImportTest, RefusesPointsAndLinesOnly) {
  expect_refused_with(write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\np 2\np 3\n"), "no triangles");
  expect_refused_with(write("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n"), "no triangles");
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "end_header\n0 0 0\n1 0 0\n0 1 0\n";
  expect_refused(write("points.ply", ply));
}

TEST_F(ImportTest, RefusesNonFiniteCoordinates) {
  // Binary STL: 80-byte header, count, then normal + 3 vertices + attribute.
  std::string stl(80, ' ');
  auto put = [&](const void* p, size_t n) { stl.append(static_cast<const char*>(p), n); };
  const uint32_t count = 1;
  put(&count, 4);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float floats[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, nan, 1, 0};
  put(floats, sizeof floats);
  const uint16_t attr = 0;
  put(&attr, 2);
  expect_refused_with(write("nan.stl", stl), "NaN or infinite");

  std::string inf_stl = stl;
  const float inf = std::numeric_limits<float>::infinity();
  std::memcpy(&inf_stl[80 + 4 + 12 + 12], &inf, 4);  // second vertex x
  std::memcpy(&inf_stl[80 + 4 + 12 + 24], floats, 4);  // third vertex finite again
  expect_refused_with(write("inf.stl", inf_stl), "NaN or infinite");
  expect_refused_with(write("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "NaN or infinite");
  // Finite in the file, infinite as the float assimp stores: the reason says so.
  expect_refused_with(write("huge.obj", "v 1e300 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
                      "NaN or infinite vertex coordinate (assimp reads floats: past 3.4e38 in magnitude is infinite)");
}

TEST_F(ImportTest, RefusesOffHeaderClaimingMoreThanTheFileHolds) {
  // assimp would allocate and zero these counts before reading anything.
  expect_refused_with(write("huge.off", "OFF\n353535235358 6 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), "OFF header");
  expect_refused_with(write("huge2.off", "OFF\n3 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), "OFF header");
  const Result<Mesh> ok = import_mesh(write("small.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  ASSERT_TRUE(ok.ok()) << ok.error().message;
  EXPECT_EQ(ok->triangles.size(), 1u);
}

TEST_F(ImportTest, RefusesPlyWhoseHeaderNeverEnds) {
  // assimp reads past the end forever, or crashes, on these: every cut of a
  // good PLY inside its header is refused before assimp sees it.
  const std::string header =
      "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const Result<Mesh> whole = import_mesh(write("whole.ply", header + body));
  ASSERT_TRUE(whole.ok()) << whole.error().message;
  EXPECT_EQ(whole->triangles.size(), 1u);
  for (size_t cut = 4; cut < header.size() - 1; ++cut)
    expect_refused_with(write("cut.ply", header.substr(0, cut)), "PLY header has no end_header line");
  // "end_header" run into the line before or after is no end either.
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = header + body;
    return text.replace(text.find(from), from.size(), to);
  };
  expect_refused_with(write("joined.ply", replaced("vertex_indices\nend_header", "vertex_indicesend_header")),
                      "PLY header has no end_header line");
  expect_refused_with(write("mangled.ply", replaced("end_header", "end_0eader")), "PLY header has no end_header line");
  // The files that crashed (SIGSEGV) and hung the importer, in process.
  for (const char* name : {"ply_no_end_header_segv.ply", "ply_no_end_header_hang.ply"})
    expect_refused_with(std::string(OCTBAKE_SOURCE_DIR) + "/tests/hostile/" + name, "PLY header has no end_header line");
  // assimp's magic is "ply" in any case, with anything after it.
  for (const char* magic : {"PLY\n", "Ply\n", "plyx\n"})
    expect_refused_with(write("magic.ply", magic + header.substr(4, 60)), "PLY header has no end_header line");
  // What assimp reads as the end of a header is one here too: a line ended
  // by CR, LF or both; blanks before the token; a blank, form feed or NUL,
  // or more text, after it.
  for (const std::string end : {"end_header\r\n", "end_header  \t\n", "  end_header\n", "\tend_header\n",
                                "end_header junk\n", "end_header\f\n"}) {
    const Result<Mesh> r = import_mesh(write("ends.ply", replaced("end_header\n", end)));
    ASSERT_TRUE(r.ok()) << end << ": " << r.error().message;
    EXPECT_EQ(r->triangles.size(), 1u);
  }
  std::string cr_only = header + body;
  std::replace(cr_only.begin(), cr_only.end(), '\n', '\r');
  const Result<Mesh> cr = import_mesh(write("cr_only.ply", cr_only));
  ASSERT_TRUE(cr.ok()) << cr.error().message;
  EXPECT_EQ(cr->triangles.size(), 1u);
}

TEST_F(ImportTest, JoinsExactlyIdenticalVerticesOnly) {
  // Two triangles sharing an edge, written as separate vertices, plus a
  // vertex 1e-12 away from another: only exact duplicates merge.
  const Result<Mesh> r = import_mesh(
      write("join.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0.000000000001 0 0\nf 1 2 3\nf 4 6 5\nf 7 2 3\n"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->triangles.size(), 3u);
  EXPECT_EQ(r->positions.size(), 5u);
  EXPECT_EQ(r->triangles[0][1], r->triangles[1][0]);
}

TEST_F(ImportTest, RefusesMissingEmptyAndDirectory) {
  const Result<Mesh> missing = import_mesh((dir_ / "no_such_file.obj").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::not_found);
  expect_refused(write("empty.obj", ""));
  expect_refused(dir_.string());
  const char junk[] = "\x00\x01\x02garbage\xff\xfe";
  expect_refused(write("junk.obj", std::string(junk, sizeof junk - 1)));
  expect_refused(write("junk.bin", "this is not a mesh at all\n"));
}

TEST_F(ImportTest, RefusesAssimpInvalidModelsWithoutCrashing) {
  const fs::path invalid = kModels / "invalid";
  if (!fs::exists(invalid)) GTEST_SKIP() << "assimp-testmodels not installed";
  int seen = 0;
  for (const auto& entry : fs::directory_iterator(invalid)) {
    SCOPED_TRACE(entry.path().string());
    // malformed2.obj is a whole cube that names a missing material; a baker
    // has no use for materials, so reading it is right.
    if (entry.path().filename() == "malformed2.obj") {
      const Result<Mesh> r = import_mesh(entry.path().string());
      ASSERT_TRUE(r.ok()) << r.error().message;
      expect_valid_mesh(*r);
      continue;
    }
    expect_refused(entry.path().string());
    ++seen;
  }
  EXPECT_GE(seen, 10);
}

}  // namespace
}  // namespace octbake

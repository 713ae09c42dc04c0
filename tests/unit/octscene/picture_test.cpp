// octscene picture: the rasteriser's buffer holds what was drawn where it
// should be, and the PNG decodes back to the same pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "box_mesh.h"
#include "build_tree.h"
#include "picture.h"
#include "raster.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb_image.h>
#pragma GCC diagnostic pop

namespace octbake::scene {
namespace {

using testing::box_mesh;

Camera looking_down_z(double distance) {
  Camera c;
  c.position = {0, 0, -distance};
  c.look_at = {0, 0, 0};
  c.up = {0, 1, 0};
  c.fov_y_deg = 90;
  c.near_plane = 0.01;
  return c;
}

TEST(Raster, TriangleCoversWhatTheProjectionSays) {
  // fov 90, distance 2, 200 px: focal = 100 px, so the square [-1, 1]^2 at
  // z = 0 spans x, y in [50, 150).
  Raster r(200, 200, Rgb{0, 0, 0});
  r.set_camera(looking_down_z(2));
  r.triangle({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, Rgb{200, 200, 200});
  r.triangle({-1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, Rgb{200, 200, 200});
  EXPECT_EQ(r.kind(100, 100), PixelKind::surface);
  EXPECT_EQ(r.kind(51, 51), PixelKind::surface);
  EXPECT_EQ(r.kind(148, 148), PixelKind::surface);
  EXPECT_EQ(r.kind(48, 100), PixelKind::background);
  EXPECT_EQ(r.kind(100, 152), PixelKind::background);
  const size_t covered = r.count(PixelKind::surface);
  EXPECT_NEAR(double(covered), 100.0 * 100.0, 2 * 200.0);  // the edges may go either way
  // Shaded, not black.
  EXPECT_GT(r.pixel(100, 100).r, 40);
}

TEST(Raster, ZBufferKeepsTheNearerSurface) {
  Raster r(100, 100, Rgb{0, 0, 0});
  r.set_camera(looking_down_z(2));
  const Rgb red{250, 0, 0}, green{0, 250, 0};
  // Near red first, then far green: red must stay; in the other order too.
  for (bool red_first : {true, false}) {
    Raster s = r;
    auto draw = [&](double z, Rgb c) {
      s.triangle({-1, -1, z}, {1, -1, z}, {0, 1, z}, c);
    };
    if (red_first) draw(-0.5, red), draw(0.5, green);
    else draw(0.5, green), draw(-0.5, red);
    EXPECT_GT(s.pixel(50, 50).r, 0);
    EXPECT_EQ(s.pixel(50, 50).g, 0);
  }
}

TEST(Raster, NearPlaneClipsInsteadOfWrapping) {
  // A floor triangle under the camera reaching behind it: the clipped part
  // fills a wedge below the horizon (row 50) and nothing above it.
  Raster r(100, 100, Rgb{0, 0, 0});
  r.set_camera(looking_down_z(2));
  r.triangle({-0.5, -0.5, 1}, {0.5, -0.5, 1}, {0, -0.5, -5}, Rgb{255, 255, 255});
  EXPECT_GT(r.count(PixelKind::surface), 500u);
  EXPECT_LT(r.count(PixelKind::surface), size_t(100 * 100 / 2));
  for (int y = 0; y < 58; ++y) {
    for (int x = 0; x < 100; ++x) ASSERT_EQ(r.kind(x, y), PixelKind::background) << x << "," << y;
  }
  EXPECT_EQ(r.kind(50, 99), PixelKind::surface);
}

TEST(Raster, HiddenLinesAreFaint) {
  Raster r(100, 100, Rgb{0, 0, 0});
  r.set_camera(looking_down_z(2));
  r.triangle({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, Rgb{100, 100, 100});
  r.triangle({-1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, Rgb{100, 100, 100});
  const Rgb before = r.pixel(50, 30);
  // A horizontal line behind the square at y = 0.4 and one in front at y = -0.4.
  r.line({-0.5, 0.4, 1}, {0.5, 0.4, 1}, Rgb{255, 0, 0}, 1.0, 0.2);
  r.line({-0.5, -0.4, -1}, {0.5, -0.4, -1}, Rgb{255, 0, 0}, 1.0, 0.2);
  // In front: full red. Behind: mostly the surface still.
  bool full_front = false, faint_back = false;
  for (int y = 0; y < 100; ++y) {
    if (r.pixel(50, y) == Rgb{255, 0, 0} && r.kind(50, y) == PixelKind::line) full_front = true;
    const Rgb p = r.pixel(50, y);
    if (r.kind(50, y) == PixelKind::surface && p.r > before.r && p.g < before.g) faint_back = true;
  }
  EXPECT_TRUE(full_front);
  EXPECT_TRUE(faint_back);
}

// The same picture at any scale: the camera, its near plane and the
// triangles scaled by 2^e give the same pixels, up to 2^1000 and down to
// 2^-1000 (a scene at 2^200 was once drawn empty: its float inverse depths
// underflowed to "nothing drawn").
TEST(Raster, SamePixelsAtEveryScale) {
  const auto draw = [](int e) {
    const double k = std::ldexp(1.0, e);
    Camera c = looking_down_z(3);
    c.position = Eigen::Vector3d(0.3, 1.1, -3) * k, c.look_at = Eigen::Vector3d(0.1, 0, 0.5) * k;
    c.near_plane *= k;
    Raster r(120, 90, Rgb{0, 0, 0});
    r.set_camera(c);
    r.triangle(Eigen::Vector3d(-1, -1, 0) * k, Eigen::Vector3d(1, -1, 0.5) * k, Eigen::Vector3d(0, 1, 0) * k,
               Rgb{250, 0, 0});
    r.triangle(Eigen::Vector3d(-0.5, -1, -0.5) * k, Eigen::Vector3d(1.5, 0, 1) * k, Eigen::Vector3d(0, 0.5, -1) * k,
               Rgb{0, 250, 0});
    r.line(Eigen::Vector3d(-2, 0.2, -0.2) * k, Eigen::Vector3d(2, -0.3, 0.8) * k, Rgb{0, 0, 255}, 1.0, 0.3);
    return r;
  };
  const Raster plain = draw(0);
  ASSERT_GT(plain.count(PixelKind::surface), 200u);
  for (const int e : {-1000, -600, -200, 200, 600, 1000}) {
    const Raster scaled = draw(e);
    EXPECT_TRUE(scaled.encode_png() == plain.encode_png()) << "scaled by 2^" << e;
    EXPECT_EQ(scaled.count(PixelKind::surface), plain.count(PixelKind::surface)) << "scaled by 2^" << e;
  }
}

TEST(Raster, PngDecodesToTheSamePixels) {
  Raster r(37, 23, Rgb{10, 20, 30});
  r.fill_rect(3, 4, 10, 5, Rgb{200, 100, 50});
  r.text(15, 2, "depth 3", Rgb{255, 255, 255}, 1);
  const std::vector<uint8_t> png = r.encode_png();
  ASSERT_GT(png.size(), 33u);
  // Signature, then the IHDR width and height (big endian).
  const uint8_t kSignature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  ASSERT_TRUE(std::equal(std::begin(kSignature), std::end(kSignature), png.begin()));
  auto be32 = [&](size_t at) { return (uint32_t(png[at]) << 24) | (png[at + 1] << 16) | (png[at + 2] << 8) | png[at + 3]; };
  EXPECT_EQ(be32(16), 37u);
  EXPECT_EQ(be32(20), 23u);
  int w = 0, h = 0, channels = 0;
  uint8_t* decoded = stbi_load_from_memory(png.data(), static_cast<int>(png.size()), &w, &h, &channels, 3);
  ASSERT_NE(decoded, nullptr);
  EXPECT_EQ(w, 37);
  EXPECT_EQ(h, 23);
  EXPECT_TRUE(std::equal(r.rgb().begin(), r.rgb().end(), decoded));
  stbi_image_free(decoded);
  // The text left ink.
  EXPECT_GT(r.count(PixelKind::overlay), 50u);
}

// A tree baked from an L-shaped mesh in memory.
ObjectTree l_shape_tree(Mesh& mesh_out) {
  Mesh a = box_mesh({0, 0, 0}, {3, 1, 1});
  const Mesh b = box_mesh({0, 1, 0}, {1, 3, 1});
  const uint32_t offset = static_cast<uint32_t>(a.positions.size());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  OctreeMasks masks = build_tree(a, /*depth=*/3, Occupancy::surface);
  TreeInfo info;
  info.name = "ell";
  info.depth = 3;
  info.bounds = masks.bounds;
  mesh_out = std::move(a);
  return ObjectTree(info, std::move(masks));
}

TEST(Picture, TreePanelShowsMeshAndBoxEdges) {
  Mesh mesh;
  const ObjectTree tree = l_shape_tree(mesh);
  const Raster boxes_only = render_tree(tree, nullptr, /*depth=*/2, /*size=*/160, TreeView::front);
  EXPECT_EQ(boxes_only.count(PixelKind::surface), 0u);
  EXPECT_GT(boxes_only.count(PixelKind::line), 200u);
  const Raster both = render_tree(tree, &mesh, /*depth=*/2, /*size=*/160, TreeView::iso);
  EXPECT_GT(both.count(PixelKind::surface), 160u * 160 / 20);
  EXPECT_GT(both.count(PixelKind::line), 200u);
  // Front view of depth 1: the L's bounds [0,3]^2 x [0,1] split in half per
  // axis; the box holding x, y in [1.5, 3] is empty, so its centre pixel is
  // background while the mesh-side boxes have edges.
  const Raster d1 = render_tree(tree, nullptr, /*depth=*/1, /*size=*/160, TreeView::front);
  EXPECT_GT(d1.count(PixelKind::line), 100u);
}

TEST(Picture, GridHasOnePanelPerDepth) {
  Mesh mesh;
  const ObjectTree tree = l_shape_tree(mesh);
  const int depths[] = {1, 2, 3};
  const Raster grid = render_tree_grid(tree, &mesh, depths, /*size=*/100, TreeView::iso);
  EXPECT_EQ(grid.width(), 3 * 100 + 2 * 4);
  EXPECT_EQ(grid.height(), 100);
  // Each panel has both mesh and box edges.
  for (int k = 0; k < 3; ++k) {
    size_t surface = 0, line = 0;
    for (int y = 0; y < 100; ++y) {
      for (int x = k * 104; x < k * 104 + 100; ++x) {
        surface += grid.kind(x, y) == PixelKind::surface;
        line += grid.kind(x, y) == PixelKind::line;
      }
    }
    EXPECT_GT(surface, 100u) << "panel " << k;
    EXPECT_GT(line, 50u) << "panel " << k;
  }
}

TEST(Picture, SceneTintsEachObjectByItsDepth) {
  Mesh mesh;
  const ObjectTree tree = l_shape_tree(mesh);
  Scene scene;
  scene.camera.position = {0, 0, -20};
  scene.camera.look_at = {0, 0, 0};
  scene.camera.viewport_w = 400, scene.camera.viewport_h = 200;
  scene.world = {{-50, -50, -50}, {50, 50, 50}};
  // Looking along +z with y up, world +x is screen left.
  Pose left, right;
  left.position = {3, -1, 0};
  right.position = {-6, -1, 0};
  const Pose poses[] = {left, right};
  const int depths[] = {1, 3};
  const Mesh* meshes[] = {&mesh, nullptr};  // the right one as boxes
  const ObjectTree* trees[] = {&tree, &tree};
  const Raster r = render_scene(scene, poses, depths, meshes, trees, "test", /*width=*/400);
  EXPECT_EQ(r.width(), 400);
  EXPECT_EQ(r.height(), 200);
  // Left half has depth-1 blue-ish pixels, right half depth-3 ones; the
  // shading scales the colour, so compare hue by the dominant channel.
  auto dominant = [](Rgb c) { return c.r >= c.g && c.r >= c.b ? 0 : c.g >= c.b ? 1 : 2; };
  const int left_hue = dominant(depth_color(1)), right_hue = dominant(depth_color(3));
  ASSERT_NE(left_hue, right_hue);
  size_t left_hits = 0, right_hits = 0;
  for (int y = 0; y < r.height(); ++y) {
    for (int x = 0; x < r.width(); ++x) {
      if (r.kind(x, y) != PixelKind::surface) continue;
      const int hue = dominant(r.pixel(x, y));
      if (x < 200) left_hits += hue == left_hue;
      else right_hits += hue == right_hue;
    }
  }
  EXPECT_GT(left_hits, 200u);
  EXPECT_GT(right_hits, 200u);
}

}  // namespace
}  // namespace octbake::scene

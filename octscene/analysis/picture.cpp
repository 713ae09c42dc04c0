// `octscene picture tree|scene`: an ObjectTree's boxes over its mesh (like the
// thesis's Figure 3.1), or a scene frame tinted by the depth its LOD chose.
#include "picture.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <optional>

#include "cli_util.h"
#include "exact.h"
#include "octbake/baked_file.h"
#include "run.h"

namespace octbake::scene {
namespace {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kInk{20, 20, 20};
constexpr Rgb kMeshGrey{205, 205, 210};
constexpr Rgb kBoxRed{210, 30, 30};

OrientedBox axis_box(const Aabb& box) {
  OrientedBox o;
  o.center = 0.5 * (box.min + box.max);
  o.half = 0.5 * (box.max - box.min);
  return o;
}

// A camera that fits the sphere around `bounds`, looking from `view`.
Camera fit_camera(const Aabb& bounds, TreeView view) {
  constexpr double kFovDeg = 35;
  Eigen::Vector3d dir{1, 0.6, 1.3}, up{0, 1, 0};
  if (view == TreeView::front) dir = {0, 0, 1};
  if (view == TreeView::side) dir = {1, 0, 0};
  if (view == TreeView::top) dir = {0, 1, 0}, up = {0, 0, -1};
  const Eigen::Vector3d center = 0.5 * (bounds.min + bounds.max);
  const double radius = std::max(1e-9, 0.5 * (bounds.max - bounds.min).norm());
  const double distance = radius / std::sin(0.5 * kFovDeg * std::numbers::pi / 180) * 1.02;
  Camera c;
  c.position = center + dir.normalized() * distance;
  c.look_at = center;
  c.up = up;
  c.fov_y_deg = kFovDeg;
  c.near_plane = distance * 1e-3;
  return c;
}

void draw_mesh(Raster& raster, const Mesh& mesh, const Pose& pose, Rgb color) {
  for (const auto& t : mesh.triangles) {
    raster.triangle(pose.apply(mesh.positions[t[0]]), pose.apply(mesh.positions[t[1]]),
                    pose.apply(mesh.positions[t[2]]), color);
  }
}

}  // namespace

Raster render_tree(const ObjectTree& tree, const Mesh* mesh, int depth, int size, TreeView view) {
  Raster raster(size, size, kWhite);
  raster.set_camera(fit_camera(tree.bounds(), view));
  if (mesh) draw_mesh(raster, *mesh, Pose{}, kMeshGrey);
  const std::vector<BoxCoord> boxes = tree.masks().boxes(depth);
  // Thin lines over many boxes turn to a smear: fade them as the depth grows.
  const double alpha = boxes.size() > 1000 ? 0.5 : 0.9;
  for (const BoxCoord& c : boxes) raster.box_edges(axis_box(tree.masks().box_bounds(depth, c)), kBoxRed, alpha, 0.22);
  const int scale = std::max(1, size / 240);
  raster.text(8, 8, "depth " + std::to_string(depth) + ": " + std::to_string(boxes.size()) + " boxes", kInk, scale);
  return raster;
}

Raster render_tree_grid(const ObjectTree& tree, const Mesh* mesh, std::span<const int> depths, int size,
                        TreeView view) {
  const int n = static_cast<int>(depths.size());
  const int columns = std::min(n, 4), rows = (n + columns - 1) / columns;
  constexpr int kGap = 4;
  Raster grid(columns * size + (columns - 1) * kGap, rows * size + (rows - 1) * kGap, Rgb{150, 150, 150});
  for (int k = 0; k < n; ++k) {
    grid.blit(render_tree(tree, mesh, depths[k], size, view), (k % columns) * (size + kGap),
              (k / columns) * (size + kGap));
  }
  return grid;
}

Rgb depth_color(int depth) {
  static constexpr Rgb kPalette[] = {{120, 120, 120}, {40, 100, 220}, {40, 170, 70},  {230, 200, 30},
                                     {240, 130, 20},  {220, 40, 40},  {150, 60, 190}, {30, 190, 200},
                                     {140, 90, 40},   {240, 120, 190}, {90, 90, 30},   {20, 60, 90},
                                     {0, 0, 0}};
  return kPalette[std::clamp(depth, 0, 12)];
}

Raster render_scene(const Scene& scene, std::span<const Pose> poses, std::span<const int> depths,
                    std::span<const Mesh* const> meshes, std::span<const ObjectTree* const> trees,
                    const std::string& title, int width) {
  const double aspect = double(scene.camera.viewport_h) / std::max(1, scene.camera.viewport_w);
  Raster raster(width, std::max(1, static_cast<int>(std::lround(width * aspect))), Rgb{236, 240, 245});
  raster.set_camera(scene.camera);
  raster.box_edges(axis_box(scene.world), Rgb{120, 120, 140}, 0.6, 0.6);
  std::map<int, int> objects_at_depth;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Rgb color = depth_color(depths[i]);
    ++objects_at_depth[depths[i]];
    if (meshes[i]) {
      draw_mesh(raster, *meshes[i], poses[i], color);
      continue;
    }
    const OctreeMasks& masks = trees[i]->masks();
    const int d = std::min(depths[i], trees[i]->loaded_depth());
    for (const BoxCoord& c : masks.boxes(d)) raster.box_faces(place(masks.box_bounds(d, c), poses[i]), color);
  }
  const int scale = std::max(1, width / 480);
  const int line_h = 12 * scale;
  raster.fill_rect(0, 0, 190 * scale, line_h * (2 + static_cast<int>(objects_at_depth.size())), kWhite);
  raster.text(6, 4, title, kInk, scale);
  int y = 4 + line_h;
  for (const auto& [depth, count] : objects_at_depth) {
    raster.fill_rect(6, y, 9 * scale, 8 * scale, depth_color(depth));
    raster.text(6 + 12 * scale, y, "depth " + std::to_string(depth) + ": " + std::to_string(count) + " objects",
                kInk, scale);
    y += line_h;
  }
  return raster;
}

namespace {

// Mesh for the picture: --mesh, else the first DIR/<model>.<ext> that exists.
std::optional<Mesh> load_mesh(const std::string& explicit_path, const std::string& dir, const std::string& model) {
  const std::string path = explicit_path.empty() ? find_mesh(dir, model) : explicit_path;
  if (path.empty()) {
    std::fprintf(stderr, "octscene: note: no mesh for \"%s\" in %s: drawing boxes only\n", model.c_str(), dir.c_str());
    return std::nullopt;
  }
  auto mesh = octbake::load_mesh(path);  // the error names the path
  if (!mesh) {
    std::fprintf(stderr, "octscene: warning: %s: drawing boxes only\n", mesh.error().message.c_str());
    return std::nullopt;
  }
  return std::move(*mesh);
}

int fail(const std::string& what, const Error& e) {
  std::fprintf(stderr, "octscene: error: %s: %s\n", what.c_str(), e.message.c_str());
  return 1;
}

int write_or_fail(const Raster& raster, const std::string& out) {
  if (!raster.write_png(out)) {
    std::fprintf(stderr, "octscene: error: %s: cannot write\n", out.c_str());
    return 1;
  }
  std::printf("wrote %s (%dx%d)\n", out.c_str(), raster.width(), raster.height());
  return 0;
}

struct TreeArgs {
  std::string file, baked, model, mesh, meshes = "assets", out;
  std::vector<int> depths;
  int size = 400;
  TreeView view = TreeView::iso;
};

int picture_tree(const TreeArgs& a) {
  std::optional<ObjectTree> tree;
  if (!a.file.empty()) {
    auto file = BakedFile::open(a.file);
    if (!file) return fail(a.file, file.error());
    size_t index = 0;
    if (!a.model.empty()) {
      auto found = file->find(a.model);
      if (!found) return fail(a.file, found.error());
      index = *found;
    }
    auto loaded = file->load(index, file->trees()[index].depth);
    if (!loaded) return fail(a.file, loaded.error());
    tree = std::move(*loaded);
  } else {
    if (a.baked.empty() || a.model.empty()) {
      std::fputs("octscene: error: picture tree needs MODEL.oct or --baked DIR --model NAME\n", stderr);
      return 2;
    }
    auto library = ModelLibrary::open(a.baked);
    if (!library) return fail(a.baked, library.error());
    auto loaded = library->load(a.model, /*depth=*/12);
    if (!loaded) return fail(a.baked, loaded.error());
    tree = std::move(*loaded);
  }
  std::vector<int> depths = a.depths;
  if (depths.empty()) {
    for (int d = 1; d <= tree->loaded_depth(); ++d) depths.push_back(d);
  }
  for (int d : depths) {
    if (d < 0 || d > tree->loaded_depth()) {
      std::fprintf(stderr, "octscene: error: depth %d: the tree is baked to depth %d\n", d, tree->loaded_depth());
      return 2;
    }
  }
  const std::optional<Mesh> mesh = load_mesh(a.mesh, a.meshes, tree->info().name);
  return write_or_fail(render_tree_grid(*tree, mesh ? &*mesh : nullptr, depths, a.size, a.view), a.out);
}

struct SceneArgs {
  std::string scene, meshes = "assets", out;
  int64_t frame = 0;
  LodSettings lod;
  Response response = Response::separate;
  int width = 0;
};

int picture_scene(const SceneArgs& a) {
  auto scene = load_scene(a.scene);
  if (!scene) return fail(a.scene, scene.error());
  if (a.frame >= scene->frames) {
    std::fprintf(stderr, "octscene: error: --frame %lld: past the scene's end (%s has frames 0..%lld)\n",
                 static_cast<long long>(a.frame), a.scene.c_str(), static_cast<long long>(scene->frames) - 1);
    return 2;
  }
  auto library = ModelLibrary::open(scene->baked);
  if (!library) return fail(scene->baked, library.error());
  auto models = load_scene_models(*scene, *library, a.lod.max_depth);
  if (!models) return fail(a.scene, models.error());
  RunOptions run;
  run.lod = a.lod;
  run.response = a.response;
  run.frames = a.frame + 1;
  run.report_poses = true;
  std::vector<Pose> poses;
  std::vector<int> depths;
  auto result = run_scene(*scene, *models, run, [&](const FrameReport& f) {
    if (f.frame != a.frame) return;
    poses.assign(f.poses.begin(), f.poses.end());
    for (size_t i = 0; i < f.world->size(); ++i) depths.push_back(f.world->depth(i));
  });
  if (!result) return fail(a.scene, result.error());
  if (poses.size() != scene->objects.size()) {
    std::fprintf(stderr, "octscene: error: %s: frame %lld not reached\n", a.scene.c_str(),
                 static_cast<long long>(a.frame));
    return 1;
  }
  std::vector<std::optional<Mesh>> mesh_of_model;
  for (const std::string& name : models->names) mesh_of_model.push_back(load_mesh("", a.meshes, name));
  std::vector<const Mesh*> meshes;
  std::vector<const ObjectTree*> trees;
  for (uint32_t m : models->tree_of_object) {
    meshes.push_back(mesh_of_model[m] ? &*mesh_of_model[m] : nullptr);
    trees.push_back(&models->trees[m]);
  }
  char title[96];
  int deepest = 0;
  for (const ObjectTree& t : models->trees) deepest = std::max(deepest, t.loaded_depth());
  std::snprintf(title, sizeof title, "frame %lld, LOD %s, depths %d-%d", static_cast<long long>(a.frame),
                to_string(a.lod.policy), a.lod.min_depth, std::min(a.lod.max_depth, deepest));
  const int width = a.width > 0 ? a.width : std::min(scene->camera.viewport_w, 1280);
  // The frame's camera: the one the LOD saw when it chose these depths.
  Scene at_frame = *scene;
  at_frame.camera = camera_on_path(scene->camera, scene->camera_path, a.frame);
  return write_or_fail(render_scene(at_frame, poses, depths, meshes, trees, title, width), a.out);
}

}  // namespace

int picture_main(int argc, char** argv) {
  CLI::App app{"PNG pictures of baked trees and scene frames", "octscene picture"};
  app.require_subcommand(1);

  TreeArgs t;
  CLI::App* tree = app.add_subcommand("tree", "a tree's occupied boxes over its mesh, one panel per depth");
  tree->add_option("file", t.file, "a baked .oct file (or use --baked/--model)");
  tree->add_option("--baked", t.baked, "a folder of .oct files or a pack")->check(kNonEmptyPath);
  tree->add_option("--model", t.model, "tree name (in FILE or --baked)");
  tree->add_option("--mesh", t.mesh, "the source mesh (default: --meshes DIR/<model>.<ext>)");
  tree->add_option("--meshes", t.meshes, "folder to look for the mesh in")->check(kNonEmptyPath);
  tree->add_option("--out", t.out, "PNG to write")->required()->check(kNonEmptyPath);
  tree->add_option("--depth", t.depths, "depths to draw, e.g. 1,2,3,4 (default: all)")->delimiter(',');
  tree->add_option("--size", t.size, "pixels per panel side")->check(CLI::Range(64, 4096));
  const std::map<std::string, TreeView> views{
      {"iso", TreeView::iso}, {"front", TreeView::front}, {"side", TreeView::side}, {"top", TreeView::top}};
  tree->add_option("--view", t.view, "iso, front, side or top")->transform(CLI::CheckedTransformer(views));

  SceneArgs s;
  CLI::App* sc = app.add_subcommand("scene", "a scene frame from its camera, objects tinted by LOD depth");
  sc->add_option("scene", s.scene, "scene JSON")->required();
  sc->add_option("--frame", s.frame, "frame to draw (0 .. the scene's frames - 1)")->check(CLI::Range(int64_t{0}, kMaxFrames));
  sc->add_option("--out", s.out, "PNG to write")->required()->check(kNonEmptyPath);
  sc->add_option("--meshes", s.meshes, "folder of the source meshes")->check(kNonEmptyPath);
  const auto policies = names_of(kLodPolicies);
  sc->add_option("--lod", s.lod.policy, "fixed, thesis or screen")->transform(CLI::CheckedTransformer(policies));
  sc->add_option("--min-depth", s.lod.min_depth)->check(CLI::Range(0, 12));
  sc->add_option("--max-depth", s.lod.max_depth)->check(CLI::Range(0, 12));
  sc->add_option("--pixel-tolerance", s.lod.pixel_tolerance)->check(CLI::PositiveNumber)->check(kFiniteNumber);
  const auto responses = names_of(kResponses);
  sc->add_option("--response", s.response, "motion up to the frame")->transform(CLI::CheckedTransformer(responses));
  sc->add_option("--width", s.width, "picture width (default: viewport, at most 1280)")->check(CLI::Range(64, 8192));

  try {
    app.parse(argc, argv);  // argv[0] is the subcommand name, skipped like a program name
  } catch (const CLI::ParseError& e) {
    const char* command = tree->parsed() ? "octscene picture tree"
                          : sc->parsed() ? "octscene picture scene"
                                         : "octscene picture";
    return parse_error_exit(app, e, command);
  }
  if (tree->parsed()) return picture_tree(t);
  if (depth_range_error(s.lod.min_depth, s.lod.max_depth)) return 2;
  return picture_scene(s);
}

}  // namespace octbake::scene

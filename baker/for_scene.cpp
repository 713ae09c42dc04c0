#include "for_scene.h"

#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <set>

#include "cli.h"
#include "plan.h"
#include "run.h"
#include "scene.h"

namespace octbake {
namespace {

namespace fs = std::filesystem;

// A folder removed when it goes out of scope.
struct TempDir {
  fs::path path;
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "octbake-for-scene-XXXXXX").string();
    if (mkdtemp(pattern.data())) path = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    if (!path.empty()) fs::remove_all(path, ignored);
  }
};

}  // namespace

int bake_for_scene(const std::string& scene_path, const BakeConfig& config, std::FILE* err) {
  auto error = [&](const std::string& path, const std::string& reason) {
    std::fprintf(err, "octbake: error: %s: %s\n", path.c_str(), reason.c_str());
    return 1;
  };
  if (!config.pack.empty()) {
    std::fputs("octbake: error: --for-scene bakes one file per model at its own depth; it cannot write a --pack "
               "(see octbake --help)\n", err);
    return 2;
  }
  Result<scene::Scene> scene = scene::load_scene(scene_path);
  if (!scene) return error(scene_path, error_reason(scene.error(), scene_path));

  // The scene's models, and the inputs that provide them.
  std::set<std::string> wanted;
  for (const scene::SceneObject& o : scene->objects) wanted.insert(o.model);
  std::map<std::string, std::vector<std::string>> inputs_of_model;
  std::set<std::string> seen;  // the same file named twice is baked once (run_bake's rule)
  for (const std::string& path : config.inputs) {
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(path, ec);
    if (!seen.insert(ec ? path : canonical.string()).second) continue;
    const std::string model = fs::path(path).stem().string();
    if (wanted.count(model))
      inputs_of_model[model].push_back(path);
    else
      std::fprintf(err, "octbake: note: %s: skipped: %s names no model \"%s\"\n", path.c_str(), scene_path.c_str(),
                   model.c_str());
  }
  int status = 0;
  for (size_t i = 0; i < scene->objects.size(); ++i) {
    const std::string& model = scene->objects[i].model;
    if (inputs_of_model.count(model) || !wanted.erase(model)) continue;  // reported once per model
    status = error(scene_path, "objects[" + std::to_string(i) + "].model: no input file provides model \"" + model +
                                   "\" (a file named " + model + ".<ext>)");
  }

  // 1. Full trees, only to plan with.
  TempDir temp;
  if (temp.path.empty()) return error(fs::temp_directory_path().string(), "cannot create a temporary folder");
  BakeConfig full = config;
  full.inputs.clear();
  for (const auto& [model, paths] : inputs_of_model) full.inputs.insert(full.inputs.end(), paths.begin(), paths.end());
  full.out_dir = temp.path.string();
  full.force = true;
  full.progress = false;
  full.export_obj_dir.clear();
  full.summary = false;
  const auto start = std::chrono::steady_clock::now();
  BakeSummary total;  // of the bakes into config.out_dir, and the failures
  auto bake_into_out = [&](BakeConfig part) {
    part.summary = false;
    const BakeSummary s = run_bake(part, err);
    total.baked += s.baked, total.up_to_date += s.up_to_date, total.failed += s.failed;
    total.triangles += s.triangles;
  };
  auto finish = [&](int status) {
    if (config.summary) {
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(err, "%s\n", summary_line(total.baked, total.up_to_date, total.failed, seconds, total.triangles).c_str());
    }
    return status;
  };
  const BakeSummary planning = run_bake(full, err);  // each failure printed here, once
  total.failed = planning.failed;
  if (planning.failed != 0 || status != 0) {
    // The scene cannot be run without every model, so nothing is planned;
    // the files that did bake are still baked, to the full depth.
    BakeConfig rest = config;
    rest.inputs.clear();
    for (const std::string& path : full.inputs) {
      if (!fs::exists(fs::path(full.out_dir) / (fs::path(path).stem().string() + ".oct"))) continue;
      rest.inputs.push_back(path);
      std::fprintf(err, "octbake: note: %s: to depth %d: %s cannot be planned without every model\n", path.c_str(),
                   config.options.depth, scene_path.c_str());
    }
    if (!rest.inputs.empty()) bake_into_out(rest);
    return finish(1);
  }

  // 2. The scene's run on them: the depth each model needs.
  scene->baked = full.out_dir;
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  if (!library) return finish(error(scene_path, library.error().message));
  const scene::RunOptions options;  // octscene run's defaults
  Result<scene::SceneModels> models = scene::load_scene_models(*scene, *library, options.lod.max_depth);
  if (!models) return finish(error(scene_path, models.error().message));
  Result<scene::ScenePlan> plan = scene::plan_scene(*scene, *models, options);
  if (!plan) return finish(error(scene_path, plan.error().message));

  // 3. Each file at its depth, in groups of equal depth.
  std::map<int, std::vector<std::string>> inputs_at_depth;
  for (const scene::ModelPlan& m : plan->models) {
    const int depth = std::max(1, m.needed);
    const std::vector<std::string>& paths = inputs_of_model[m.model];
    inputs_at_depth[depth].insert(inputs_at_depth[depth].end(), paths.begin(), paths.end());
    for (const std::string& path : paths) {
      std::fprintf(err, "octbake: note: %s: model \"%s\" to depth %d of %d (%llu of %llu decoded bytes)%s\n",
                   path.c_str(), m.model.c_str(), depth, m.baked_depth,
                   static_cast<unsigned long long>(m.bytes_needed), static_cast<unsigned long long>(m.bytes_loaded),
                   m.reaches_baked() ? "; the scene's LOD reaches it: a larger -d would be used" : "");
    }
  }
  for (const auto& [depth, paths] : inputs_at_depth) {
    BakeConfig reduced = config;
    reduced.inputs = paths;
    reduced.options.depth = depth;
    bake_into_out(reduced);
  }
  return finish(total.failed == 0 ? status : 1);
}

}  // namespace octbake

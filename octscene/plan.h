// `octscene plan`: which depth of each model a scene actually uses, found by
// running the scene (its motion, responses and LOD) and taking, per model,
// the deepest depth the LOD chose for any of its objects in any frame. Also
// what `octbake --for-scene` bakes to.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "octbake/result.h"
#include "run.h"
#include "scene.h"

namespace octbake::scene {

struct ModelPlan {
  std::string model;
  size_t objects = 0;      // scene objects that use it
  int baked_depth = 0;     // depth of the tree in the library
  int lod_top = 0;         // deepest depth the LOD may pick: min(--max-depth, baked_depth)
  int deepest = 0;         // deepest depth the LOD picked over the run (0 when no frame ran)
  // Depth a reduced file must hold so that a run on it gives the same log as
  // on this one: `deepest`, except under the thesis LOD, whose formula scales
  // with the LOD's top depth (so nothing below lod_top is equivalent).
  int needed = 0;
  uint64_t bytes_needed = 0;  // decoded bytes of levels 1..needed
  uint64_t bytes_loaded = 0;  // decoded bytes of levels 1..lod_top (what `run` decodes)
  // needed == baked_depth: the LOD was stopped by the bake, not by the scene;
  // a deeper bake could be used.
  bool reaches_baked() const { return needed >= baked_depth; }
};

struct ScenePlan {
  int64_t frames = 0;
  std::vector<ModelPlan> models;  // in order of first use in the scene
};

// Runs `scene` with `models` (loaded as load_scene_models(scene, library,
// options.lod.max_depth) does) under `options` and returns each model's plan.
// Errors: those of run_scene.
Result<ScenePlan> plan_scene(const Scene& scene, const SceneModels& models, const RunOptions& options);

// Decoded bytes of levels 1..depth of a tree (level sizes from its header;
// depth clamped to the baked depth).
uint64_t decoded_bytes(const TreeInfo& info, int depth);

}  // namespace octbake::scene

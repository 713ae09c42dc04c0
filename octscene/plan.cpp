#include "plan.h"

#include <algorithm>

namespace octbake::scene {

uint64_t decoded_bytes(const TreeInfo& info, int depth) {
  uint64_t bytes = 0;
  const int top = std::min<int>(depth, static_cast<int>(info.raw_bytes.size()) - 1);
  for (int d = 1; d <= top; ++d) bytes += info.raw_bytes[static_cast<size_t>(d)];
  return bytes;
}

Result<ScenePlan> plan_scene(const Scene& scene, const SceneModels& models, const RunOptions& options) {
  std::vector<int> deepest(models.trees.size(), 0);
  auto run = run_scene(scene, models, options, [&](const FrameReport& frame) {
    // World::step chose these depths at the start of the frame just tested.
    for (size_t i = 0; i < frame.world->size(); ++i) {
      int& d = deepest[models.tree_of_object[i]];
      d = std::max(d, frame.world->depth(i));
    }
  });
  if (!run) return run.error();

  ScenePlan plan;
  plan.frames = run->frames;
  for (size_t t = 0; t < models.trees.size(); ++t) {
    const ObjectTree& tree = models.trees[t];
    ModelPlan m;
    m.model = models.names[t];
    m.objects = static_cast<size_t>(std::count(models.tree_of_object.begin(), models.tree_of_object.end(), t));
    m.baked_depth = tree.info().depth;
    m.lod_top = std::min(tree.loaded_depth(), std::max(0, options.lod.max_depth));
    m.deepest = deepest[t];
    m.needed = options.lod.policy == LodPolicy::thesis && plan.frames > 0 ? m.lod_top : m.deepest;
    m.bytes_needed = decoded_bytes(tree.info(), m.needed);
    m.bytes_loaded = decoded_bytes(tree.info(), m.lod_top);
    plan.models.push_back(std::move(m));
  }
  return plan;
}

}  // namespace octbake::scene

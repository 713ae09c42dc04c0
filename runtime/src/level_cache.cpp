// LevelCache: decode levels on demand, evict the deepest levels of the least
// recently used trees to stay within a byte budget.
#include "octbake/level_cache.h"

#include <algorithm>
#include <cassert>
#include <string>

namespace octbake {

LevelCache::LevelCache(uint64_t budget_bytes) : budget_(budget_bytes) {}

Result<TreeId> LevelCache::add(const BakedFile& file, size_t index) {
  if (index >= file.trees().size()) {
    return Error{ErrorCode::invalid_argument, file.path() + ": no tree " + std::to_string(index)};
  }
  const auto [it, added] = ids_.try_emplace({&file, index}, static_cast<TreeId>(entries_.size()));
  if (!added) return it->second;
  const TreeInfo& info = file.trees()[index];
  OctreeMasks root;
  root.bounds = info.bounds;
  Entry e;
  e.file = &file;
  e.index = index;
  e.tree = std::make_unique<ObjectTree>(info, std::move(root));
  entries_.push_back(std::move(e));
  return static_cast<TreeId>(entries_.size() - 1);
}

uint64_t LevelCache::bytes_at(const Entry& e, int depth) const {
  uint64_t bytes = 0;
  for (int k = 1; k <= depth; ++k) bytes += ObjectTree::level_bytes(e.tree->info(), k);
  return bytes;
}

bool LevelCache::evict_one(const Entry* keep) {
  Entry* victim = nullptr;
  for (Entry& e : entries_) {  // in TreeId order, so ties go to the smaller id
    if (&e == keep || e.tree->loaded_depth() == 0) continue;
    if (!victim || e.last_used < victim->last_used) victim = &e;
  }
  if (!victim) return false;
  ObjectTree& tree = *victim->tree;
  stats_.bytes_held -= tree.level_bytes(tree.loaded_depth() - 1);
  tree.pop_level();
  stats_.evictions += 1;
  return true;
}

Result<int> LevelCache::require(TreeId id, int depth) {
  if (id >= entries_.size()) {
    return Error{ErrorCode::invalid_argument, "level cache: no tree id " + std::to_string(id)};
  }
  if (depth < 0) return Error{ErrorCode::invalid_argument, "level cache: negative depth"};
  Entry& e = entries_[id];
  e.last_used = ++use_clock_;
  ObjectTree& tree = *e.tree;
  const int asked = std::min(depth, tree.info().depth);
  const int held = tree.loaded_depth();
  if (asked <= held) return asked;

  // The deepest depth this tree alone can hold within the budget.
  int target = held;
  uint64_t own = bytes_at(e, held);
  while (target < asked && own + ObjectTree::level_bytes(tree.info(), target + 1) <= budget_) {
    own += ObjectTree::level_bytes(tree.info(), ++target);
  }
  if (target < asked) stats_.budget_clamps += 1;
  if (target == held) return held;

  const uint64_t needed = own - bytes_at(e, held);
  while (stats_.bytes_held + needed > budget_) {
    const bool dropped = evict_one(&e);
    assert(dropped);  // `target` fits alone, so the others can always make room
    (void)dropped;
  }
  for (int k = held + 1; k <= target; ++k) {
    Result<std::vector<uint8_t>> level = e.file->decode_level(e.index, k);
    if (!level) return level.error();
    tree.push_level(std::move(level).value());
    stats_.decodes += 1;
    stats_.bytes_held += tree.level_bytes(k - 1);
    stats_.peak_bytes_held = std::max(stats_.peak_bytes_held, stats_.bytes_held);
  }
  return target;
}

int LevelCache::held_depth(TreeId id) const {
  assert(id < entries_.size());
  return entries_[id].tree->loaded_depth();
}

int LevelCache::baked_depth(TreeId id) const {
  assert(id < entries_.size());
  return entries_[id].tree->info().depth;
}

const ObjectTree& LevelCache::tree(TreeId id) const {
  assert(id < entries_.size());
  return *entries_[id].tree;
}

void LevelCache::set_budget(uint64_t bytes) {
  budget_ = bytes;
  while (stats_.bytes_held > budget_ && evict_one(nullptr)) {
  }
}

}  // namespace octbake

// Streamed levels: ObjectTrees decoded level by level when first needed,
// within a memory budget.
//
// A LevelCache holds one growing ObjectTree per registered tree of a
// BakedFile. require(id, d) decodes the missing levels down to d at once
// (synchronously, so results never depend on timing) and evicts the deepest
// levels of the trees unused for the longest when the budget would be
// exceeded. Everything is deterministic: "unused for the longest" is a
// counter of require() calls, not a clock.
//
// Bytes counted (CacheStats::bytes_held, the budget): per held level, its
// mask bytes plus its first-child index table, i.e. (1 + 4) bytes per box of
// the depth above it (ObjectTree::level_bytes). Depth 0, the root box, costs
// nothing and is always held. Headers, vector overheads and the cache's own
// bookkeeping are not counted.
//
// Thread safety: a LevelCache is used by one world/thread at a time (its
// trees change inside require() and set_budget()). Several caches on several
// threads may share one BakedFile (its reads are thread-safe, see
// baked_file.h); a tree from one cache must not be read by another thread
// while its owner calls require() or set_budget().
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "octbake/export.h"
#include "octbake/baked_file.h"
#include "octbake/object_tree.h"
#include "octbake/result.h"

namespace octbake {

using TreeId = uint32_t;

struct CacheStats {
  uint64_t decodes = 0;        // levels decoded (each level of each tree counts once per decode)
  uint64_t evictions = 0;      // levels dropped to fit the budget
  uint64_t bytes_held = 0;     // decoded bytes currently held (see the header comment)
  uint64_t peak_bytes_held = 0;
  uint64_t budget_clamps = 0;  // require() calls that returned less than asked because of the budget
};

class OCTBAKE_API LevelCache {
 public:
  explicit LevelCache(uint64_t budget_bytes = UINT64_MAX);
  LevelCache(LevelCache&&) noexcept = default;
  LevelCache& operator=(LevelCache&&) noexcept = default;

  // Registers tree `index` of `file` and returns its id (0, 1, 2... in the
  // order trees are first added). Adding the same tree of the same file again
  // returns the same id: instances of one model share one decoded tree. The
  // BakedFile must outlive the cache and stay where it is (not moved).
  // Decodes nothing: the tree starts at depth 0.
  // Errors: invalid_argument for a bad index.
  Result<TreeId> add(const BakedFile& file, size_t index);

  // Makes depth min(depth, baked depth) available, decoding the missing
  // levels synchronously, and marks the tree used now. To stay within the
  // budget it first evicts the deepest levels of the least recently used
  // OTHER trees (ties: the smaller TreeId first), one level at a time, so a
  // tree is emptied down to its root before the next one is touched.
  // Returns the depth available for this request: min(depth, baked depth),
  // or less when the tree alone cannot hold that depth within the budget (the
  // deepest depth that fits; counted in budget_clamps). A tree already held
  // deeper keeps its deeper levels (the return value is still capped at the
  // request). Depth 0 is always available and costs nothing.
  // Caution: a later require() of another tree may evict this tree's levels;
  // read held_depth() again before using tree(id) at some depth.
  // Errors: invalid_argument (unknown id, negative depth);
  // decompress_failed / corrupt from decoding (the levels decoded before the
  // broken one stay held, the stats stay exact).
  Result<int> require(TreeId id, int depth);

  // Preconditions (asserted): id returned by add().
  int held_depth(TreeId id) const;  // levels currently decoded for the tree (0..baked)
  int baked_depth(TreeId id) const;
  // The tree with its currently held levels. The reference stays valid for
  // the cache's lifetime (stable address, also across moves of the cache);
  // its loaded_depth() changes only inside require()/set_budget().
  const ObjectTree& tree(TreeId id) const;
  // Number of registered (distinct) trees.
  size_t size() const { return entries_.size(); }

  // Sets the budget and evicts now if needed: deepest levels of the least
  // recently used trees first (this time any tree, same order as require()).
  void set_budget(uint64_t bytes);
  uint64_t budget() const { return budget_; }
  const CacheStats& stats() const { return stats_; }

 private:
  struct Entry {
    const BakedFile* file = nullptr;
    size_t index = 0;
    std::unique_ptr<ObjectTree> tree;  // heap: a stable address for tree()
    uint64_t last_used = 0;            // value of use_clock_ at its last require(); 0 = never
  };
  // Bytes the tree would hold at `depth` (from its header).
  uint64_t bytes_at(const Entry& e, int depth) const;
  // Drops the deepest level of the least recently used tree holding any level,
  // skipping `keep` (nullptr: none). False when there is nothing to drop.
  bool evict_one(const Entry* keep);

  uint64_t budget_;
  uint64_t use_clock_ = 0;
  std::vector<Entry> entries_;
  std::map<std::pair<const BakedFile*, size_t>, TreeId> ids_;  // for add() of a tree already added
  CacheStats stats_;
};

}  // namespace octbake

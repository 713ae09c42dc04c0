// The WorldTree: a fixed octree over the world bounds whose leaves hold object
// ids; objects sharing a leaf are candidate pairs. An object may sit in several
// leaves.
//
// Only the leaf level is stored (a uniform grid of 2^depth cells per axis), and
// only cells that hold something: a sparse table of cells plus, per object,
// the cells it sits in.
//
// Objects (partly) outside the world box are clamped into the border cells,
// which thus reach to infinity. Clamping keeps the cell map monotone, so two
// boxes that overlap always share a cell and nothing is ever dropped. (Pairing
// outside objects with everything, the first design, made a frame quadratic as
// soon as moving objects grazed the world's faces.) Only an object whose cell
// range exceeds kMaxCells (a ground plane in a deep world) goes to the
// overflow set, which is paired with everything, instead of filling thousands
// of cells.
//
// Pairs are reported without duplicates and without a dedup pass: a pair is
// emitted only by its *first common cell*, the cell (max of both objects' min
// cell, per axis), which both objects hold whenever they share any cell.
// Only cells holding two or more objects are scanned (a list kept as objects
// enter and leave cells), then the pairs are sorted. Cost: the sum over busy
// cells of occupants^2, i.e. the true candidate set, plus |overflow| *
// |objects|, all linear; no pass over the world's single-object cells.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "octbake/octree.h"
#include "octbake/export.h"

namespace octbake {

class OCTBAKE_API WorldTree {
 public:
  // depth 0..10 (cells per axis = 2^depth). The world box must have a positive
  // extent on every axis.
  WorldTree(const Aabb& world, int depth);

  // An object spanning more cells than this is paired with everything instead.
  static constexpr uint64_t kMaxCells = 1024;

  // Inserts object `id` or moves it to `box`. Returns true when its leaf set
  // (the cell range its box covers, clamped to the grid) changed, false when nothing needed re-inserting. A move that
  // returns true counts one reinsertion; a first insertion does not. `box`
  // must not hold NaN.
  bool update(uint32_t id, const Aabb& box);
  void remove(uint32_t id);  // no-op for an absent id

  // Candidate pairs (a < b), each once, sorted ascending: every two objects
  // sharing a (clamped) cell, plus every overflow object with every other
  // object. A superset of the pairs whose boxes overlap.
  // `out` is cleared first.
  void candidate_pairs(std::vector<std::pair<uint32_t, uint32_t>>& out) const;
  // The candidate pairs whose boxes overlap (closed boxes: touching counts),
  // filtered before sorting. boxes[id] must be the box last given to update(id).
  void overlapping_pairs(std::span<const Aabb> boxes, std::vector<std::pair<uint32_t, uint32_t>>& out) const;

  int depth() const { return depth_; }
  const Aabb& bounds() const { return world_; }
  uint64_t reinsertions() const { return reinsertions_; }
  bool contains(uint32_t id) const { return id < entries_.size() && entries_[id].present; }
  bool in_overflow(uint32_t id) const { return contains(id) && entries_[id].overflow; }

 private:
  using Coord = std::array<uint16_t, 3>;
  struct Entry {
    Coord lo{}, hi{};  // inclusive cell range, clamped to the grid
    bool present = false;
    bool overflow = false;
    std::vector<uint32_t> cells;  // slots in cells_ (empty when overflow)
  };
  struct Cell {
    Coord at{};
    std::vector<uint32_t> ids;  // sorted ascending
  };

  Coord cell_of(const Eigen::Vector3d& p) const;
  template <class Keep>
  void collect_pairs(std::vector<std::pair<uint32_t, uint32_t>>& out, Keep keep) const;
  // Moves `id` from the cells of entries_[id]'s range to those of [lo, hi],
  // touching only the cells that differ.
  void relink(uint32_t id, const Coord& lo, const Coord& hi, bool overflow);
  void enter_cell(uint32_t slot, uint32_t id);
  void leave_cell(uint32_t slot, uint32_t id);
  uint32_t cell_slot(const Coord& at);  // finds or creates
  size_t table_find(uint32_t key) const;
  void table_grow();

  Aabb world_;
  int depth_;
  uint32_t side_;  // cells per axis
  Eigen::Vector3d inv_cell_;
  uint64_t reinsertions_ = 0;
  std::vector<Entry> entries_;  // by id
  std::vector<Coord> lo_;       // hot copy of entries_[id].lo for the pair loop
  std::vector<Cell> cells_;
  std::vector<uint32_t> free_cells_;  // emptied slots, reused LIFO
  // Bit per cell slot: set while the cell holds two or more objects. The pair
  // scan visits only these, in slot order (most cells of a sparse world hold
  // one object; a list in arbitrary order made every visit a cache miss).
  std::vector<uint64_t> busy_;
  // Cell coordinate -> slot: open addressing with linear probing and
  // backward-shift deletion (no tombstones, no allocation per insert; the
  // node-based std::unordered_map was 15% of a frame). Entries are
  // (packed coord + 1) << 32 | slot, 0 when empty. Never iterated.
  std::vector<uint64_t> table_;
  size_t table_used_ = 0;
  std::vector<uint32_t> overflow_ids_;  // sorted
  std::vector<uint32_t> present_ids_;   // sorted
  mutable std::vector<std::pair<uint32_t, uint32_t>> sort_scratch_;  // candidate_pairs' radix sort
};

}  // namespace octbake

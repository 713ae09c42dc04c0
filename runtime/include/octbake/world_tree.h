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
// |objects|, all linear; no pass over the world's single-object cells. When
// the pairs are filtered by their boxes (overlapping_pairs, scan_part), a
// cell of more than 32 is swept by box min x instead: a crowd in a shallow
// world costs k log k plus the overlapping pairs, not k^2. And once the
// overflow set is large (kCoarseFrom), those scans pair it through coarse
// cells instead of with every object.
#pragma once
#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "octbake/octree.h"
#include "octbake/export.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace octbake {

class OCTBAKE_API WorldTree {
 public:
  // depth 0..10 (cells per axis = 2^depth). The world box must have a positive
  // extent on every axis.
  WorldTree(const Aabb& world, int depth);

  // An object spanning more cells than this is paired with everything instead.
  static constexpr uint64_t kMaxCells = 1024;
  // Past this many (overflow objects x objects), the box-filtered scans pair
  // the overflow objects through coarse cells of 2^kCoarseShift cells a side
  // (those over more than kCoarseMaxCells of them still with everything): the
  // cost is then about the objects' coarse cells, not the product. Where the
  // coarse cells would cost more (huge overflow objects, or many sharing
  // coarse cells), all are still paired with everything.
  static constexpr uint64_t kCoarseFrom = uint64_t(1) << 18;
  static constexpr int kCoarseShift = 3;
  static constexpr uint64_t kCoarseMaxCells = 4096;

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

  // ---- the same work in parallel parts (CollisionWorld runs them on its
  // executor). The const ones read only, so any number may run at once while
  // no update(), update_cells() or remove() runs.
  // The cells update(id, box) would put an object in; update_cells(id, range)
  // does the same as update(id, box) without computing them again.
  struct CellRange {
    std::array<uint16_t, 3> lo{}, hi{};  // inclusive, clamped to the grid
    bool overflow = false;
  };
  CellRange cell_range(const Aabb& box) const;  // `box` must not hold NaN
  bool update_cells(uint32_t id, const CellRange& range);
  // Would update_cells(id, range) change anything (a new id, or other cells)?
  bool needs_update(uint32_t id, const CellRange& range) const;
  // The same for update(id, box), without building a CellRange: set_pose
  // asks it for every moved object.
  bool needs_update(uint32_t id, const Aabb& box) const;
  // What the batch below runs its parts on: calls task(ctx, begin, end) on
  // disjoint ranges covering [0, count) exactly once, on any threads, in any
  // order, and returns when all are done.
  class Parallel {
   public:
    virtual void for_ranges(size_t count, size_t grain, void (*task)(const void* ctx, size_t begin, size_t end),
                            const void* ctx) = 0;

   protected:
    ~Parallel() = default;
  };
  // update_cells(ids[k], ranges[k]) for every k (ids distinct), mostly in
  // parallel: each object works out the cells it leaves and enters (looked
  // up, not yet changed); the cells new to the table are made, in k order;
  // then the cells take their arrivals and departures in `parts` groups of
  // disjoint cells (a power of two; 1 when running inline; a batch of at
  // most 64 moves uses 1: handing out parts would cost more), and each object
  // its new cell list; last the cells left empty are freed, in k order.
  // Objects that are new, go to or from overflow, or span more than
  // kFastCells cells take the one-by-one path, in k order. The cells'
  // contents, pairs, queries and reinsertions after it equal those of the
  // one-by-one calls whatever `parts` and `parallel` do; only the internal
  // cell numbering may differ, and nothing observable depends on it (pairs
  // and query answers are sorted, ray walks go by geometry). Allocates only
  // to grow with the world.
  static constexpr uint32_t kFastCells = 8;
  void update_cells(std::span<const uint32_t> ids, std::span<const CellRange> ranges, Parallel& parallel, size_t parts);
  // overlapping_pairs in pieces: scan_part(k) for every k < scan_parts()
  // hands the cell pairs of its share of the cells to `sink`, in blocks,
  // every pair in exactly one part; finish_pairs, given all the parts' pairs
  // in any order, adds the overflow pairs and sorts. The result equals
  // overlapping_pairs however the parts are run.
  class PairSink {
   public:
    // Called by scan_part, from several threads at once when parts run in parallel.
    virtual void take(std::span<const std::pair<uint32_t, uint32_t>> pairs) = 0;

   protected:
    ~PairSink() = default;
  };
  size_t scan_parts() const;
  void scan_part(size_t part, std::span<const Aabb> boxes, PairSink& sink) const;
  void finish_pairs(std::span<const Aabb> boxes, std::vector<std::pair<uint32_t, uint32_t>>& out) const;

  int depth() const { return depth_; }
  const Aabb& bounds() const { return world_; }
  uint64_t reinsertions() const { return reinsertions_; }
  // Cells in the table: after every update(), update_cells() and remove(),
  // exactly the cells holding an object (those left empty are freed).
  size_t cells_in_use() const { return table_used_; }
  // Cells the tree can hold before its cell array or table must grow (copy
  // or rehash every cell). A batch of update_cells that made at least a
  // third as many cells as it found (a load, a spawn) leaves room for twice
  // the cells in use, so the frames after it, which make a few, grow neither.
  size_t cell_room() const { return std::min(cells_.capacity(), table_.size() / 2); }
  bool contains(uint32_t id) const { return id < entries_.size() && entries_[id].present; }
  bool in_overflow(uint32_t id) const { return contains(id) && entries_[id].overflow; }

  // ---- queries ----
  // Every object whose cell range meets the (clamped) cell range of `box`,
  // plus every overflow object, each once, sorted ascending: a superset of the
  // objects whose update() box overlaps `box`, exactly as candidate_pairs
  // (the cell map is monotone, so no padding is needed). Dedup without state:
  // an object is taken only in its first common cell with the query range.
  // Cost: min(cells in the range, occupied cells) + ids found; `out` is
  // cleared first and only allocates to grow. `box` must not hold NaN.
  void query_box(const Aabb& box, std::vector<uint32_t>& out) const;
  const std::vector<uint32_t>& overflow_ids() const { return overflow_ids_; }  // sorted

  // The occupied cells met by the ray segment origin + t * dir, t in
  // [0, t_max] (t_max may be infinite), in order of entry: a 3D DDA
  // (Amanatides & Woo) over the clamped grid, so a ray outside the world box
  // still walks the border cells that reach to infinity. Conservative: it
  // walks a thin tube around the ray (delta grid units, 1e-12 of the
  // coordinates' magnitude in cells, far above rounding), so every cell whose region
  // the ray meets, up to rounding, is reported; entry() is never later than
  // the ray's entry into the tube's part of that cell. Each cell is reported
  // once; an object spanning several cells is reported once per cell (the
  // caller dedups). Overflow objects are in no cell: see overflow_ids().
  // origin and dir must be finite. Holds no allocation; the tree must not
  // change while walking.
  class OCTBAKE_API RayWalk {
   public:
    RayWalk(const WorldTree& tree, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max);
    // Advances to the next occupied cell; false when the segment is done.
    bool next();
    double entry() const { return entry_; }  // ray distance at which the current cell was reached
    std::array<uint16_t, 3> cell() const { return at_; }
    std::span<const uint32_t> ids() const {  // sorted
      const CellIds& ids = tree_->cells_[slot_].ids;
      return {ids.data(), ids.size()};
    }

   private:
    void schedule(int k);  // next lead and trail event times of axis k
    const WorldTree* tree_;
    double t_max_;
    double entry_ = 0;
    // Per axis, in grid units: g(t) = g0 + t * dg; the tube covers cells
    // [lo, hi] = clamped floor of g(t) -+ delta. The leading edge (hi when
    // dg > 0, lo when dg < 0) adds a slab of cells when it crosses a cell
    // boundary; the trailing edge only shrinks the range.
    std::array<double, 3> g0_{}, dg_{}, delta_{}, t_lead_{}, t_trail_{};
    std::array<int, 3> lo_{}, hi_{}, step_{};
    // The box of cells being enumerated (a slab just reached, or the first box).
    std::array<int, 3> elo_{}, ehi_{}, cur_{};
    bool enumerating_ = false;
    std::array<uint16_t, 3> at_{};
    uint32_t slot_ = 0;
  };

 private:
  using Coord = std::array<uint16_t, 3>;
  struct Entry {
    Coord lo{}, hi{};  // inclusive cell range, clamped to the grid
    bool present = false;
    bool overflow = false;
    // Slots in cells_ of [lo, hi], z slowest, x fastest (so a slot's cell is
    // known from its index without reading the cell); empty when overflow.
    std::vector<uint32_t> cells;
  };
  // A cell's ids, sorted ascending: up to kInline in place, so a cell of a
  // few objects (most of them) needs no heap block of its own and its ids
  // come with it. Capacity is kept when ids leave: a reused cell allocates
  // only to hold more than it ever held (6 in place: no allocation in a
  // steady bench_world frame; 4 gave a few).
  class CellIds {
   public:
    CellIds() = default;
    CellIds(const CellIds& o) { assign(o); }
    CellIds& operator=(const CellIds& o) {
      if (this != &o) release(), assign(o);
      return *this;
    }
    CellIds(CellIds&& o) noexcept { take(o); }
    CellIds& operator=(CellIds&& o) noexcept {
      if (this != &o) release(), take(o);
      return *this;
    }
    ~CellIds() { release(); }
    const uint32_t* data() const { return on_heap() ? heap_ : in_; }
    size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    bool in_place() const { return cap_ <= kInline; }  // data() is inside this object
    const uint32_t* begin() const { return data(); }
    const uint32_t* end() const { return data() + size_; }
    void insert_sorted(uint32_t id);
    void erase_sorted(uint32_t id);  // no-op when absent

   private:
    static constexpr uint32_t kInline = 6;
    bool on_heap() const { return cap_ > kInline; }
    uint32_t* data() { return on_heap() ? heap_ : in_; }
    void assign(const CellIds& o);
    void take(CellIds& o);
    void release();
    uint32_t size_ = 0, cap_ = kInline;
    union {
      uint32_t in_[kInline]{};
      uint32_t* heap_;
    };
  };
  struct Cell {
    Coord at{};
    bool linked = false;  // in table_ (else on free_cells_)
    CellIds ids;
  };
  // The batch update_cells: one object's cell changes.
  enum class MoveKind : uint8_t { same, fast, slow };
  struct Move {
    MoveKind kind = MoveKind::same;
    uint8_t leaves = 0, enters = 0;
    uint8_t missing = 0;  // bit i: enter[i]'s cell was not in the table yet
    // Slots (enter in [lo, hi] order); a missing cell's enter is its packed
    // coordinate until the serial step finds or makes its slot.
    std::array<uint32_t, kFastCells> leave, enter;
    std::array<bool, kFastCells> emptied;  // leave[i] left its cell empty
  };

  Coord cell_of(const Eigen::Vector3d& p) const;
  static uint64_t packed(const Coord& c) { return uint64_t(c[0]) | uint64_t(c[1]) << 16 | uint64_t(c[2]) << 32; }
#if defined(__SSE2__)
  // cell_of's cells of box.min[k] and box.max[k], in int32 lanes 0 and 1.
  __m128i axis_cells(const Aabb& box, int k) const;
#endif
  // Cells in the inclusive range [lo, hi].
  static uint64_t cell_count(const Coord& lo, const Coord& hi) {
    uint64_t n = 1;
    for (int k = 0; k < 3; ++k) n *= uint64_t(hi[k]) - lo[k] + 1;
    return n;
  }
  // emit(a, b) for the cell pairs of the busy cells of bitmap words
  // [begin, end) that keep(a, b) accepts.
  template <class Keep, class Emit>
  void scan_cells(size_t begin, size_t end, Keep keep, Emit emit) const;
  // Appends the overflow pairs and sorts `out`.
  template <class Keep>
  void finish(std::vector<std::pair<uint32_t, uint32_t>>& out, Keep keep) const;
  // finish()'s overflow pairs with overlapping boxes, through coarse cells;
  // returns the overflow objects it leaves to pair with every object.
  std::span<const uint32_t> pair_overflow_by_coarse_cells(std::vector<std::pair<uint32_t, uint32_t>>& out,
                                     std::span<const Aabb> boxes) const;
  // Moves `id` from the cells of entries_[id]'s range to those of [lo, hi],
  // touching only the cells that differ.
  void relink(uint32_t id, const Coord& lo, const Coord& hi, bool overflow);
  bool move_one(uint32_t id, const CellRange& range);  // update_cells but free_emptied()
  // The batch's phases (see update_cells(ids, ...)).
  void plan_move(uint32_t id, const CellRange& range, Move& m) const;
  void apply_moves(std::span<const uint32_t> ids, size_t part, size_t parts);
  void finish_move(uint32_t id, const CellRange& range, const Move& m);
  void enter_cell(uint32_t slot, uint32_t id);
  bool leave_cell(uint32_t slot, uint32_t id);  // true: the cell is left empty
  uint32_t cell_slot(const Coord& at);  // finds or creates
  size_t table_find(uint32_t key) const;
  void table_grow(size_t at_least = 0);  // to twice its size, and at least `at_least` entries
  // leave_cell, the cell listed in emptied_ if left empty.
  void leave_and_list(uint32_t slot, uint32_t id);
  // Frees emptied_'s cells that are still empty. update() and remove() call
  // it at their end; a batch at its end only (its plan holds slots looked up
  // before).
  void free_emptied();
  void free_cell(uint32_t slot);

  Aabb world_;
  int depth_;
  uint32_t side_;  // cells per axis
  Eigen::Vector3d inv_cell_;
  // axis_cells' constants for the six bounds (min x, max x, min y, ...).
  alignas(16) std::array<double, 6> origin6_{}, inv6_{};
  uint64_t reinsertions_ = 0;
  std::vector<Entry> entries_;  // by id
  // Hot copy of entries_[id].lo for the pair loop, packed (x | y << 16 |
  // z << 32): the first-common-cell test is one lane-wise max and compare.
  std::vector<uint64_t> lo_;
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
  std::vector<Move> moves_;         // the batch's plan, per item
  std::vector<uint32_t> old_cells_;  // relink's copy of an entry's cells
  std::vector<uint32_t> emptied_;    // cells left empty, to free (free_emptied)
  std::vector<uint32_t> overflow_ids_;  // sorted
  size_t present_ = 0;                  // objects in the tree (entries_ present)
  mutable std::vector<std::pair<uint32_t, uint32_t>> sort_scratch_;  // candidate_pairs' radix sort
  mutable std::vector<std::pair<uint64_t, uint32_t>> coarse_scratch_;  // pair_overflow_by_coarse_cells
  mutable std::vector<uint32_t> everywhere_scratch_;                   // and its objects paired with all
};

// Inline: commit_poses runs these once per moved object.

// Monotone in p on every axis (subtraction and multiplication by a positive
// constant round monotonically, and clamping keeps order), so two boxes
// overlapping on an axis always share a cell on it, inside the world or not:
// the broadphase never misses a pair.
inline WorldTree::Coord WorldTree::cell_of(const Eigen::Vector3d& p) const {
  Coord c;
  for (int k = 0; k < 3; ++k) {
    const double t = (p[k] - world_.min[k]) * inv_cell_[k];
    c[k] = t >= double(side_) ? uint16_t(side_ - 1) : t > 0 ? uint16_t(t) : uint16_t(0);
  }
  return c;
}

#if defined(__SSE2__)
inline __m128i WorldTree::axis_cells(const Aabb& box, int k) const {
  // cell_of on two bounds at once (set_pose and commit_poses run this per
  // moved object: the scalar clamps were most of its cost). The same
  // subtraction and product, so the same t; clamping t to [0, side - 1]
  // before truncating gives cell_of's cells (t >= side and t in
  // [side - 1, side) both give side - 1). Each bound is read on its own, as
  // set_pose has just stored it: a 16-byte load over two stores cannot take
  // their values from the store buffer, and stalled set_pose until they
  // reached the cache.
  const __m128d bounds = _mm_loadh_pd(_mm_load_sd(&box.min[k]), &box.max[k]);
  const __m128d t = _mm_mul_pd(_mm_sub_pd(bounds, _mm_load_pd(origin6_.data() + 2 * k)), _mm_load_pd(inv6_.data() + 2 * k));
  return _mm_cvttpd_epi32(_mm_min_pd(_mm_max_pd(t, _mm_setzero_pd()), _mm_set1_pd(double(side_ - 1))));
}
#endif

inline WorldTree::CellRange WorldTree::cell_range(const Aabb& box) const {
  assert(!box.min.hasNaN() && !box.max.hasNaN());
  CellRange r;
#if defined(__SSE2__)
  alignas(16) std::array<int32_t, 8> cell;
  for (int k = 0; k < 3; ++k) _mm_storel_epi64(reinterpret_cast<__m128i*>(cell.data() + 2 * k), axis_cells(box, k));
  for (int k = 0; k < 3; ++k) {
    r.lo[k] = uint16_t(cell[2 * k]);
    r.hi[k] = uint16_t(cell[2 * k + 1]);
  }
#else
  r.lo = cell_of(box.min);
  r.hi = cell_of(box.max);
#endif
  r.overflow = cell_count(r.lo, r.hi) > kMaxCells;
  return r;
}

inline bool WorldTree::needs_update(uint32_t id, const CellRange& r) const {
  if (!contains(id)) return true;
  const Entry& e = entries_[id];
  for (int k = 0; k < 3; ++k)
    if (e.lo[k] != r.lo[k] || e.hi[k] != r.hi[k]) return true;
  return e.overflow != r.overflow;
}

}  // namespace octbake

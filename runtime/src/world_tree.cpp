#include "octbake/world_tree.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <limits>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace octbake {

namespace {

constexpr size_t kEntryReserve = 8;
constexpr size_t kRadixFrom = 256;

void insert_sorted(std::vector<uint32_t>& v, uint32_t id) {
  v.insert(std::lower_bound(v.begin(), v.end(), id), id);
}

void erase_sorted(std::vector<uint32_t>& v, uint32_t id) {
  auto it = std::lower_bound(v.begin(), v.end(), id);
  if (it != v.end() && *it == id) v.erase(it);
}

}  // namespace

void WorldTree::CellIds::insert_sorted(uint32_t id) {
  if (size_ == cap_) {
    uint32_t* grown = new uint32_t[2 * size_t(cap_)];
    std::copy(begin(), end(), grown);
    release();
    heap_ = grown;
    cap_ *= 2;
  }
  uint32_t* d = data();
  uint32_t* at = std::lower_bound(d, d + size_, id);
  std::copy_backward(at, d + size_, d + size_ + 1);
  *at = id;
  ++size_;
}

void WorldTree::CellIds::erase_sorted(uint32_t id) {
  uint32_t* d = data();
  uint32_t* at = std::lower_bound(d, d + size_, id);
  if (at == d + size_ || *at != id) return;
  std::copy(at + 1, d + size_, at);
  --size_;
}

// The union's members are made active by assigning to them by name.
void WorldTree::CellIds::assign(const CellIds& o) {
  size_ = o.size_, cap_ = o.cap_;
  if (on_heap()) {
    heap_ = new uint32_t[cap_];
    std::copy(o.begin(), o.end(), heap_);
  } else {
    for (uint32_t i = 0; i < kInline; ++i) in_[i] = o.in_[i];
  }
}

void WorldTree::CellIds::take(CellIds& o) {
  size_ = o.size_, cap_ = o.cap_;
  if (on_heap())
    heap_ = o.heap_;
  else
    for (uint32_t i = 0; i < kInline; ++i) in_[i] = o.in_[i];
  o.size_ = 0, o.cap_ = kInline;
  for (uint32_t i = 0; i < kInline; ++i) o.in_[i] = 0;
}

void WorldTree::CellIds::release() {
  if (on_heap()) delete[] heap_;
}

WorldTree::WorldTree(const Aabb& world, int depth) : world_(world), depth_(depth), side_(1u << depth) {
  assert(depth >= 0 && depth <= 10);  // packed cell keys use 10 bits per axis
  assert((world.max.array() > world.min.array()).all());
  inv_cell_ = Eigen::Vector3d::Constant(double(side_)).cwiseQuotient(world.max - world.min);
  for (int k = 0; k < 6; ++k) {
    origin6_[k] = world.min[k / 2];
    inv6_[k] = inv_cell_[k / 2];
  }
}

namespace {

uint32_t pack(const std::array<uint16_t, 3>& c) { return uint32_t(c[0]) | (uint32_t(c[1]) << 10) | (uint32_t(c[2]) << 20); }
std::array<uint16_t, 3> unpack(uint32_t key) {
  return {uint16_t(key & 1023u), uint16_t((key >> 10) & 1023u), uint16_t((key >> 20) & 1023u)};
}

// Fibonacci hashing of the packed coordinate into the table.
size_t home(uint32_t key, size_t mask) { return size_t((key * 0x9E3779B97F4A7C15ull) >> 32) & mask; }

bool inside(const std::array<uint16_t, 3>& c, const std::array<uint16_t, 3>& lo, const std::array<uint16_t, 3>& hi) {
  for (int k = 0; k < 3; ++k)
    if (c[k] < lo[k] || c[k] > hi[k]) return false;
  return true;
}

// f(c) for the cells of [lo, hi], z slowest, x fastest: Entry::cells' order.
template <class F>
void for_each_cell(const std::array<uint16_t, 3>& lo, const std::array<uint16_t, 3>& hi, F f) {
  std::array<uint16_t, 3> c;
  for (c[2] = lo[2]; c[2] <= hi[2]; ++c[2])
    for (c[1] = lo[1]; c[1] <= hi[1]; ++c[1])
      for (c[0] = lo[0]; c[0] <= hi[0]; ++c[0]) f(c);
}

// Index of cell c in for_each_cell(lo, hi)'s order.
size_t index_in(const std::array<uint16_t, 3>& c, const std::array<uint16_t, 3>& lo, const std::array<uint16_t, 3>& hi) {
  const size_t nx = size_t(hi[0]) - lo[0] + 1, ny = size_t(hi[1]) - lo[1] + 1;
  return ((size_t(c[2]) - lo[2]) * ny + (size_t(c[1]) - lo[1])) * nx + (size_t(c[0]) - lo[0]);
}

}  // namespace

// Index of `key`'s entry, or of the empty entry where it would go.
size_t WorldTree::table_find(uint32_t key) const {
  const size_t mask = table_.size() - 1;
  const uint64_t tag = uint64_t(key) + 1;
  for (size_t i = home(key, mask);; i = (i + 1) & mask)
    if (table_[i] == 0 || (table_[i] >> 32) == tag) return i;
}

void WorldTree::table_grow(size_t at_least) {
  std::vector<uint64_t> old(std::max({size_t(64), table_.size() * 2, std::bit_ceil(at_least)}), 0);
  old.swap(table_);
  for (uint64_t e : old)
    if (e != 0) table_[table_find(uint32_t((e >> 32) - 1))] = e;
}

uint32_t WorldTree::cell_slot(const Coord& at) {
  if (2 * (table_used_ + 1) > table_.size()) table_grow();
  const uint32_t key = pack(at);
  const size_t i = table_find(key);
  if (table_[i] != 0) return uint32_t(table_[i]);
  uint32_t slot;
  if (free_cells_.empty()) {
    slot = uint32_t(cells_.size());
    cells_.emplace_back();  // room for a few ids in place (CellIds)
    if (busy_.size() * 64 < cells_.size()) busy_.push_back(0);
  } else {
    slot = free_cells_.back();
    free_cells_.pop_back();
  }
  cells_[slot].at = at;
  cells_[slot].linked = true;
  table_[i] = ((uint64_t(key) + 1) << 32) | slot;
  ++table_used_;
  return slot;
}

void WorldTree::enter_cell(uint32_t slot, uint32_t id) {
  Cell& cell = cells_[slot];
  cell.ids.insert_sorted(id);
  if (cell.ids.size() == 2) busy_[slot / 64] |= uint64_t(1) << (slot % 64);
}

bool WorldTree::leave_cell(uint32_t slot, uint32_t id) {
  Cell& cell = cells_[slot];
  cell.ids.erase_sorted(id);
  if (cell.ids.size() < 2) busy_[slot / 64] &= ~(uint64_t(1) << (slot % 64));
  return cell.ids.empty();
}

// Takes the cell out of the table (so a long run over a deep world does not
// accumulate cells) and lists its slot for reuse.
void WorldTree::free_cell(uint32_t slot) {
  Cell& cell = cells_[slot];
  const size_t mask = table_.size() - 1;
  size_t i = table_find(pack(cell.at));
  // Backward-shift deletion: pull later entries of the probe run into the gap
  // unless their home lies cyclically in (gap, j].
  for (size_t j = (i + 1) & mask; table_[j] != 0; j = (j + 1) & mask) {
    const size_t h = home(uint32_t((table_[j] >> 32) - 1), mask);
    const bool stays = i <= j ? (i < h && h <= j) : (i < h || h <= j);
    if (stays) continue;
    table_[i] = table_[j];
    i = j;
  }
  table_[i] = 0;
  --table_used_;
  cell.linked = false;
  free_cells_.push_back(slot);
}

void WorldTree::relink(uint32_t id, const Coord& lo, const Coord& hi, bool overflow) {
  Entry& e = entries_[id];
  const bool was_linked = e.present && !e.overflow;
  const bool was_overflow = e.present && e.overflow;
  if (was_overflow && !overflow) erase_sorted(overflow_ids_, id);
  if (overflow && !was_overflow) insert_sorted(overflow_ids_, id);
  if (e.cells.capacity() < kEntryReserve) e.cells.reserve(kEntryReserve);  // a box over 2x2x2 cells
  old_cells_.assign(e.cells.begin(), e.cells.end());
  e.cells.clear();
  // Leave the cells outside the new range (all of them when going to overflow).
  if (was_linked) {
    size_t i = 0;
    for_each_cell(e.lo, e.hi, [&](const Coord& c) {
      const uint32_t slot = old_cells_[i++];
      if (overflow || !inside(c, lo, hi)) leave_and_list(slot, id);
    });
  }
  if (!overflow)
    for_each_cell(lo, hi, [&](const Coord& c) {
      if (was_linked && inside(c, e.lo, e.hi)) {  // already there
        e.cells.push_back(old_cells_[index_in(c, e.lo, e.hi)]);
        return;
      }
      const uint32_t slot = cell_slot(c);
      enter_cell(slot, id);
      e.cells.push_back(slot);
    });
  e.lo = lo;
  e.hi = hi;
  e.overflow = overflow;
  e.present = true;
  lo_[id] = packed(lo);
}

void WorldTree::leave_and_list(uint32_t slot, uint32_t id) {
  if (leave_cell(slot, id)) emptied_.push_back(slot);
}

// Frees the cells listed as emptied that still are, in list order: the free
// list then serves the next cells made, so the table and the cells stay the
// size of the occupied cells. (Left to pile up until they outnumbered the
// occupied ones, a moving crowd's empty cells grew both first: at ~850k
// cells a 200-400 ms frame, mostly fresh memory, then a pass over them all.)
void WorldTree::free_emptied() {
  for (uint32_t slot : emptied_)
    if (cells_[slot].linked && cells_[slot].ids.empty()) free_cell(slot);
  emptied_.clear();
}

bool WorldTree::update(uint32_t id, const Aabb& box) { return update_cells(id, cell_range(box)); }

bool WorldTree::needs_update(uint32_t id, const Aabb& box) const {
#if defined(__SSE2__)
  // cell_range's cells compared with the entry's as they come, without
  // building a CellRange: most moves keep their cells, and the same cells
  // mean the same overflow. Set_pose asks this per moved object.
  if (!contains(id)) return true;
  const __m128i c[3] = {axis_cells(box, 0), axis_cells(box, 1), axis_cells(box, 2)};
  // As the entry stores them: lo x, y, z, hi x, y, z (16-bit, all < 2^10).
  const __m128i xy = _mm_unpacklo_epi32(c[0], c[1]);                                      // lo x, lo y, hi x, hi y
  const __m128i zx = _mm_unpacklo_epi32(c[2], _mm_shuffle_epi32(c[0], 1));                // lo z, hi x, hi z, -
  const __m128i lo_hx = _mm_unpacklo_epi64(xy, zx);                                       // lo x, y, z, hi x
  const __m128i hyz = _mm_unpacklo_epi32(_mm_shuffle_epi32(xy, 3), _mm_shuffle_epi32(zx, 2));  // hi y, hi z
  const Entry& e = entries_[id];
  static_assert(offsetof(Entry, hi) == sizeof(Coord) && sizeof(Coord) == 6);
  const __m128i stored = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&e.lo));  // lo, hi, then 4 bytes not compared
  const int same = _mm_movemask_epi8(_mm_cmpeq_epi16(_mm_packs_epi32(lo_hx, hyz), stored));
  return (same & 0x0FFF) != 0x0FFF;
#else
  return needs_update(id, cell_range(box));
#endif
}

bool WorldTree::update_cells(uint32_t id, const CellRange& r) {
  const bool changed = move_one(id, r);
  free_emptied();
  return changed;
}

bool WorldTree::move_one(uint32_t id, const CellRange& r) {
  if (id >= entries_.size()) {
    entries_.resize(id + 1);
    lo_.resize(id + 1);
  }
  const Entry& e = entries_[id];
  if (e.present) {
    if (!needs_update(id, r)) return false;
    ++reinsertions_;
  } else {
    ++present_;
  }
  relink(id, r.lo, r.hi, r.overflow);
  return true;
}

void WorldTree::remove(uint32_t id) {
  if (!contains(id)) return;
  Entry& e = entries_[id];
  if (e.overflow) erase_sorted(overflow_ids_, id);
  for (uint32_t slot : e.cells) leave_and_list(slot, id);
  e = Entry{};
  --present_;
  free_emptied();
}

// ---- the batch ----

namespace {

// Items per part of the per-object phases.
constexpr size_t kMoveGrain = 64;

template <class F>
void for_ranges(WorldTree::Parallel& parallel, size_t count, size_t grain, const F& f) {
  if (count == 0) return;
  parallel.for_ranges(count, grain, [](const void* ctx, size_t b, size_t e) { (*static_cast<const F*>(ctx))(b, e); }, &f);
}

}  // namespace

// Reads only: the cells `id` leaves (from its entry, no cell read) and the
// slots of those it enters, when the table has them.
void WorldTree::plan_move(uint32_t id, const CellRange& r, Move& m) const {
  m.leaves = m.enters = m.missing = 0;
  if (!needs_update(id, r)) {
    m.kind = MoveKind::same;
    return;
  }
  if (!contains(id) || entries_[id].overflow || r.overflow || cell_count(entries_[id].lo, entries_[id].hi) > kFastCells ||
      cell_count(r.lo, r.hi) > kFastCells) {
    m.kind = MoveKind::slow;
    return;
  }
  const Entry& e = entries_[id];
  m.kind = MoveKind::fast;
  size_t i = 0;
  for_each_cell(e.lo, e.hi, [&](const Coord& c) {
    const uint32_t slot = e.cells[i++];
    if (!inside(c, r.lo, r.hi)) m.leave[m.leaves++] = slot;
  });
  for_each_cell(r.lo, r.hi, [&](const Coord& c) {
    if (inside(c, e.lo, e.hi)) return;
    const uint32_t key = pack(c);
    const size_t t = table_find(key);  // the table is not empty: e has cells
    if (table_[t] == 0) {
      m.missing |= uint8_t(1u << m.enters);
      m.enter[m.enters++] = key;
    } else {
      m.enter[m.enters++] = uint32_t(table_[t]);
    }
  });
}

// The arrivals and departures of the cells of part `part`: the slots in
// the part-th of parts equal runs of busy_ words, so every busy word has one
// writer. Runs, not a hash: the pair scan hands its threads runs of words
// too, so a cell tends to stay with the core that scans it.
void WorldTree::apply_moves(std::span<const uint32_t> ids, size_t part, size_t parts) {
  // This part's words: [first, end) (the slots 64 times that).
  const uint64_t words = busy_.size(), first = words * part / parts, end = words * (part + 1) / parts;
  const auto mine = [&](uint32_t slot) { return slot / 64 >= first && slot / 64 < end; };
  for (size_t k = 0; k < ids.size(); ++k) {
    Move& m = moves_[k];
    if (m.kind != MoveKind::fast) continue;
    for (int i = 0; i < m.leaves; ++i)
      if (mine(m.leave[i])) m.emptied[i] = leave_cell(m.leave[i], ids[k]);  // this op's own byte
    for (int i = 0; i < m.enters; ++i)
      if (mine(m.enter[i])) enter_cell(m.enter[i], ids[k]);
  }
}

// The object's own entry: its new cell list, in [lo, hi] order.
void WorldTree::finish_move(uint32_t id, const CellRange& r, const Move& m) {
  Entry& e = entries_[id];
  std::array<uint32_t, kFastCells> old;
  assert(e.cells.size() <= kFastCells);
  std::copy(e.cells.begin(), e.cells.end(), old.begin());
  e.cells.clear();  // capacity kEntryReserve >= kFastCells: no allocation
  size_t j = 0;
  for_each_cell(r.lo, r.hi, [&](const Coord& c) {
    e.cells.push_back(inside(c, e.lo, e.hi) ? old[index_in(c, e.lo, e.hi)] : m.enter[j++]);
  });
  assert(j == m.enters);
  e.lo = r.lo;
  e.hi = r.hi;
  lo_[id] = packed(r.lo);
}

void WorldTree::update_cells(std::span<const uint32_t> ids, std::span<const CellRange> ranges, Parallel& parallel,
                             size_t parts) {
  assert(ids.size() == ranges.size());
  assert(parts >= 1 && std::has_single_bit(parts));
  const size_t n = ids.size();
  const size_t cells_before = table_used_;
  // Sized for every object at once: grows with the world, not with a frame
  // that moves more objects than the frames before.
  if (moves_.size() < n) moves_.resize(std::max(n, entries_.size()));
  // 1. What each object leaves and enters (reads only).
  for_ranges(parallel, n, kMoveGrain, [&](size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) plan_move(ids[k], ranges[k], moves_[k]);
  });
  // 2. In k order: the one-by-one moves, and the cells new to the table
  // (emptied cells stay in it, so every slot found in 1 is still right).
  for (size_t k = 0; k < n; ++k) {
    Move& m = moves_[k];
    if (m.kind == MoveKind::slow) {
      move_one(ids[k], ranges[k]);
      continue;
    }
    if (m.kind != MoveKind::fast) continue;
    ++reinsertions_;
    // In enter order; plan_move kept the missing cells' coordinates, so the
    // entry (a cache miss per move) is not read again.
    for (uint32_t rest = m.missing; rest != 0; rest &= rest - 1) {
      const int i = std::countr_zero(rest);
      m.enter[i] = cell_slot(unpack(m.enter[i]));
    }
  }
  // 3. The cells, in parts of disjoint cells (one part for a batch that
  // steps 1 and 4 run inline: handing out the parts would cost more than the
  // few moves); 4. each object's entry.
  if (n <= kMoveGrain) parts = 1;
  for_ranges(parallel, parts, 1, [&](size_t b, size_t e) {
    for (size_t p = b; p < e; ++p) apply_moves(ids, p, parts);
  });
  for_ranges(parallel, n, kMoveGrain, [&](size_t b, size_t e) {
    for (size_t k = b; k < e; ++k)
      if (moves_[k].kind == MoveKind::fast) finish_move(ids[k], ranges[k], moves_[k]);
  });
  // 5. The cells the moves emptied are freed, unless refilled: the slow
  // moves' (listed in 2), then the fast ones' in k order (the free list, hence
  // later numbering, does not depend on the parts). Not sooner: the slots
  // planned in 1 must stay valid. The free list then serves the next batch's
  // new cells and the cells never outgrow the most ever occupied (a
  // warmed-up frame allocates nothing).
  for (size_t k = 0; k < n; ++k) {
    const Move& m = moves_[k];
    if (m.kind != MoveKind::fast) continue;
    for (int i = 0; i < m.leaves; ++i)
      if (m.emptied[i]) emptied_.push_back(m.leave[i]);
  }
  free_emptied();
  // 6. After a batch that made many cells (a load, a spawn), room for as many
  // again: growing the cells or the table copies or rehashes them all, and
  // left to the next cell made, that fell on the first moving frame after a
  // load (20k objects: that frame 16 ms against 3 ms, `octscene run`).
  if (3 * (table_used_ - std::min(table_used_, cells_before)) >= cells_before && table_used_ > 0) {
    if (cells_.capacity() < 2 * table_used_) cells_.reserve(2 * table_used_);
    if (table_.size() < 4 * table_used_ + 2) table_grow(4 * table_used_ + 2);  // cell_slot keeps it under half full
  }
}

namespace {

// LSD radix sort of pairs by (first, second), 8 bits per pass, skipping the
// passes whose digit is the same in every key (ids < 2^17 need only ~5 of 8).
void radix_sort(std::vector<std::pair<uint32_t, uint32_t>>& v, std::vector<std::pair<uint32_t, uint32_t>>& tmp) {
  const auto key = [](const std::pair<uint32_t, uint32_t>& p) { return (uint64_t(p.first) << 32) | p.second; };
  std::array<std::array<uint32_t, 256>, 8> count{};
  for (const auto& p : v) {
    const uint64_t k = key(p);
    for (int d = 0; d < 8; ++d) ++count[d][(k >> (8 * d)) & 0xFF];
  }
  tmp.resize(v.size());  // scratch kept by the caller: no allocation per frame
  for (int d = 0; d < 8; ++d) {
    auto& c = count[d];
    if (std::find(c.begin(), c.end(), uint32_t(v.size())) != c.end()) continue;  // one bucket: no-op pass
    uint32_t sum = 0;
    for (uint32_t& n : c) sum += std::exchange(n, sum);
    for (const auto& p : v) tmp[c[(key(p) >> (8 * d)) & 0xFF]++] = p;
    v.swap(tmp);
  }
}

}  // namespace

namespace {

// Lane-wise max of two packed cell coordinates (three 16-bit lanes, each
// below 2^10, so signed 16-bit max is right).
uint64_t lane_max(uint64_t a, uint64_t b) {
#if defined(__SSE2__)
  return uint64_t(_mm_cvtsi128_si64(_mm_max_epi16(_mm_cvtsi64_si128(int64_t(a)), _mm_cvtsi64_si128(int64_t(b)))));
#else
  uint64_t m = 0;
  for (int shift = 0; shift < 48; shift += 16) m |= std::max((a >> shift) & 0xFFFF, (b >> shift) & 0xFFFF) << shift;
  return m;
#endif
}

// The pair filter of the scans that know the boxes (scan_part,
// overlapping_pairs): closed world AABBs that overlap. overlaps(), with its
// six compares combined without a branch: whether two boxes that share a
// cell overlap is close to a coin toss, and the mispredicted branches cost
// more than the compares (the scan of 10k objects took ~40% less time). It
// runs only after the first-common-cell test (a branch): evaluating both for
// every pair of a crowded cell made the small bundled scenes' frames ~5%
// slower.
struct BoxesOverlap {
  std::span<const Aabb> boxes;
  bool operator()(uint32_t a, uint32_t b) const {
    const Aabb &x = boxes[a], &y = boxes[b];
    int all = 1;
    for (int k = 0; k < 3; ++k) all &= int(x.min[k] <= y.max[k]) & int(y.min[k] <= x.max[k]);
    return all != 0;
  }
};

// A busy cell with more occupants than this is swept when the pairs are
// filtered by their boxes: occupants sorted by box min x, each tested only
// against those whose x interval starts before its own ends. A crowd in the
// few cells of a shallow world is then O(k log k + pairs), not O(k^2).
constexpr size_t kSweepFrom = 32;

}  // namespace

// Busy bitmap words per scan part: 512 cells, enough work to pay for handing
// a part to another thread.
constexpr size_t kWordsPerPart = 8;

// Bytes of cells, ids and boxes below which the pair scan fetches nothing
// ahead (see scan_cells).
constexpr size_t kCachedWorldBytes = 128 * 1024;

// The busy cells, each pair emitted only by its first common cell, then one
// sort: cheaper than visiting every object's cells in id order. `keep`
// filters pairs before they are stored and sorted.
template <class Keep, class Emit>
void WorldTree::scan_cells(size_t begin, size_t end, Keep keep, Emit emit) const {
  constexpr bool kBoxes = std::is_same_v<Keep, BoxesOverlap>;
  // Each busy cell, its ids and their boxes are cache misses (a frame of
  // 10k moving objects evicts them): they are fetched in two steps ahead of
  // the visit, over a part's busy cells at once. The cell record kAhead
  // cells ahead (its address is known from the bitmap alone), then, when it
  // is in the cache, kAhead / 2 ahead, what its ids name.
  constexpr int kAhead = 8;
  const auto fetch_cell = [&](uint32_t slot) {
    const char* at = reinterpret_cast<const char*>(&cells_[slot]);
    __builtin_prefetch(at);
    __builtin_prefetch(at + sizeof(Cell) - 1);
  };
  const auto fetch_ids = [&](uint32_t slot) {
    const CellIds& ids = cells_[slot].ids;
    if (!ids.in_place()) {
      __builtin_prefetch(ids.data());
      return;
    }
    for (const uint32_t id : ids) {
      __builtin_prefetch(&lo_[id]);
      if constexpr (kBoxes) {
        const char* box = reinterpret_cast<const char*>(&keep.boxes[id]);
        __builtin_prefetch(box);
        __builtin_prefetch(box + sizeof(Aabb) - 1);
      }
    }
  };
  // A world whose cells, ids and boxes fit well inside a core's L2 cache
  // stays there between frames: fetching ahead was only instructions.
  const size_t footprint = cells_.size() * sizeof(Cell) + lo_.size() * (sizeof(uint64_t) + (kBoxes ? sizeof(Aabb) : 0));
  const bool fetch = footprint > kCachedWorldBytes;
  std::array<uint32_t, 64 * kWordsPerPart> slots;
  for (size_t first = begin; first < end; first += kWordsPerPart) {
    int count = 0;
    for (size_t word = first; word < std::min(end, first + kWordsPerPart); ++word)
      for (uint64_t bits = busy_[word]; bits != 0; bits &= bits - 1)
        slots[count++] = uint32_t(64 * word + size_t(std::countr_zero(bits)));
    if (fetch) {
      for (int k = 0; k < std::min(count, kAhead); ++k) fetch_cell(slots[k]);
      for (int k = 0; k < std::min(count, kAhead / 2); ++k) fetch_ids(slots[k]);
    }
    for (int k = 0; k < count; ++k) {
      if (fetch && k + kAhead < count) fetch_cell(slots[k + kAhead]);
      if (fetch && k + kAhead / 2 < count) fetch_ids(slots[k + kAhead / 2]);
      const Cell& cell = cells_[slots[k]];
      const uint32_t* ids = cell.ids.data();
      const size_t n = cell.ids.size();
      const uint64_t at = packed(cell.at);
      if constexpr (kBoxes) {
        if (n > kSweepFrom) {
          // Per thread, kept: a steady frame allocates nothing. Ties in min x
          // are ordered by id; the pairs are sorted afterwards anyway.
          thread_local std::vector<std::pair<double, uint32_t>> by_min_x;
          by_min_x.clear();
          for (size_t i = 0; i < n; ++i) by_min_x.emplace_back(keep.boxes[ids[i]].min.x(), ids[i]);
          std::sort(by_min_x.begin(), by_min_x.end());
          for (size_t i = 0; i + 1 < n; ++i) {
            const uint32_t a = by_min_x[i].second;
            const double max_x = keep.boxes[a].max.x();
            const uint64_t la = lo_[a];
            for (size_t j = i + 1; j < n && by_min_x[j].first <= max_x; ++j) {
              const uint32_t b = by_min_x[j].second;
              if (lane_max(la, lo_[b]) == at && keep(a, b)) emit(std::min(a, b), std::max(a, b));
            }
          }
          continue;
        }
      }
      for (size_t i = 0; i + 1 < n; ++i) {
        const uint32_t a = ids[i];
        const uint64_t la = lo_[a];
        for (size_t j = i + 1; j < n; ++j) {
          const uint32_t b = ids[j];
          // Both are in this cell, so their first common cell, max(la, lb)
          // per axis, is this one iff it equals `at`.
          if (lane_max(la, lo_[b]) == at && keep(a, b)) emit(a, b);
        }
      }
    }
  }
}

template <class Keep>
void WorldTree::finish(std::vector<std::pair<uint32_t, uint32_t>>& out, Keep keep) const {
  // Overflow objects are in no cell, so these never repeat a cell pair.
  std::span<const uint32_t> with_all = overflow_ids_;
  if constexpr (std::is_same_v<Keep, BoxesOverlap>)
    if (uint64_t(overflow_ids_.size()) * present_ > kCoarseFrom)
      with_all = pair_overflow_by_coarse_cells(out, keep.boxes);
  const bool all_overflow = with_all.size() == overflow_ids_.size();
  for (uint32_t a : with_all)
    for (uint32_t b = 0; b < entries_.size(); ++b) {
      // Two of `with_all` once (both are overflow, and it is sorted).
      const Entry& e = entries_[b];
      if (!e.present || b == a ||
          (b < a && e.overflow && (all_overflow || std::binary_search(with_all.begin(), with_all.end(), b))))
        continue;
      const uint32_t lo = std::min(a, b), hi = std::max(a, b);
      if (keep(lo, hi)) out.emplace_back(lo, hi);
    }
  // The radix sort's fixed cost (8 count tables) only pays off on many pairs.
  if (out.size() < kRadixFrom)
    std::sort(out.begin(), out.end());
  else
    radix_sort(out, sort_scratch_);
}

// The overflow objects are listed per coarse cell (2^kCoarseShift cells a
// side), each object over its cell range shifted down: a pair that overlaps
// shares a cell, hence a coarse cell, and is taken in its first common coarse
// cell only (the cell pairs' rule, one level up). An overflow object over
// more than kCoarseMaxCells coarse cells is left to pair with every object,
// and so is every one, nothing done, when listing them would cost more than
// that (very large ones among few objects). Returns those left, sorted.
std::span<const uint32_t> WorldTree::pair_overflow_by_coarse_cells(std::vector<std::pair<uint32_t, uint32_t>>& out,
                                              std::span<const Aabb> boxes) const {
  const auto coarse = [](const Coord& c) {
    return Coord{uint16_t(c[0] >> kCoarseShift), uint16_t(c[1] >> kCoarseShift), uint16_t(c[2] >> kCoarseShift)};
  };
  // Costs in plain pair checks (measured: a listed entry's sort ~16, an
  // object's lookups ~4, a pair sharing a coarse cell ~1), against the one
  // check per (overflow object, object) this replaces. Huge overflow objects
  // that overlap each other can cost more here, so this is checked twice.
  const uint64_t plain = uint64_t(overflow_ids_.size()) * present_;
  const uint64_t lookups = 4 * uint64_t(present_);
  uint64_t listed = 0;
  for (uint32_t a : overflow_ids_)
    if (const uint64_t c = cell_count(coarse(entries_[a].lo), coarse(entries_[a].hi)); c <= kCoarseMaxCells) listed += c;
  if (16 * listed + lookups >= plain) return overflow_ids_;
  const auto emit = [&](uint32_t a, uint32_t b) {
    if (overlaps(boxes[a], boxes[b])) out.emplace_back(std::min(a, b), std::max(a, b));
  };
  std::vector<std::pair<uint64_t, uint32_t>>& index = coarse_scratch_;  // (coarse cell, overflow id), sorted
  std::vector<uint32_t>& everywhere = everywhere_scratch_;             // sorted, as overflow_ids_
  index.clear(), everywhere.clear();
  for (uint32_t a : overflow_ids_) {
    const Coord lo = coarse(entries_[a].lo), hi = coarse(entries_[a].hi);
    if (cell_count(lo, hi) > kCoarseMaxCells) {
      everywhere.push_back(a);
      continue;
    }
    for (uint16_t z = lo[2]; z <= hi[2]; ++z)
      for (uint16_t y = lo[1]; y <= hi[1]; ++y)
        for (uint16_t x = lo[0]; x <= hi[0]; ++x) index.emplace_back(packed(Coord{x, y, z}), a);
  }
  std::sort(index.begin(), index.end());
  uint64_t sharing = 0;  // pairs of entries in one coarse cell
  for (size_t g = 0, end; g < index.size(); g = end) {
    for (end = g + 1; end < index.size() && index[end].first == index[g].first;) ++end;
    sharing += (end - g) * (end - g - 1) / 2;
  }
  if (sharing + lookups >= plain) return overflow_ids_;
  // Indexed overflow objects with each other: per coarse cell, the pairs
  // whose first common coarse cell it is.
  for (size_t g = 0; g < index.size();) {
    size_t end = g;
    while (end < index.size() && index[end].first == index[g].first) ++end;
    for (size_t i = g; i < end; ++i)
      for (size_t j = i + 1; j < end; ++j) {
        const uint32_t a = index[i].second, b = index[j].second;
        if (lane_max(packed(coarse(entries_[a].lo)), packed(coarse(entries_[b].lo))) == index[g].first) emit(a, b);
      }
    g = end;
  }
  // Indexed overflow objects with the objects in cells: each such object
  // looks up its own coarse cells.
  for (uint32_t b = 0; b < entries_.size(); ++b) {
    const Entry& e = entries_[b];
    if (!e.present || e.overflow) continue;
    const Coord lo = coarse(e.lo), hi = coarse(e.hi);
    const uint64_t lb = packed(lo);
    for (uint16_t z = lo[2]; z <= hi[2]; ++z)
      for (uint16_t y = lo[1]; y <= hi[1]; ++y)
        for (uint16_t x = lo[0]; x <= hi[0]; ++x) {
          const uint64_t at = packed(Coord{x, y, z});
          auto it = std::lower_bound(index.begin(), index.end(), std::pair<uint64_t, uint32_t>(at, 0));
          for (; it != index.end() && it->first == at; ++it)
            if (lane_max(packed(coarse(entries_[it->second].lo)), lb) == at) emit(it->second, b);
        }
  }
  return everywhere;
}

void WorldTree::candidate_pairs(std::vector<std::pair<uint32_t, uint32_t>>& out) const {
  const auto all = [](uint32_t, uint32_t) { return true; };
  out.clear();
  scan_cells(0, busy_.size(), all, [&](uint32_t a, uint32_t b) { out.emplace_back(a, b); });
  finish(out, all);
}

void WorldTree::overlapping_pairs(std::span<const Aabb> boxes, std::vector<std::pair<uint32_t, uint32_t>>& out) const {
  assert(boxes.size() >= entries_.size());
  out.clear();
  scan_cells(0, busy_.size(), BoxesOverlap{boxes}, [&](uint32_t a, uint32_t b) { out.emplace_back(a, b); });
  finish(out, BoxesOverlap{boxes});
}

size_t WorldTree::scan_parts() const { return (busy_.size() + kWordsPerPart - 1) / kWordsPerPart; }

void WorldTree::scan_part(size_t part, std::span<const Aabb> boxes, PairSink& sink) const {
  assert(boxes.size() >= entries_.size());
  const size_t begin = std::min(busy_.size(), part * kWordsPerPart);
  // Handed over when full. Left uninitialised: std::pair's constructor
  // zeroed all of it (a rep stos) in every part, a small scene's few pairs or not.
  using Pair = std::pair<uint32_t, uint32_t>;
  constexpr size_t kBlock = 32;
  alignas(Pair) unsigned char storage[kBlock * sizeof(Pair)];
  Pair* const block = std::launder(reinterpret_cast<Pair*>(storage));
  size_t n = 0;
  scan_cells(begin, std::min(busy_.size(), begin + kWordsPerPart), BoxesOverlap{boxes}, [&](uint32_t a, uint32_t b) {
    new (block + n++) Pair(a, b);
    if (n == kBlock) sink.take(std::span(block, n)), n = 0;
  });
  if (n > 0) sink.take(std::span(block, n));
}

void WorldTree::finish_pairs(std::span<const Aabb> boxes, std::vector<std::pair<uint32_t, uint32_t>>& out) const {
  assert(boxes.size() >= entries_.size());
  finish(out, BoxesOverlap{boxes});
}

// ---- queries ----

void WorldTree::query_box(const Aabb& box, std::vector<uint32_t>& out) const {
  assert(!box.min.hasNaN() && !box.max.hasNaN());
  out.clear();
  const Coord qlo = cell_of(box.min), qhi = cell_of(box.max);
  // An object meeting the range is taken in its first common cell with it:
  // max(its lo, qlo) per axis, a cell both hold.
  const auto take = [&](const Cell& cell) {
    for (const uint32_t id : cell.ids) {
      const Coord& lo = entries_[id].lo;
      bool first = true;
      for (int k = 0; k < 3; ++k) first &= cell.at[k] == std::max(lo[k], qlo[k]);
      if (first) out.push_back(id);
    }
  };
  uint64_t range = 1;
  for (int k = 0; k < 3; ++k) range *= uint64_t(qhi[k]) - qlo[k] + 1;
  if (table_used_ == 0) {
    // no cells
  } else if (range <= table_used_) {  // look up the range's cells
    Coord c;
    for (c[2] = qlo[2]; c[2] <= qhi[2]; ++c[2])
      for (c[1] = qlo[1]; c[1] <= qhi[1]; ++c[1])
        for (c[0] = qlo[0]; c[0] <= qhi[0]; ++c[0]) {
          const size_t i = table_find(pack(c));
          if (table_[i] != 0) take(cells_[uint32_t(table_[i])]);
        }
  } else {  // a big range over a sparse world: scan the occupied cells instead
    for (const Cell& cell : cells_)
      if (!cell.ids.empty() && inside(cell.at, qlo, qhi)) take(cell);
  }
  out.insert(out.end(), overflow_ids_.begin(), overflow_ids_.end());
  std::sort(out.begin(), out.end());
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// cell_of's clamp for one grid coordinate.
int clamp_cell(double g, uint32_t side) { return g >= double(side) ? int(side) - 1 : g > 0 ? int(g) : 0; }

}  // namespace

WorldTree::RayWalk::RayWalk(const WorldTree& tree, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                            double t_max)
    : tree_(&tree), t_max_(t_max) {
  const Aabb& w = tree.world_;
  for (int k = 0; k < 3; ++k) {
    const double inv = tree.inv_cell_[k];
    g0_[k] = (origin[k] - w.min[k]) * inv;
    dg_[k] = dir[k] * inv;
    // Rounding in cell_of, in a slab test against a box near the grid and in
    // these event times is a few 1e-16 of the magnitudes below; 1e-12 is
    // thousands of times that, and still a sliver of a cell for a ray from
    // 1e7 away (a wider tube only costs cells, never a miss).
    delta_[k] = 1e-12 * ((std::abs(origin[k]) + std::abs(w.min[k]) + std::abs(w.max[k])) * inv + tree.side_ + 1);
    step_[k] = dg_[k] > 0 ? 1 : dg_[k] < 0 ? -1 : 0;
    lo_[k] = clamp_cell(g0_[k] - delta_[k], tree.side_);
    hi_[k] = clamp_cell(g0_[k] + delta_[k], tree.side_);
    schedule(k);
  }
  // The first box: every cell of the tube at t = 0.
  elo_ = lo_;
  ehi_ = hi_;
  cur_ = elo_;
  enumerating_ = tree.table_used_ > 0;
}

// Only boundaries 1..side-1 change a clamped cell: past the outer ones the
// border cells reach to infinity, so an axis with no boundary left never
// fires again.
void WorldTree::RayWalk::schedule(int k) {
  const int side = int(tree_->side_);
  const double g0 = g0_[k], dg = dg_[k], d = delta_[k];
  t_lead_[k] = t_trail_[k] = kInf;
  if (step_[k] > 0) {
    if (hi_[k] + 1 <= side - 1) t_lead_[k] = std::max(0.0, (hi_[k] + 1 - d - g0) / dg);
    if (lo_[k] + 1 <= side - 1) t_trail_[k] = std::max(0.0, (lo_[k] + 1 + d - g0) / dg);
  } else if (step_[k] < 0) {
    if (lo_[k] >= 1) t_lead_[k] = std::max(0.0, (lo_[k] + d - g0) / dg);
    if (hi_[k] >= 1) t_trail_[k] = std::max(0.0, (hi_[k] - d - g0) / dg);
  }
}

bool WorldTree::RayWalk::next() {
  for (;;) {
    // Report the occupied cells of the box being enumerated.
    while (enumerating_) {
      const Coord c{uint16_t(cur_[0]), uint16_t(cur_[1]), uint16_t(cur_[2])};
      // Advance cur_ over [elo_, ehi_], x fastest.
      int k = 0;
      for (; k < 3; ++k) {
        if (cur_[k] < ehi_[k]) {
          ++cur_[k];
          break;
        }
        cur_[k] = elo_[k];
      }
      if (k == 3) enumerating_ = false;
      const size_t i = tree_->table_find(pack(c));
      if (tree_->table_[i] != 0 && !tree_->cells_[uint32_t(tree_->table_[i])].ids.empty()) {  // skip emptied cells
        at_ = c;
        slot_ = uint32_t(tree_->table_[i]);
        return true;
      }
    }
    // The next event: the earliest edge crossing, leading edges first on ties
    // (a larger tube is the conservative side).
    int axis = -1;
    bool lead = false;
    double t = kInf;
    for (int k = 0; k < 3; ++k)
      if (t_lead_[k] < t) t = t_lead_[k], axis = k, lead = true;
    for (int k = 0; k < 3; ++k)
      if (t_trail_[k] < t) t = t_trail_[k], axis = k, lead = false;
    if (axis < 0 || !(t <= t_max_) || tree_->table_used_ == 0) return false;
    if (!lead) {
      // The trailing edge leaves a cell: the range shrinks. It never passes
      // the lead (which crosses each boundary first); if rounding ever says
      // otherwise, keep the cells and wait for the lead.
      int& edge = step_[axis] > 0 ? lo_[axis] : hi_[axis];
      if (lo_[axis] < hi_[axis]) {
        edge += step_[axis];
        schedule(axis);
      } else {
        t_trail_[axis] = kInf;
      }
      continue;
    }
    // The leading edge enters a new layer of cells: enumerate that slab.
    const int layer = step_[axis] > 0 ? ++hi_[axis] : --lo_[axis];
    schedule(axis);
    entry_ = t;
    elo_ = lo_;
    ehi_ = hi_;
    elo_[axis] = ehi_[axis] = layer;
    cur_ = elo_;
    enumerating_ = true;
  }
}

}  // namespace octbake

#include "octbake/world_tree.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace octbake {

namespace {

void insert_sorted(std::vector<uint32_t>& v, uint32_t id) {
  v.insert(std::lower_bound(v.begin(), v.end(), id), id);
}

void erase_sorted(std::vector<uint32_t>& v, uint32_t id) {
  auto it = std::lower_bound(v.begin(), v.end(), id);
  if (it != v.end() && *it == id) v.erase(it);
}

}  // namespace

WorldTree::WorldTree(const Aabb& world, int depth) : world_(world), depth_(depth), side_(1u << depth) {
  assert(depth >= 0 && depth <= 10);  // packed cell keys use 10 bits per axis
  assert((world.max.array() > world.min.array()).all());
  inv_cell_ = Eigen::Vector3d::Constant(double(side_)).cwiseQuotient(world.max - world.min);
}

// Monotone in p on every axis (subtraction and multiplication by a positive
// constant round monotonically, and clamping keeps order), so two boxes
// overlapping on an axis always share a cell on it, inside the world or not:
// the broadphase never misses a pair.
WorldTree::Coord WorldTree::cell_of(const Eigen::Vector3d& p) const {
  Coord c;
  for (int k = 0; k < 3; ++k) {
    const double t = (p[k] - world_.min[k]) * inv_cell_[k];
    c[k] = t >= double(side_) ? uint16_t(side_ - 1) : t > 0 ? uint16_t(t) : uint16_t(0);
  }
  return c;
}

uint32_t WorldTree::cell_slot(uint32_t x, uint32_t y, uint32_t z) {
  const uint32_t key = x | (y << 10) | (z << 20);
  auto [it, inserted] = cell_index_.try_emplace(key, 0);
  if (inserted) {
    if (free_cells_.empty()) {
      it->second = uint32_t(cells_.size());
      cells_.emplace_back();
    } else {
      it->second = free_cells_.back();
      free_cells_.pop_back();
    }
    cells_[it->second].at = {uint16_t(x), uint16_t(y), uint16_t(z)};
  }
  return it->second;
}

void WorldTree::link(uint32_t id) {
  Entry& e = entries_[id];
  lo_[id] = e.lo;
  if (e.overflow) {
    insert_sorted(overflow_ids_, id);
    return;
  }
  for (uint32_t z = e.lo[2]; z <= e.hi[2]; ++z)
    for (uint32_t y = e.lo[1]; y <= e.hi[1]; ++y)
      for (uint32_t x = e.lo[0]; x <= e.hi[0]; ++x) {
        const uint32_t slot = cell_slot(x, y, z);
        insert_sorted(cells_[slot].ids, id);
        e.cells.push_back(slot);
      }
}

void WorldTree::unlink(uint32_t id) {
  Entry& e = entries_[id];
  if (e.overflow) erase_sorted(overflow_ids_, id);
  for (uint32_t slot : e.cells) {
    Cell& cell = cells_[slot];
    erase_sorted(cell.ids, id);
    if (cell.ids.empty()) {
      // Free the cell so a long run over a deep world does not accumulate them.
      cell_index_.erase(uint32_t(cell.at[0]) | (uint32_t(cell.at[1]) << 10) | (uint32_t(cell.at[2]) << 20));
      free_cells_.push_back(slot);
    }
  }
  e.cells.clear();
}

bool WorldTree::update(uint32_t id, const Aabb& box) {
  assert(!box.min.hasNaN() && !box.max.hasNaN());
  if (id >= entries_.size()) {
    entries_.resize(id + 1);
    lo_.resize(id + 1);
  }
  const Coord lo = cell_of(box.min), hi = cell_of(box.max);
  uint64_t count = 1;
  for (int k = 0; k < 3; ++k) count *= uint64_t(hi[k]) - lo[k] + 1;
  const bool overflow = count > kMaxCells;

  Entry& e = entries_[id];
  if (e.present) {
    if (e.lo == lo && e.hi == hi && e.overflow == overflow) return false;
    unlink(id);
    ++reinsertions_;
  } else {
    e.present = true;
    insert_sorted(present_ids_, id);
  }
  e.lo = lo;
  e.hi = hi;
  e.overflow = overflow;
  link(id);
  return true;
}

void WorldTree::remove(uint32_t id) {
  if (!contains(id)) return;
  unlink(id);
  entries_[id].present = false;
  entries_[id].overflow = false;
  erase_sorted(present_ids_, id);
}

void WorldTree::candidate_pairs(std::vector<std::pair<uint32_t, uint32_t>>& out) const {
  out.clear();
  for (size_t n = 0; n < present_ids_.size(); ++n) {
    const uint32_t a = present_ids_[n];
    const Entry& ea = entries_[a];
    if (ea.overflow) {
      for (size_t m = n + 1; m < present_ids_.size(); ++m) out.emplace_back(a, present_ids_[m]);
      continue;
    }
    const size_t first = out.size();
    const Coord la = ea.lo;
    for (uint32_t slot : ea.cells) {
      const Cell& cell = cells_[slot];
      // The first common cell of a and b is max(la, lb) per axis; since both
      // are in this cell, it is this cell iff on each axis one of them starts here.
      const bool ax = cell.at[0] == la[0], ay = cell.at[1] == la[1], az = cell.at[2] == la[2];
      auto it = std::upper_bound(cell.ids.begin(), cell.ids.end(), a);
      for (; it != cell.ids.end(); ++it) {
        const uint32_t b = *it;
        const Coord& lb = lo_[b];
        if ((ax || cell.at[0] == lb[0]) && (ay || cell.at[1] == lb[1]) && (az || cell.at[2] == lb[2]))
          out.emplace_back(a, b);
      }
    }
    // Overflow objects are in no cell, so these never repeat a cell pair.
    for (auto it = std::upper_bound(overflow_ids_.begin(), overflow_ids_.end(), a); it != overflow_ids_.end(); ++it)
      out.emplace_back(a, *it);
    std::sort(out.begin() + first, out.end());
  }
}

}  // namespace octbake

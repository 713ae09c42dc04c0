// ObjectTree construction: occupancy (surface / solid / vertices) built top
// down, each triangle handed only to the children it overlaps, so the cost
// follows the occupied boxes rather than 8^depth.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>

#include "import.h"
#include "octbake/octree.h"

namespace octbake {

// A count of threads that may still be started, shared by every job of one
// run (files baked in parallel, and the subtrees of one large file), so that
// together they never run more than the budget. A thread that works holds a
// slot; it returns the slot when it has nothing left to do, so a build still
// running can take it. Thread safe.
class ThreadBudget {
 public:
  // `slots` >= 0 threads may be started.
  explicit ThreadBudget(int slots) : free_(slots) {}
  ThreadBudget(const ThreadBudget&) = delete;
  ThreadBudget& operator=(const ThreadBudget&) = delete;

  // Takes a slot when one is free; never blocks.
  bool try_acquire() {
    for (int f = free_.load(); f > 0;)
      if (free_.compare_exchange_weak(f, f - 1)) return true;
    return false;
  }
  // Gives back a slot taken by try_acquire.
  void release() { free_.fetch_add(1); }
  int free() const { return free_.load(); }

 private:
  std::atomic<int> free_;
};

// How build_tree may use threads and report how far it is.
struct BuildControl {
  // Helper threads are started only with slots taken from here (null: the
  // calling thread alone). The calling thread is not counted: it is assumed
  // to hold a slot of its own already.
  ThreadBudget* threads = nullptr;
  // Called with work done and total work (arbitrary units: done / total is
  // the fraction finished): once with done 0 when the total is known, then
  // after each finished part, the last call with done == total. Calls come
  // from the building threads but never overlap, and done never decreases.
  std::function<void(uint64_t done, uint64_t total)> progress;
};

// Root = the mesh's axis-aligned bounds over all positions (an axis may have
// zero thickness: its boxes stay flat). depth in 1..12 (asserted); the mesh
// must have at least one position.
//
// Modes (docs/interface.md section 2):
//  - surface: a box is occupied when a triangle overlaps the closed box grown
//    by occupancy_pad(bounds) (exact separating-axis test, degenerate
//    triangles included);
//  - solid: surface plus the interior enclosed by it. Empty space is flood
//    filled from outside the grid through 6-connected empty boxes of depth
//    min(depth, 8); boxes deeper than 8 are interior when their depth-8
//    ancestor is wholly interior (interior space sharing a depth-8 box with
//    the surface is left to the surface boxes). An open mesh whose holes are
//    wider than a fill box gives the same tree as surface;
//  - vertices: the thesis's rule, a box is occupied when it holds a vertex.
//    Boxes are closed (grown by the same pad), so a vertex on a face, edge or
//    corner shared by boxes occupies all of them.
// Deterministic: the same mesh gives the same masks, whatever the threads.
// The levels below the top few are built per subtree, in parallel as far as
// `control.threads` allows, and joined in Morton order. Throws what the
// allocator throws (std::bad_alloc) after every thread has stopped.
OctreeMasks build_tree(const Mesh& mesh, int depth, Occupancy mode, const BuildControl& control = {});

// The margin build_tree grows every box by so rounding never drops a touched
// box: 1e-9 of the largest extent plus a few ulp of the largest coordinate.
double occupancy_pad(const Aabb& bounds);

// The flood-fill depth cap of solid mode.
constexpr int kSolidFillDepth = 8;

}  // namespace octbake

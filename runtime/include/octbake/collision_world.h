// CollisionWorld: the app-driven collision world. The app owns the motion: it
// creates and destroys objects at any time, sets every object's pose and the
// camera whenever it likes (typically every frame), and calls detect() to get
// this frame's contacts. The world never moves anything: no response, no
// integration (World, in world.h, is the built-in simulation on top of it).
//
// A frame, as an engine uses it:
//
//   CollisionWorld world(settings);
//   ObjectHandle h = world.create(TreeSource::fixed(&tree), pose).value();
//   for (;;) {
//     world.set_camera(camera);               // every frame
//     world.set_pose(h, pose_of_my_entity);   // for every object that moved
//     world.detect(contacts);                 // LOD + broadphase + pair tests
//     for (const Contact& c : contacts) respond(c.a, c.b, c.estimate);
//     world.ray_cast(eye, dir, 100.0);        // queries see the same depths
//   }
//
// Determinism: with the same sequence of calls every result (contacts, depths,
// counts, query answers) is bit-identical across runs and thread counts.
//
// Errors: a call with a destroyed handle (stale generation), a handle of
// another CollisionWorld or a never-created slot, or bad numbers (non-finite
// pose, scale <= 0, non-unit quaternion) returns a typed Error
// (ErrorCode::invalid_argument, message naming the reason) and changes
// nothing. No call has undefined behaviour on bad input.
#pragma once
#include <cstddef>
#include <cassert>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <variant>
#include <vector>

#include "octbake/export.h"
#include "octbake/collide.h"
#include "octbake/lod.h"
#include "octbake/object_tree.h"
#include "octbake/pose.h"
#include "octbake/result.h"
#include "octbake/world_tree.h"

namespace octbake {

class LevelCache;        // octbake/level_cache.h: streamed trees
using TreeId = uint32_t;  // a tree inside a LevelCache

// Success or a typed Error.
using Status = Result<std::monostate>;

// Names one object of one CollisionWorld. A handle stays valid until its
// object is destroyed; the slot is then reused with a new generation, so an
// old handle is refused instead of naming the new object. generation 0 is
// never issued: a default-constructed handle is always invalid.
struct ObjectHandle {
  uint32_t slot = 0;
  uint32_t generation = 0;
  uint32_t world = 0;  // id of the issuing CollisionWorld (foreign handles are refused)
  bool operator==(const ObjectHandle&) const = default;
};

// Where an object's ObjectTree comes from.
//  fixed(tree): a decoded tree the app keeps alive while any object uses it;
//    its usable depth is tree->loaded_depth().
//  streamed(cache, id): a tree of a LevelCache; levels deeper than held are
//    decoded on demand by detect() up to the baked depth, within the cache's
//    memory budget (see detect()).
struct TreeSource {
  const ObjectTree* tree = nullptr;
  LevelCache* cache = nullptr;
  TreeId id = 0;
  static TreeSource fixed(const ObjectTree* t) { return {t, nullptr, 0}; }
  static TreeSource streamed(LevelCache* c, TreeId i) { return {nullptr, c, i}; }
};

// ---- the executor seam (parallel narrow phase) ----

// A range job: run(ctx, begin, end) handles items [begin, end). Plain function
// pointer + context, so handing work to an executor never allocates.
struct RangeTask {
  void (*run)(const void* ctx, size_t begin, size_t end) = nullptr;
  const void* ctx = nullptr;
  void operator()(size_t begin, size_t end) const { run(ctx, begin, end); }
};

// A RangeTask running f(begin, end); f must outlive the call.
template <class F>
RangeTask range_task(const F& f) {
  return {[](const void* ctx, size_t b, size_t e) { (*static_cast<const F*>(ctx))(b, e); }, &f};
}

// The app's job system. parallel_for must call task on disjoint ranges that
// together cover [0, count) exactly once, each range at least `grain` items
// (except possibly the last), in any order, on any threads, and return only
// when all are done. Items are independent and write to separate slots, so
// results do not depend on how the ranges are split or scheduled.
class OCTBAKE_API Executor {
 public:
  virtual ~Executor() = default;
  virtual void parallel_for(size_t count, size_t grain, RangeTask task) = 0;
};

// The cores the calling thread may run on, at least 1: on Linux its CPU
// affinity (the process's, from taskset or a container's cpuset, unless the
// app pinned the thread; threads it starts inherit it), which
// hardware_concurrency() ignores; elsewhere hardware_concurrency(). The
// default thread count of octscene and octbake, and what a ThreadPool
// compares its threads with when it starts them.
OCTBAKE_API int usable_cores();

// The built-in executor: `threads - 1` worker threads plus the caller. Used by
// CollisionWorld when settings.threads > 1 and no executor is given. Workers
// spin briefly, then sleep between jobs; parallel_for does not allocate.
class OCTBAKE_API ThreadPool final : public Executor {
 public:
  explicit ThreadPool(int threads);
  ~ThreadPool() override;
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;
  void parallel_for(size_t count, size_t grain, RangeTask task) override;
  int threads() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// ---- settings and results ----

// When pixel areas (hence depths) are recomputed.
enum class AreaRefresh {
  // Default. An object's area is recomputed when it is needed (it is in a
  // candidate pair whose root boxes are not apart, see detect(); a query
  // reaches it; depth() or area() asks) and its pose, the camera or the LOD
  // settings changed since it was last computed. With the fixed and screen
  // policies only those objects are computed, and screen skips the
  // exact area when pixel_area_lower_bound already gives the deepest depth,
  // or pixel_area_upper_bound the same depth as the lower bound (not
  // counted in area_computations); thesis needs every
  // area (its A_min and A_max are global): when anything changed, every live
  // object's area is recomputed, O(objects) per frame.
  on_demand,
  // The simulation layer's historic modes (World): areas of every object
  // whose WorldTree cell set changed (resp. every object), recomputed at the
  // start of detect(), whether or not it is in a pair.
  on_cell_change,
  every_frame,
};

struct CollisionSettings {
  Aabb bounds{{-100, -100, -100}, {100, 100, 100}};  // the WorldTree's box; objects may leave it
  int world_depth = 4;                               // WorldTree cells per axis = 2^world_depth (0..10)
  LodSettings lod;
  Camera camera;
  AreaRefresh area_refresh = AreaRefresh::on_demand;
  // detect() and set_poses() run their parallel parts (pose moves, the
  // WorldTree's cell checks and pair scan, depths, pair tests) on `executor`
  // when given, else on a built-in ThreadPool of `threads` threads when
  // threads > 1, else inline. Results are bit-identical for every choice.
  int threads = 1;
  Executor* executor = nullptr;  // not owned; must outlive the world
  // Temporal coherence: each candidate pair first tries the leaf pair that
  // proved its contact last frame (collide() with a PairCache), and a pair
  // tested last frame on the same trees, poses (bit for bit) and depths as
  // now is not tested again: its result is last frame's, with 0 box tests
  // (the static scenery of a scene). A pair that missed, whose objects
  // since only translated (trees, depths, rotations and scales the same), is
  // not tested while they moved apart or together by less than the
  // separation collide() gave it (DetectStats::pairs_kept_apart). Same
  // contacts either way; only box-test counts differ (fewer on coherent
  // motion), and they stay deterministic.
  bool coherence = true;
};

// What an app can respond with, from the leaf pair that proved the contact.
struct ContactEstimate {
  OrientedBox leaf_a, leaf_b;  // the overlapping leaf boxes, in world space
  Aabb overlap;                // intersection of their world AABBs
  // Separating-axis estimate between the two leaf boxes: the axis (of the 15
  // box-box axes) with the least penetration, pointing from a towards b, and
  // the penetration along it (>= 0). Moving b by normal * penetration (or a
  // by the opposite) separates these two leaves.
  Eigen::Vector3d normal{1, 0, 0};
  double penetration = 0;
};

struct Contact {
  ObjectHandle a, b;  // a.slot < b.slot
  int depth_a = 0, depth_b = 0;  // depths the pair was tested at
  uint64_t box_tests = 0;
  ContactEstimate estimate;
};

struct DetectStats {
  uint64_t objects = 0;            // live objects
  uint64_t candidate_pairs = 0;    // WorldTree pairs whose world AABBs overlap
  uint64_t pair_tests = 0;         // candidate pairs tested with ObjectTrees (== candidate_pairs)
  uint64_t box_tests = 0;
  uint64_t contacts = 0;
  uint64_t area_computations = 0;  // pixel areas computed this frame
  uint64_t depth_clamps = 0;       // streamed objects tested shallower than asked (memory budget)
  // Streamed trees whose LevelCache::require failed this frame (a damaged
  // level that does not decode): one per failing require. Their objects are
  // tested at the depth still held (conservative, as for depth_clamps); the
  // error itself is CollisionWorld::last_stream_error().
  uint64_t stream_errors = 0;
  // Pairs answered by last frame's result (see CollisionSettings::coherence):
  // counted in pair_tests, with 0 box tests.
  uint64_t pairs_reused = 0;
  // Misses answered by collide()'s separation (CollisionSettings::coherence):
  // the pair's objects only translated since its last test, by less than
  // the separation it gave. Counted in pair_tests (not in pairs_reused),
  // with 0 box tests.
  uint64_t pairs_kept_apart = 0;
};

struct RayHit {
  ObjectHandle object;
  double distance = 0;  // along the normalized direction, from the origin
  int depth = 0;        // depth the object was tested at
  BoxCoord box;         // the leaf box hit, at that depth
};

class OCTBAKE_API CollisionWorld {
 public:
  // The lenient form: settings.world_depth is clamped into 0..10; bounds
  // without a finite positive extent on every axis are replaced by the
  // default box; threads < 1 run inline. Prefer make(), which refuses them.
  explicit CollisionWorld(CollisionSettings settings);
  // The strict form: validate(settings), then the world.
  static Result<std::unique_ptr<CollisionWorld>> make(CollisionSettings settings);
  // Refuses (ErrorCode::invalid_argument, the message naming the setting):
  // bounds not finite or without a positive extent on some axis, world_depth
  // outside 0..10, threads < 1, and LodSettings set_lod() refuses.
  static Status validate(const CollisionSettings& settings);
  ~CollisionWorld();
  CollisionWorld(const CollisionWorld&) = delete;
  CollisionWorld& operator=(const CollisionWorld&) = delete;

  // ---- objects ----
  // A new object at `pose`. Errors: null tree, bad pose, streamed source
  // without a cache. The tree must outlive the object and not change while
  // the object lives (the world keeps its bounds, and with coherence the
  // pair results tested on it).
  Result<ObjectHandle> create(TreeSource tree, const Pose& pose);
  Status destroy(ObjectHandle h);
  bool alive(ObjectHandle h) const;
  size_t size() const { return live_; }
  // Position, unit quaternion (|q| within 1e-6 of 1; stored as given, placed
  // as q / |q|), uniform scale > 0. Cheap when only the position changed, and
  // a no-op when nothing changed (bitwise): an app may set every pose every
  // frame.
  Status set_pose(ObjectHandle h, const Pose& pose);
  // set_pose(handles[k], poses[k]) for every k, all or nothing, on the
  // world's threads (settings.executor or settings.threads) when the batch is
  // large: the form for an engine that moves many objects a frame. Refused,
  // changing nothing, when the spans differ in length, an object appears
  // twice, or any item would be refused by set_pose; the error names the
  // first such item (ErrorCode::invalid_argument). Handles in ascending
  // slot order (as create() hands them out, without destroys) skip the pass
  // that looks for an object named twice. The objects it moves into other
  // WorldTree cells are moved there as it goes (one thread updates the tree
  // block by block while the others move the next blocks), as commit_poses()
  // would. Allocates only to grow its scratch with the world.
  Status set_poses(std::span<const ObjectHandle> handles, std::span<const Pose> poses);
  Result<Pose> pose(ObjectHandle h) const;

  // ---- view and LOD ----
  // Takes effect at the next detect() or query. Setting the same camera (all
  // fields equal) again does not invalidate any area.
  void set_camera(const Camera& camera);
  const Camera& camera() const { return settings_.camera; }
  // Errors: min_depth < 0 or max_depth < min_depth.
  Status set_lod(const LodSettings& lod);
  const LodSettings& lod() const { return settings_.lod; }

  // ---- a frame ----
  // Replaces `out` with this frame's contacts, sorted by (a.slot, b.slot):
  //  1. the WorldTree follows the poses set since the last detect();
  //  2. candidate pairs: objects sharing a WorldTree cell whose world AABBs
  //     (padded by 1e-9 relative, never rejecting a touching pair) overlap;
  //     a pair with no cached leaf pair whose root boxes are apart
  //     (roots_apart) is a miss after one box test, as collide() would find
  //     at any depths, and needs neither depth nor streamed level;
  //  3. depths: the pixel area of every object in another candidate pair (see
  //     AreaRefresh) and choose_depths, each object's max depth being its
  //     tree's loaded (fixed) or baked (streamed) depth;
  //  4. streamed trees: LevelCache::require for every streamed tree used this
  //     frame, in ascending TreeId order, then each object's depth is clamped
  //     to its tree's held depth (counted in depth_clamps);
  //  5. collide() on every candidate pair (in parallel per the settings), hits
  //     merged in pair order with their ContactEstimate.
  // Steady state (no new objects, same number of pairs or fewer) allocates
  // nothing.
  DetectStats detect(std::vector<Contact>& out);
  // The error of the last failing LevelCache::require in detect() (names the
  // file, tree and reason), kept until a later failure replaces it; nullopt
  // while none failed. Counted per frame in DetectStats::stream_errors. A
  // frame without failures allocates nothing for it.
  const std::optional<Error>& last_stream_error() const { return last_stream_error_; }

  // Moves the WorldTree to the poses set so far (detect() starts with it).
  // Optional: lets the simulation layer (or an app) see world_tree() follow
  // the poses right away.
  void commit_poses();

  // The depth object h is tested at in the current state (computed on demand
  // as detect() would; for thesis, from every object's current area).
  Result<int> depth(ObjectHandle h);
  // The pixel area behind depth(h).
  Result<double> area(ObjectHandle h);

  // ---- queries (current poses and depths; no detect() needed) ----
  // Nearest hit of the ray origin + t * direction/|direction|, t in
  // [0, max_distance], among every object's leaf boxes at its current depth.
  // Conservative: a ray through an occupied leaf box (padded by 1e-9
  // relative) hits; the distance is that box's entry distance (0 when the
  // origin is inside); ties go to the smallest slot. nullopt when nothing is
  // hit. Errors: non-finite input, zero direction, max_distance < 0.
  // Cost: the WorldTree cells along the ray up to the nearest hit (a DDA that
  // also walks the border cells for rays outside the world box), the objects
  // in them, the overflow objects and the objects moved since the last
  // detect()/commit_poses(); not O(objects). Only objects whose world AABB
  // the ray meets get their depth refreshed and their tree searched.
  Result<std::optional<RayHit>> ray_cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                         double max_distance);
  // Replaces `out` with every object, ascending slot, with a leaf box at its
  // current depth overlapping the world box (resp. the sphere). Conservative
  // as above. Errors: non-finite input, min > max, radius < 0.
  // Cost: the WorldTree cells the box (the sphere's bounding box) covers, or
  // the occupied cells when fewer, their objects, the overflow objects and
  // the objects moved since the last detect()/commit_poses(); then a leaf
  // search of each object whose world AABB overlaps.
  Status overlap_box(const Aabb& box, std::vector<ObjectHandle>& out);
  Status overlap_sphere(const Eigen::Vector3d& center, double radius, std::vector<ObjectHandle>& out);
  // The same queries by a scan over every object (the implementation before
  // the WorldTree was used, O(objects)): the reference the tests and
  // benchmarks compare with. Same results (ray_cast_scan keeps its historic
  // slot-order pruning, which can differ only when two distances agree to
  // within rounding).
  Result<std::optional<RayHit>> ray_cast_scan(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                              double max_distance);
  Status overlap_box_scan(const Aabb& box, std::vector<ObjectHandle>& out);
  Status overlap_sphere_scan(const Eigen::Vector3d& center, double radius, std::vector<ObjectHandle>& out);

  // ---- for the simulation layer and tools ----
  // The pair scan runs inline below this many objects: it costs ~12-16 ns
  // per object (1,000 to 10,000 objects), so a smaller scan is under ~60 µs
  // and handing out its parts costs more than it saves (measured: a
  // 1,000-object scene's scan, 23 parts, 12 µs inline, 14-25 µs on two
  // threads).
  static constexpr size_t kParallelScanObjects = 4096;
  const WorldTree& world_tree() const { return tree_; }
  const CollisionSettings& settings() const { return settings_; }
  // The world AABB (padded) detect() pre-filters with; as of the last
  // set_pose. Precondition: alive(h) (asserted; a dead handle gives an empty
  // box in release builds, never an out-of-range read).
  const Aabb& bounds(ObjectHandle h) const {
    static const Aabb kNone{};
    assert(alive(h));
    return alive(h) ? boxes_[h.slot] : kNone;
  }
  // Depth and area as last computed (no refresh). The area is NaN when the
  // screen policy decided the depth from a lower bound (area() computes it).
  // Precondition: alive(h) (asserted; 0 in release builds for a dead handle).
  int cached_depth(ObjectHandle h) const {
    assert(alive(h));
    return alive(h) ? slots_[h.slot].depth : 0;
  }
  double cached_area(ObjectHandle h) const {
    assert(alive(h));
    return alive(h) ? slots_[h.slot].area : 0.0;
  }
  // The handle living in `slot`, if any.
  std::optional<ObjectHandle> handle_at(uint32_t slot) const;
  // Memory held for pair tests: the records of what each candidate pair was
  // tested on and its contact estimate, 560 bytes each. detect() keeps one
  // per pair whose roots are not apart and reuses those of pairs gone, so
  // this never exceeds the most pair tests two consecutive frames had.
  size_t pair_records() const { return records_.size(); }

 private:
  friend class World;  // runs its per-object motion with run_parallel

  // Hot first: set_pose reads the flags and the pose.
  struct alignas(64) Slot {
    uint32_t generation = 0;  // the last issued: its object's while live (see live_generation_)
    bool tree_dirty = false;  // WorldTree entry stale: its cells are not those of `box`
    bool listed = false;      // in dirty_ (also after a destroy, until the next commit)
    int depth = 0;
    Pose pose;
    Aabb offset;  // world AABB of the tree at (rotation, scale), relative to the position
    double offset_reach = 0;  // largest |coordinate| of offset: place_box's padding, kept with it
    uint64_t area_epoch = 0;  // == epoch_: area/depth match the current pose, camera and LOD
    double area = 0;
    TreeSource source;
  };

  Status check(ObjectHandle h) const;
  // check(h) passes (inline: a handle check per set_pose).
  bool valid(ObjectHandle h) const {
    return h.world == id_ && h.slot < live_generation_.size() && h.generation != 0 &&
           live_generation_[h.slot] == h.generation;
  }
  bool live(uint32_t slot) const { return live_generation_[slot] != 0; }
  const ObjectTree& tree_of(const Slot& s) const;
  int max_depth_of(const Slot& s) const;
  void place_box(uint32_t slot);  // boxes_[slot] from the slot's pose and offset
  OrientedBox root_box(uint32_t slot) const;  // place(tree bounds, pose), from roots_
  void set_offset(uint32_t i);    // roots_[i], offset and offset_reach from slot i's tree, rotation and scale
  // Sets live slot i to a checked pose that differs from its own; true when
  // it is not listed in dirty_ and its WorldTree cells change (set_pose then
  // lists it, set_poses commits it).
  bool move_to(uint32_t i, const Pose& pose, bool same_frame);  // same_frame: rotation and scale unchanged
  void commit_moves(std::span<const uint32_t> slots, std::span<const WorldTree::CellRange> cells);
  Status first_pose_error(std::span<const ObjectHandle> handles, std::span<const Pose> poses) const;
  void invalidate_all_areas();
  // Makes the area and depth of slot i current; returns areas computed.
  uint64_t refresh_depth(uint32_t i);
  uint64_t refresh_all_thesis();
  template <class Stale, class Computed>
  uint64_t compute_areas(Stale stale, Computed computed, double* range);  // see the definition
  void set_depths_from(const double (&range)[2]);
  int depth_in_range(const Slot& s, double a_min, double a_max) const;  // depth_for, clamped to the tree
  uint64_t refresh_legacy(bool all);
  PlacedTree placed(uint32_t i) const;
  void run_parallel(size_t count, size_t grain, RangeTask task);
  bool has_threads() const { return settings_.executor != nullptr || pool_ != nullptr; }  // else run_parallel is a loop
  void collect_pairs();  // pairs_: the WorldTree's overlapping pairs, sorted
  void find_apart(size_t begin, size_t end);  // results_[k].apart
  void assign_records();  // results_[k].record
  void test_pairs(size_t begin, size_t end);
  // Queries: the nearest leaf of slot i entered within `limit` past t_box
  // (local distance and box); does slot i have a leaf overlapping the box
  // (sphere)? Depths must be current.
  bool ray_leaves(uint32_t i, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_box, double limit,
                  double& local, BoxCoord& box) const;
  bool box_leaves(uint32_t i, const Aabb& box) const;
  bool sphere_leaves(uint32_t i, const Eigen::Vector3d& center, double radius) const;
  // query_ids_: the slots whose world AABB may overlap `box`, ascending, once:
  // the WorldTree's answer for committed objects, plus the moved ones.
  void query_candidates(const Aabb& box);
  // Appends to `out` every live slot of `ids` whose world AABB meets `bounds`
  // and for which leaves(slot) holds at its current depth.
  template <class Ids, class Leaves>
  void keep_overlapping(const Ids& ids, const Aabb& bounds, Leaves leaves, std::vector<ObjectHandle>& out);

  CollisionSettings settings_;
  CameraView view_;  // settings_.camera prepared for pixel_area
  uint32_t id_;
  WorldTree tree_;
  std::vector<Slot> slots_;
  // Per slot: its live object's generation, 0 when it has none. Apart from
  // the slots so that handle checks (set_poses checks every item first)
  // read 4 bytes an object, not a slot's cache line (one thread, 10k
  // objects: 505 -> 461 us a frame).
  std::vector<uint32_t> live_generation_;
  std::vector<Aabb> boxes_;  // per slot: world AABB (offset + position, padded); hot in the pair loop
  std::vector<PlacedRoot> roots_;  // per slot: the root box less the position (roots_apart)
  std::vector<uint32_t> free_slots_;  // reused LIFO
  std::vector<uint32_t> dirty_;       // slots whose WorldTree entry is stale, each once
  size_t live_ = 0;
  uint64_t epoch_ = 1;                // bumped by set_camera / set_lod
  bool any_stale_area_ = true;        // thesis: some live area is not fresh
  bool legacy_all_ = false;           // legacy modes: recompute every area
  std::vector<uint8_t> cell_changed_;  // on_cell_change: per slot

  // Per frame scratch, kept to avoid allocations.
  std::vector<std::pair<uint32_t, uint32_t>> pairs_;
  // Per candidate pair, what every pass of detect() reads. What was tested
  // and the contact estimate are in the pair's TestRecord, which it keeps
  // from frame to frame while it stays a candidate and is not apart: a
  // reused result copies nothing (BM_Resting, 10k objects, fixed LOD: 1.53
  // -> 1.33 ms a frame against one 656-byte result per pair, double
  // buffered).
  static constexpr uint32_t kNone = UINT32_MAX;
  struct PairResult {
    PairTest test;
    uint32_t last = kNone;    // coherence: index of the pair in last_results_, if it was tested (not apart)
    uint32_t record = kNone;  // its TestRecord in records_ (not apart)
    bool apart = false;  // roots_apart, and last frame no hit: test is one box test, a miss
    bool reused = false;  // test and estimate are last's, with 0 box tests
    bool kept_apart = false;  // a miss by the separation of the pair's last test, with 0 box tests
  };
  struct TestRecord {  // read and written only for the pair that holds it
    PlacedTree a, b;  // the placements last tested
    ContactEstimate estimate;  // with that test's hit
    // After a miss tested with collide()'s separation: how far b may move
    // relative to a (world units) with the same trees, depths, rotations and
    // scales and the answer still a miss; else 0.
    double separation = 0;
    // Tests left before the separation is asked for again, and the last such
    // wait (see test_pairs).
    uint8_t separation_rest = 0, separation_wait = 0;
  };
  std::vector<std::pair<uint32_t, uint32_t>> pair_room_, spilled_pairs_;  // collect_pairs: the scan's room, overflow
  std::vector<uint32_t> stale_;  // objects in pairs whose depth is stale
  std::vector<uint64_t> stale_bits_;  // detect()'s marks for stale_: a bit per slot, all clear between frames
  // commit_poses scratch: per dirty_ entry, whether its cells change.
  enum : uint8_t { kUnmoved, kMoved };
  std::vector<uint8_t> move_flags_;
  // set_poses: per block of items, kBlockNotMoved, kBlockTaken while a
  // thread moves it, then how many of its objects change cells; those objects
  // and their cells, at the block's items' offset.
  static constexpr uint32_t kBlockNotMoved = UINT32_MAX, kBlockTaken = UINT32_MAX - 1;
  std::vector<uint32_t> block_moves_;
  std::vector<uint32_t> move_slots_;
  std::vector<WorldTree::CellRange> move_cells_;
  std::vector<WorldTree::CellRange> ranges_;  // commit_poses: per dirty_ entry
  std::vector<uint32_t> claim_;  // set_poses: per slot, the item that claimed it (duplicate check)
  std::vector<PairResult> results_;
  // Temporal coherence: last frame's pairs (sorted) and their results,
  // swapped with this frame's at the end of detect(). A hit's leaf pair is
  // tried first: only an occupied leaf pair that still overlaps counts, so a
  // stale one (a slot reused, a depth changed) costs one box test and is
  // never a false hit. The whole result is reused only while both objects'
  // trees, poses (bit for bit) and depths are those tested, or, after a miss,
  // while their trees, depths, rotations and scales are and they have moved
  // apart or together by less than its separation (TestRecord).
  std::vector<std::pair<uint32_t, uint32_t>> last_pairs_;
  std::vector<PairResult> last_results_;
  std::vector<TestRecord> records_;     // of the pairs in results_ (and last_results_ until assign_records)
  std::vector<uint32_t> free_records_;  // records_ no pair holds
  std::vector<uint32_t> streamed_;  // scratch for the require phase
  std::vector<double> areas_scratch_;
  std::vector<int> max_scratch_, depth_scratch_;
  std::unique_ptr<ThreadPool> pool_;
  std::optional<Error> last_stream_error_;
  // Query scratch: candidate slots, and per-slot visit stamps (ray_cast).
  std::vector<uint32_t> query_ids_;
  std::vector<uint32_t> visit_;
  uint32_t visit_epoch_ = 0;
};

// The SAT estimate between two overlapping oriented boxes (see ContactEstimate).
OCTBAKE_API ContactEstimate estimate_contact(const OrientedBox& a, const OrientedBox& b);

}  // namespace octbake

#include "octbake/collision_world.h"
#include "octbake/format.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <bit>
#include <cassert>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>

#if defined(__linux__)
#include <sched.h>
#endif

#if __has_include("octbake/level_cache.h")
#include "octbake/level_cache.h"
#define OCTBAKE_HAS_LEVEL_CACHE 1
#else
#define OCTBAKE_HAS_LEVEL_CACHE 0
#endif

namespace octbake {

namespace {

// World AABBs (and the queries' boxes) are padded by kRelativePad of the
// object's own extent, as collide() pads its boxes, plus kWorldRoundingPad of
// the world coordinates, whose rounding (~1e-16 of them, in position + offset)
// it covers ~4,500 times over. The second term used to be kRelativePad too:
// at 1e6 it padded 1e-3-sized objects by their own size (test1 scaled by 1e-3
// at 1e6: 6x the candidate pairs, 9.0 against 6.6 µs a frame).
constexpr double kRelativePad = 1e-9;
constexpr double kWorldRoundingPad = 1e-12;
// Items per parallel chunk: enough work per chunk to pay for handing it out.
constexpr size_t kPairGrain = 16;    // pair tests: 0.3-1 µs each on small scenes, more on mixed sizes
constexpr size_t kPoseGrain = 512;   // set_poses items
// commit_poses' checks: a cell range each (~30 ns); a 10k-object frame lists
// only ~200 objects, which one chunk of kPoseGrain would leave to one thread.
constexpr size_t kCellCheckGrain = 64;
constexpr size_t kDepthGrain = 32;   // depth refreshes (a pixel area each at most)
constexpr size_t kAreaGrain = 256;   // slots in the passes over every object's area (thesis, legacy modes)
// WorldTree cell-move parts on an executor of unknown size: each part reads
// every move, so few, but enough to balance a few threads.
constexpr size_t kCellParts = 8;

std::atomic<uint32_t> g_next_world_id{1};

// Slot::area when the depth was decided from a lower bound (see refresh_depth).
constexpr double kAreaNotComputed = std::numeric_limits<double>::quiet_NaN();

Error bad(std::string why) { return Error{ErrorCode::invalid_argument, std::move(why)}; }

// |q| within 1e-6 of 1, on the squared norm (no square root per set_pose).
// NaN fails the comparisons and infinity the upper bound, so no finite test.
bool unit_rotation(const Pose& p) {
  constexpr double kLo = (1 - 1e-6) * (1 - 1e-6), kHi = (1 + 1e-6) * (1 + 1e-6);
  const double n2 = p.rotation.squaredNorm();
  return n2 > kLo && n2 < kHi;
}

// check_pose's test alone, inline: no Status built on the hot path.
[[gnu::always_inline]] inline bool position_ok(const Pose& p) {
  const Eigen::Vector3d& x = p.position;
  return std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]);
}
[[gnu::always_inline]] inline bool pose_ok(const Pose& p) {
  return position_ok(p) && std::isfinite(p.scale) && p.scale > 0 && unit_rotation(p);
}

// pose_ok's verdict, with the first rule broken named.
Status check_pose(const Pose& p) {
  if (pose_ok(p)) return std::monostate{};
  if (!p.position.allFinite()) return bad("pose: position is not finite");
  if (!std::isfinite(p.scale) || !(p.scale > 0)) return bad("pose: scale must be finite and > 0");
  return bad("pose: rotation is not a unit quaternion");
}

// set_lod's rules, shared with validate().
Status check_lod(const LodSettings& lod) {
  if (lod.min_depth < 0 || lod.max_depth < lod.min_depth) return bad("lod: need 0 <= min_depth <= max_depth");
  if (!(lod.pixel_tolerance > 0)) return bad("lod: pixel_tolerance must be > 0");
  return std::monostate{};
}

bool same_camera(const Camera& a, const Camera& b) {
  return a.position == b.position && a.look_at == b.look_at && a.up == b.up && a.fov_y_deg == b.fov_y_deg &&
         a.viewport_w == b.viewport_w && a.viewport_h == b.viewport_h && a.near_plane == b.near_plane &&
         a.far_plane == b.far_plane;
}

// The deepest depth the LOD lets an object of `max_depth` levels have.
int deepest_allowed(const LodSettings& s, int max_depth) { return std::max(0, std::min(s.max_depth, max_depth)); }

// choose_depths for one object (same rule, no allocation).
int depth_for(const LodSettings& s, double area, double a_min, double a_max, int max_depth) {
  const int hi = deepest_allowed(s, max_depth);
  const int lo = std::clamp(s.min_depth, 0, hi);
  switch (s.policy) {
    case LodPolicy::fixed: return hi;
    case LodPolicy::thesis: return thesis_depth(area, a_min, a_max, lo, hi);
    case LodPolicy::screen: return screen_depth(area, lo, hi, s.pixel_tolerance);
  }
  return hi;
}

// Bitwise equality (0.0 and -0.0 differ): "unchanged" must mean unchanged.
// Compared as integers, inline (a memcmp of a run-time size was a library
// call per set_pose).
bool same_bits(double a, double b) { return std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b); }
template <class V>
bool same_bits(const V& a, const V& b) {
  static_assert(V::SizeAtCompileTime > 0);
  bool same = true;
  for (int k = 0; k < V::SizeAtCompileTime; ++k) same &= same_bits(a[k], b[k]);
  return same;
}

double max_abs(const Eigen::Vector3d& v) { return v.cwiseAbs().maxCoeff(); }

// Local-space box of `c` at depth d, padded by `pad` on every side.
Aabb node_box(const Aabb& root, int d, uint32_t x, uint32_t y, uint32_t z, double pad) {
  const Eigen::Vector3d size = (root.max - root.min) / double(uint64_t{1} << d);
  const Eigen::Vector3d lo = root.min + size.cwiseProduct(Eigen::Vector3d(x, y, z));
  return {lo.array() - pad, (lo + size).array() + pad};
}

// Entry distance of the ray o + t*dir into `b`, within [t0, t1]; < 0 = miss.
double ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, const Aabb& b, double t0, double t1) {
  for (int k = 0; k < 3; ++k) {
    if (dir[k] == 0) {
      if (o[k] < b.min[k] || o[k] > b.max[k]) return -1;
      continue;
    }
    double ta = (b.min[k] - o[k]) / dir[k], tb = (b.max[k] - o[k]) / dir[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (!(t0 <= t1)) return -1;
  }
  return t0;
}

// Separating-axis test of two oriented boxes on the 15 candidate axes: the
// axis of least overlap (pointing from a to b) and that overlap (< 0 when
// separated along it by more than nothing). Worked out in a's frame, where
// b's axes are the columns of R = A^T B and the centre offset is t: an axis
// then costs a few products (Gottschalk's terms) instead of two 3x3 products
// and a normalisation in world space.
struct Sat {
  Eigen::Vector3d axis{1, 0, 0};
  double overlap = 0;
};
Sat sat(const OrientedBox& a, const OrientedBox& b) {
  const Eigen::Matrix3d r = a.axes.transpose() * b.axes;
  const Eigen::Vector3d t = a.axes.transpose() * (b.center - a.center);
  double best = std::numeric_limits<double>::infinity(), best_dist = 0;
  Eigen::Vector3d best_l{1, 0, 0};
  // Axis l (in a's frame, |l| = n), the boxes' radii and the centres' distance along l, all times n.
  const auto try_axis = [&](const Eigen::Vector3d& l, double n, double ra, double rb, double dist) {
    if (!(n > 1e-9)) return;  // near-parallel edges: no new axis
    const double overlap = (ra + rb - std::abs(dist)) / n;
    if (overlap < best) best = overlap, best_l = l / n, best_dist = dist;
  };
  const Eigen::Matrix3d abs_r = r.cwiseAbs();
  for (int i = 0; i < 3; ++i)
    try_axis(Eigen::Vector3d::Unit(i), 1, a.half[i], abs_r.row(i).dot(b.half.transpose()), t[i]);
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d l = r.col(j);
    try_axis(l, l.norm(), abs_r.col(j).dot(a.half), (r.transpose() * l).cwiseAbs().dot(b.half), t.dot(l));
  }
  // a_i x b_j = e_i x R e_j: zero on axis i, (-R(i2, j), R(i1, j)) on i1, i2.
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      Eigen::Vector3d l = Eigen::Vector3d::Zero();
      l[i1] = -r(i2, j);
      l[i2] = r(i1, j);
      double rb = 0;
      for (int k = 0; k < 3; ++k) rb += b.half[k] * std::abs(r(i1, k) * l[i1] + r(i2, k) * l[i2]);
      try_axis(l, std::sqrt(l[i1] * l[i1] + l[i2] * l[i2]), a.half[i1] * abs_r(i2, j) + a.half[i2] * abs_r(i1, j), rb,
               t[i1] * l[i1] + t[i2] * l[i2]);
    }
  }
  Sat s;
  s.overlap = best;
  s.axis = a.axes * (best_dist < 0 ? Eigen::Vector3d(-best_l) : best_l);
  return s;
}

void run_inline(size_t count, RangeTask task) {
  if (count > 0) task(0, count);
}

}  // namespace

ContactEstimate estimate_contact(const OrientedBox& a, const OrientedBox& b) {
  ContactEstimate e;
  e.leaf_a = a;
  e.leaf_b = b;
  const Aabb wa = world_bounds(a), wb = world_bounds(b);
  e.overlap = {wa.min.cwiseMax(wb.min), wa.max.cwiseMin(wb.max)};
  const Sat s = sat(a, b);
  e.normal = s.axis;
  e.penetration = std::max(0.0, s.overlap);
  return e;
}

// ---- ThreadPool ----

namespace {

void spin_pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace

int usable_cores() {
#if defined(__linux__)
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
#endif
  return int(std::max(1u, std::thread::hardware_concurrency()));  // 0: unknown
}

// A job is open from parallel_for's start until every chunk is done; a
// worker joins it only while it is open, so the caller never waits for a
// worker that was not scheduled in time (it runs the chunks itself). Workers
// spin before sleeping: detect() hands out several short jobs per frame, and
// waking a sleeping thread costs more than most of them. They spin 500 µs,
// long enough to bridge an app's work between two frames of a 10k-object
// scene (computing its poses), unless the pool has more threads than the
// process has cores (usable_cores): then spinners would take the cores from
// the threads with work, and they spin only 50 µs (libgomp likewise spins
// far less when oversubscribed).
//
// The chunks are split into one contiguous share per thread, which that
// thread runs first; then it helps with the others' shares. Jobs over the
// same items (set_poses' checks, frame after frame) thus find most of their
// data in the cache of the core that touched it last, instead of pulling it
// from the other core's.
struct ThreadPool::State {
  static constexpr auto kSpin = std::chrono::microseconds(500), kSpinOversubscribed = std::chrono::microseconds(50);

  std::mutex mutex;
  std::condition_variable work, done;
  std::vector<std::thread> workers;
  // Set by parallel_for while no worker is inside a job (see `inside`).
  RangeTask task;
  size_t count = 0, grain = 1;
  // Share t: chunks [next, end) not yet handed out (own cache lines: every
  // thread takes from its own cursor most of the time).
  struct alignas(64) Share {
    std::atomic<size_t> next{0};
    size_t end = 0;
  };
  std::unique_ptr<Share[]> shares;  // one per thread, the caller's first
  size_t threads = 1;
  std::atomic<size_t> chunks_left{0};  // chunks of the open job not yet done
  std::atomic<uint64_t> job{0};        // bumped when a job opens
  std::atomic<bool> open{false};
  std::atomic<int> inside{0};          // workers that joined the current job
  std::atomic<bool> stop{false};
  std::chrono::microseconds spin_for = kSpin;

  // Spins until pred() or spin_for passed; returns pred().
  template <class Pred>
  bool spin(Pred pred) const {
    const auto until = std::chrono::steady_clock::now() + spin_for;
    for (;;) {
      for (int i = 0; i < 64; ++i) {
        if (pred()) return true;
        spin_pause();
      }
      if (std::chrono::steady_clock::now() > until) return pred();
    }
  }
  // Thread `self`'s share first, then the others' in turn. The chunks done
  // are counted off once at the end (a shared counter bumped per chunk cost
  // ~45 ns a chunk on two cores).
  void run_chunks(size_t self) {
    size_t ran = 0;
    for (size_t k = 0; k < threads; ++k) {
      Share& share = shares[(self + k) % threads];
      for (;;) {
        const size_t chunk = share.next.fetch_add(1);
        if (chunk >= share.end) break;
        const size_t begin = chunk * grain;
        task(begin, std::min(count, begin + grain));
        ++ran;
      }
    }
    if (ran != 0 && chunks_left.fetch_sub(ran) == ran) {
      std::lock_guard lock(mutex);  // the caller may be about to wait
      done.notify_one();
    }
  }
  void worker(size_t self) {
    uint64_t seen = 0;
    for (;;) {
      const auto ready = [&] { return stop.load() || job.load() != seen; };
      if (!spin(ready)) {
        std::unique_lock lock(mutex);
        work.wait(lock, ready);
      }
      if (stop.load()) return;
      seen = job.load();
      // Join only the job still open (seq_cst pairs with the caller's close).
      inside.fetch_add(1);
      if (open.load() && job.load() == seen) run_chunks(self);
      inside.fetch_sub(1);
    }
  }
};

ThreadPool::ThreadPool(int threads) : state_(std::make_unique<State>()) {
  state_->threads = size_t(std::max(threads, 1));
  if (state_->threads > size_t(usable_cores())) state_->spin_for = State::kSpinOversubscribed;
  state_->shares = std::make_unique<State::Share[]>(state_->threads);
  for (size_t i = 1; i < state_->threads; ++i) {
    try {
      state_->workers.emplace_back([s = state_.get(), i] { s->worker(i); });
    } catch (const std::system_error&) {  // no thread to be had (a pid limit): run with those started
      state_->threads = i;
      break;
    }
  }
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(state_->mutex);
    state_->stop.store(true);
  }
  state_->work.notify_all();
  for (std::thread& t : state_->workers) t.join();
}

int ThreadPool::threads() const { return int(state_->threads); }

void ThreadPool::parallel_for(size_t count, size_t grain, RangeTask task) {
  State& s = *state_;
  grain = std::max<size_t>(grain, 1);
  if (s.workers.empty() || count <= grain) return run_inline(count, task);
  s.task = task;
  s.count = count;
  s.grain = grain;
  const size_t chunks = (count + grain - 1) / grain;
  for (size_t t = 0; t < s.threads; ++t) {
    s.shares[t].next.store(chunks * t / s.threads);
    s.shares[t].end = chunks * (t + 1) / s.threads;
  }
  s.chunks_left.store(chunks);
  s.open.store(true);
  {
    std::lock_guard lock(s.mutex);  // a worker between its check and its wait sees it
    s.job.fetch_add(1);
  }
  s.work.notify_all();
  s.run_chunks(0);
  const auto finished = [&] { return s.chunks_left.load() == 0; };
  if (!s.spin(finished)) {
    std::unique_lock lock(s.mutex);
    s.done.wait(lock, finished);
  }
  // Close the job, then let the workers that joined it leave before its
  // fields change (they find no chunk left).
  s.open.store(false);
  while (s.inside.load() != 0) spin_pause();
}

// ---- CollisionWorld ----

CollisionWorld::CollisionWorld(CollisionSettings settings)
    : settings_(std::move(settings)),
      view_(settings_.camera),
      id_(g_next_world_id.fetch_add(1)),
      tree_((settings_.bounds.min.array() < settings_.bounds.max.array()).all() && settings_.bounds.min.allFinite() &&
                    settings_.bounds.max.allFinite()
                ? settings_.bounds
                : CollisionSettings{}.bounds,
            std::clamp(settings_.world_depth, 0, 10)) {
  settings_.bounds = tree_.bounds();
  settings_.world_depth = tree_.depth();
  if (!settings_.executor && settings_.threads > 1) pool_ = std::make_unique<ThreadPool>(settings_.threads);
}

CollisionWorld::~CollisionWorld() = default;

Status CollisionWorld::validate(const CollisionSettings& s) {
  if (!s.bounds.min.allFinite() || !s.bounds.max.allFinite()) return bad("settings.bounds: not finite");
  if (!(s.bounds.min.array() < s.bounds.max.array()).all())
    return bad("settings.bounds: extent not positive on every axis (need min < max)");
  if (s.world_depth < 0 || s.world_depth > 10) return bad("settings.world_depth: outside 0..10");
  if (s.threads < 1) return bad("settings.threads: must be >= 1");
  if (Status st = check_lod(s.lod); !st) return bad("settings." + st.error().message);
  return std::monostate{};
}

Result<std::unique_ptr<CollisionWorld>> CollisionWorld::make(CollisionSettings settings) {
  if (Status st = validate(settings); !st) return st.error();
  return std::make_unique<CollisionWorld>(std::move(settings));
}

Status CollisionWorld::check(ObjectHandle h) const {
  if (h.world != id_) return bad("handle: belongs to another CollisionWorld (or was never issued)");
  if (h.slot >= slots_.size() || h.generation == 0) return bad("handle: no such object");
  if (live_generation_[h.slot] != h.generation) return bad("handle: object was destroyed");
  return std::monostate{};
}

bool CollisionWorld::alive(ObjectHandle h) const { return valid(h); }

std::optional<ObjectHandle> CollisionWorld::handle_at(uint32_t slot) const {
  if (slot >= slots_.size() || !live(slot)) return std::nullopt;
  return ObjectHandle{slot, live_generation_[slot], id_};
}

const ObjectTree& CollisionWorld::tree_of(const Slot& s) const {
#if OCTBAKE_HAS_LEVEL_CACHE
  if (s.source.cache) return s.source.cache->tree(s.source.id);
#endif
  return *s.source.tree;
}

int CollisionWorld::max_depth_of(const Slot& s) const {
#if OCTBAKE_HAS_LEVEL_CACHE
  if (s.source.cache) return std::min(s.source.cache->baked_depth(s.source.id), kMaxDepth);
#endif
  return std::min(s.source.tree->loaded_depth(), kMaxDepth);
}

void CollisionWorld::set_offset(uint32_t i) {
  Slot& s = slots_[i];
  roots_[i] = placed_root(tree_of(s), s.pose);
  s.offset = world_bounds(roots_[i].box);
  // A box too large for a double (scale times bounds past 1.8e308) comes out
  // with infinities and NaN (0 * inf in the rotation): it then spans every
  // axis, so the object meets every other one, instead of a NaN box that the
  // WorldTree would file in one corner cell and no overlap test would pass.
  if (!s.offset.min.allFinite() || !s.offset.max.allFinite()) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    s.offset = {Eigen::Vector3d::Constant(-inf), Eigen::Vector3d::Constant(inf)};
  }
  s.offset_reach = max_abs_coordinate(s.offset);
}

OrientedBox CollisionWorld::root_box(uint32_t i) const {
  OrientedBox box = roots_[i].box;
  box.center = slots_[i].pose.position + box.center;  // as Pose::apply adds them: place()'s bits
  return box;
}

void CollisionWorld::place_box(uint32_t i) {
  const Slot& s = slots_[i];
  const Eigen::Vector3d& p = s.pose.position;
  const double pad = kRelativePad * s.offset_reach + kWorldRoundingPad * max_abs(p);
  boxes_[i].min = (p + s.offset.min).array() - pad;
  boxes_[i].max = (p + s.offset.max).array() + pad;
}

Result<ObjectHandle> CollisionWorld::create(TreeSource source, const Pose& pose) {
  if (source.cache) {
#if !OCTBAKE_HAS_LEVEL_CACHE
    return bad("create: streamed trees need octbake/level_cache.h (not in this build)");
#endif
  } else if (!source.tree) {
    return bad("create: null tree");
  }
  if (Status st = check_pose(pose); !st) return st.error();
  if (slots_.size() >= (size_t{1} << 31) && free_slots_.empty()) return bad("create: too many objects");
  uint32_t i;
  if (!free_slots_.empty()) {
    i = free_slots_.back();
    free_slots_.pop_back();
  } else {
    i = uint32_t(slots_.size());
    slots_.emplace_back();
    live_generation_.push_back(0);
    cell_changed_.push_back(0);
    boxes_.emplace_back();
    roots_.emplace_back();
  }
  Slot& s = slots_[i];
  const uint32_t generation = s.generation + 1 == 0 ? 1 : s.generation + 1;
  // A slot destroyed since the last commit is still listed: list it once.
  const bool listed = s.listed;
  s = Slot{};
  s.generation = live_generation_[i] = generation;
  s.source = source;
  s.pose = pose;
  set_offset(i);
  place_box(i);
  s.tree_dirty = s.listed = true;
  if (!listed) dirty_.push_back(i);
  cell_changed_[i] = 1;
  any_stale_area_ = true;
  ++live_;
  return ObjectHandle{i, generation, id_};
}

Status CollisionWorld::destroy(ObjectHandle h) {
  if (Status st = check(h); !st) return st;
  Slot& s = slots_[h.slot];
  tree_.remove(h.slot);
  live_generation_[h.slot] = 0;
  s.tree_dirty = false;  // a stale entry in dirty_ is skipped
  free_slots_.push_back(h.slot);
  --live_;
  any_stale_area_ = true;  // thesis: A_min / A_max may change
  return std::monostate{};
}

namespace {

// Bitwise the same rotation and scale: the offset box stays.
bool same_frame_of(const Pose& a, const Pose& b) {
  return same_bits(a.rotation.coeffs(), b.rotation.coeffs()) && same_bits(a.scale, b.scale);
}
// Bitwise the same pose: set_pose is then a no-op (the stored pose was checked).
bool same_pose(const Pose& a, const Pose& b) { return same_frame_of(a, b) && same_bits(a.position, b.position); }
// The same tree, rotation, scale and depth: only the position may differ.
bool same_but_position(const PlacedTree& a, const PlacedTree& b) {
  return a.tree == b.tree && a.depth == b.depth && same_frame_of(a.pose, b.pose);
}
// How far b moved relative to a from (a0, b0), the difference taken as
// collide() takes it (b's position less a's). Its length is taken scaled to
// its largest coordinate: squared, a move of a scene scaled by 2^-1000
// underflowed to 0 (every miss then kept apart).
double relative_move(const PlacedTree& a0, const PlacedTree& b0, const PlacedTree& a, const PlacedTree& b) {
  const Eigen::Vector3d move = (b.pose.position - a.pose.position) - (b0.pose.position - a0.pose.position);
  const double largest = move.cwiseAbs().maxCoeff();
  return largest > 0 ? largest * (move / largest).norm() : largest;
}

}  // namespace

// Inlined: set_pose runs it for every moved object.
[[gnu::always_inline]] inline bool CollisionWorld::move_to(uint32_t i, const Pose& pose, bool same_frame) {
  Slot& s = slots_[i];
  s.pose = pose;
  if (!same_frame) set_offset(i);  // only the position changed: the offset box stays
  place_box(i);
  if (settings_.area_refresh == AreaRefresh::on_demand) s.area_epoch = 0;
  if (s.tree_dirty) return false;
  // Most moves stay in the same WorldTree cells, whose entry then stays
  // right: only a change of cells is listed or committed (reading the entry
  // here, while the slot is hot, spares commit_poses a pass over every
  // mover).
  return tree_.needs_update(i, boxes_[i]);
}

// set_poses' objects that change cells, to their new cells (as
// commit_poses would) in one inline batch: per object, the one-by-one update
// cost ~40% more.
void CollisionWorld::commit_moves(std::span<const uint32_t> slots, std::span<const WorldTree::CellRange> cells) {
  for (uint32_t i : slots) cell_changed_[i] = 1;
  struct Inline final : WorldTree::Parallel {
    void for_ranges(size_t count, size_t, void (*task)(const void*, size_t, size_t), const void* ctx) override {
      task(ctx, 0, count);
    }
  } inline_parts;
  tree_.update_cells(slots, cells, inline_parts, 1);
}

Status CollisionWorld::set_pose(ObjectHandle h, const Pose& pose) {
  // Statuses are built only for errors: their construction and destruction
  // were a fifth of a set_pose.
  if (!valid(h)) return check(h);
  // An app that sets every pose every frame pays almost nothing for the
  // objects that did not move.
  const Pose& now = slots_[h.slot].pose;
  const bool same_frame = same_frame_of(pose, now);
  if (same_frame && same_bits(pose.position, now.position)) return std::monostate{};
  // The same rotation and scale as the stored pose passed pose_ok already.
  if (!(same_frame ? position_ok(pose) : pose_ok(pose))) return check_pose(pose);
  if (move_to(h.slot, pose, same_frame)) {
    // A live slot that is not dirty was committed, so it is not listed.
    slots_[h.slot].tree_dirty = slots_[h.slot].listed = true;
    dirty_.push_back(h.slot);
  }
  if (settings_.area_refresh == AreaRefresh::on_demand) any_stale_area_ = true;
  return std::monostate{};
}

Status CollisionWorld::set_poses(std::span<const ObjectHandle> handles, std::span<const Pose> poses) {
  if (handles.size() != poses.size())
    return bad("set_poses: " + std::to_string(handles.size()) + " handles but " + std::to_string(poses.size()) +
               " poses");
  if (handles.size() > std::numeric_limits<uint32_t>::max()) return bad("set_poses: more than 2^32 - 1 items");
  const size_t n = handles.size();
  std::atomic<bool> refused{false}, unordered{false};
  // 1. Every item checked as set_pose would, and whether the slots ascend:
  //    then none is named twice (handles in creation order, the usual case,
  //    need no duplicate pass).
  const auto check_items = [&](size_t b, size_t e) {
    bool ok = true, ascending = true;
    for (size_t k = b; k < e; ++k) {
      const ObjectHandle h = handles[k];
      ascending &= k == 0 || handles[k - 1].slot < h.slot;
      // A pose bitwise equal to the stored one passed pose_ok when it was
      // set, but telling it apart would read the slot: every pose is checked.
      if (!valid(h) || !pose_ok(poses[k])) ok = false;
    }
    if (!ok) refused.store(true, std::memory_order_relaxed);
    if (!ascending) unordered.store(true, std::memory_order_relaxed);
  };
  run_parallel(n, kPoseGrain, range_task(check_items));
  // 2. Otherwise each item claims its slot, the last claim winning (plain
  //    stores: relaxed atomics); a slot claimed by another item is named twice.
  if (!refused.load() && unordered.load()) {
    if (claim_.size() < slots_.size()) claim_.resize(slots_.size());  // grows with the world only
    const auto claim = [&](size_t b, size_t e) {
      for (size_t k = b; k < e; ++k)
        std::atomic_ref<uint32_t>(claim_[handles[k].slot]).store(uint32_t(k), std::memory_order_relaxed);
    };
    const auto check_claims = [&](size_t b, size_t e) {
      for (size_t k = b; k < e; ++k)
        if (std::atomic_ref<uint32_t>(claim_[handles[k].slot]).load(std::memory_order_relaxed) != k) {
          refused.store(true, std::memory_order_relaxed);
          return;
        }
    };
    run_parallel(n, kPoseGrain, range_task(claim));
    run_parallel(n, kPoseGrain, range_task(check_claims));
  }
  if (refused.load()) return first_pose_error(handles, poses);
  // 3. The moves, each on its own slot, in blocks taken in order; and the
  //    WorldTree following them block by block, in block order, beside the
  //    moves of later blocks. Its updates are serial and bound by cache
  //    misses: run after all the moves, they took as long on two threads as
  //    on one. A block hands over only its objects that change cells, with
  //    their cells, in its share of move_slots_ and move_cells_: the update
  //    then reads no slot or box that another core has just written.
  if (move_slots_.size() < n) move_slots_.resize(n), move_cells_.resize(n);
  const size_t blocks = (n + kPoseGrain - 1) / kPoseGrain;
  if (block_moves_.size() < blocks) block_moves_.resize(blocks);
  std::fill_n(block_moves_.begin(), blocks, kBlockNotMoved);
  std::atomic<bool> any_moved{false};
  // Moves block `block` unless a thread has taken it; false if one had.
  const auto move_block = [&](size_t block) {
    uint32_t state = kBlockNotMoved;
    if (!std::atomic_ref(block_moves_[block]).compare_exchange_strong(state, kBlockTaken, std::memory_order_relaxed))
      return false;
    bool any = false;
    uint32_t* slots = move_slots_.data() + block * kPoseGrain;
    WorldTree::CellRange* cells = move_cells_.data() + block * kPoseGrain;
    uint32_t changed = 0;
    for (size_t k = block * kPoseGrain; k < std::min(n, (block + 1) * kPoseGrain); ++k) {
      const uint32_t i = handles[k].slot;
      const bool same_frame = same_frame_of(poses[k], slots_[i].pose);
      if (same_frame && same_bits(poses[k].position, slots_[i].pose.position)) continue;
      any = true;
      if (move_to(i, poses[k], same_frame)) {
        slots[changed] = i;
        cells[changed++] = tree_.cell_range(boxes_[i]);
      }
    }
    if (any) any_moved.store(true, std::memory_order_relaxed);
    std::atomic_ref(block_moves_[block]).store(changed, std::memory_order_release);
    return true;
  };
  // Each block's objects that change cells to their new cells, in block
  // order, each block as soon as it is moved: it moves a block no thread
  // has taken itself; while another thread moves it, it moves a later one
  // not taken, so it waits only while every block left is being moved by a
  // running chunk, whatever order the executor runs the chunks in (inline:
  // it moves and updates block after block, while they are in the cache).
  const auto follow_blocks = [&] {
    size_t help = 0;  // blocks before it are taken
    for (size_t block = 0; block < blocks; ++block) {
      uint32_t changed;
      while ((changed = std::atomic_ref(block_moves_[block]).load(std::memory_order_acquire)) >= kBlockTaken)
        if (!move_block(block)) {
          for (help = std::max(help, block + 1); help < blocks && !move_block(help);) ++help;
          if (help == blocks) spin_pause();
        }
      commit_moves(std::span(move_slots_).subspan(block * kPoseGrain, changed),
                   std::span(move_cells_).subspan(block * kPoseGrain, changed));
    }
  };
  // Chunk 0 follows the blocks (first, on the calling thread, for the
  // built-in pool); chunk c moves block c - 1. The pool runs each thread's
  // share of the chunks first: a worker moves the same blocks frame after
  // frame, and finds their slots in its core's cache (taking whichever
  // block came next made two threads' moves ~1.7x slower per block than
  // one's on a host with a slow core-to-core round trip). One block is not
  // worth a fork.
  if (blocks == 1)
    follow_blocks();
  else
    run_parallel(blocks + 1, 1, range_task([&](size_t b, size_t e) {
                   for (size_t c = b; c < e; ++c)
                     if (c == 0)
                       follow_blocks();
                     else
                       move_block(c - 1);
                 }));
  const bool moved = any_moved.load();
  if (moved && settings_.area_refresh == AreaRefresh::on_demand) any_stale_area_ = true;
  return std::monostate{};
}

// The error set_poses reports: the first refused item, in index order.
Status CollisionWorld::first_pose_error(std::span<const ObjectHandle> handles, std::span<const Pose> poses) const {
  std::vector<uint32_t> first_at(slots_.size(), UINT32_MAX);
  for (size_t k = 0; k < handles.size(); ++k) {
    const std::string at = "set_poses: item " + std::to_string(k) + ": ";
    if (Status st = check(handles[k]); !st) return bad(at + st.error().message);
    const uint32_t i = handles[k].slot;
    if (!same_pose(poses[k], slots_[i].pose))
      if (Status st = check_pose(poses[k]); !st) return bad(at + st.error().message);
    if (first_at[i] != UINT32_MAX)
      return bad(at + "the same object as item " + std::to_string(first_at[i]) + " (each object at most once)");
    first_at[i] = uint32_t(k);
  }
  return bad("set_poses: refused");  // not reached: phase 1 or 2 found one of the above
}

Result<Pose> CollisionWorld::pose(ObjectHandle h) const {
  if (Status st = check(h); !st) return st.error();
  return slots_[h.slot].pose;
}

// O(1): a new epoch makes every area stale (set_camera runs every frame).
void CollisionWorld::invalidate_all_areas() {
  ++epoch_;
  legacy_all_ = true;
  any_stale_area_ = true;
}

void CollisionWorld::set_camera(const Camera& camera) {
  if (same_camera(camera, settings_.camera)) return;
  settings_.camera = camera;
  view_ = CameraView(camera);
  invalidate_all_areas();
}

Status CollisionWorld::set_lod(const LodSettings& lod) {
  if (Status st = check_lod(lod); !st) return st;
  settings_.lod = lod;
  invalidate_all_areas();
  return std::monostate{};
}

uint64_t CollisionWorld::refresh_depth(uint32_t i) {
  if (settings_.lod.policy == LodPolicy::thesis) return refresh_all_thesis();
  Slot& s = slots_[i];
  if (s.area_epoch == epoch_) return 0;
  const int max_depth = max_depth_of(s);
  const auto depth_at = [&](double area) { return depth_for(settings_.lod, area, 0, 0, max_depth); };
  uint64_t computed = 0;
  // The fixed policy does not look at the area: it is not computed. Neither
  // does screen when bounds already decide the depth (screen depths never
  // fall as the area grows): when a lower bound gives the deepest depth (near
  // objects) or an upper bound the same depth as the lower one (far objects,
  // objects out of view).
  if (settings_.lod.policy == LodPolicy::screen) {  // thesis returned above
    // (An infinite pixel tolerance makes every depth the shallowest: such a
    // world takes the exact path below, with the same result.)
    const OrientedBox box = root_box(i);
    const int at_least = depth_at(pixel_area_lower_bound(view_, box));
    if (at_least == deepest_allowed(settings_.lod, max_depth) ||
        depth_at(pixel_area_upper_bound(view_, box)) == at_least) {
      s.area = kAreaNotComputed;  // area() computes it if asked
      s.depth = at_least;
      s.area_epoch = epoch_;
      return 0;
    }
    s.area = pixel_area(view_, box);
    computed = 1;
  }
  s.depth = depth_at(s.area);
  s.area_epoch = epoch_;
  return computed;
}

namespace {

// The smallest and largest of values merged from several threads: exact, so
// the result does not depend on the order (as std::min / std::max, a NaN is
// skipped).
class AreaRange {
 public:
  void merge(double lo, double hi) {
    for (double x = lo_.load(std::memory_order_relaxed); lo < x;)
      if (lo_.compare_exchange_weak(x, lo, std::memory_order_relaxed)) break;
    for (double x = hi_.load(std::memory_order_relaxed); hi > x;)
      if (hi_.compare_exchange_weak(x, hi, std::memory_order_relaxed)) break;
  }
  double lo() const { return lo_.load(); }
  double hi() const { return hi_.load(); }

 private:
  std::atomic<double> lo_{std::numeric_limits<double>::infinity()};
  std::atomic<double> hi_{-std::numeric_limits<double>::infinity()};
};

}  // namespace

// The areas of the live slots for which stale(i) holds, computed now, then
// computed(slot) for each, on the world's threads (each slot is written by
// one item only). With `range` (a_min, a_max): the range of every live area
// afterwards (a loop-carried min and max: only when asked).
template <class Stale, class Computed>
uint64_t CollisionWorld::compute_areas(Stale stale, Computed computed, double* range) {
  std::atomic<uint64_t> count{0};
  AreaRange merged;
  const auto areas = [&](size_t b, size_t e) {
    uint64_t c = 0;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (size_t i = b; i < e; ++i) {
      if (!live(uint32_t(i))) continue;
      Slot& s = slots_[i];
      if (stale(uint32_t(i))) {
        s.area = pixel_area(view_, root_box(uint32_t(i)));
        computed(s);
        ++c;
      }
      if (range) lo = std::min(lo, s.area), hi = std::max(hi, s.area);
    }
    count.fetch_add(c, std::memory_order_relaxed);
    if (range) merged.merge(lo, hi);
  };
  run_parallel(slots_.size(), kAreaGrain, range_task(areas));
  if (range) range[0] = merged.lo(), range[1] = merged.hi();
  return count.load();
}

int CollisionWorld::depth_in_range(const Slot& s, double a_min, double a_max) const {
  return std::clamp(depth_for(settings_.lod, s.area, a_min, a_max, max_depth_of(s)), 0, max_depth_of(s));
}

// Every depth from the area range (thesis LOD), on the world's threads.
void CollisionWorld::set_depths_from(const double (&range)[2]) {
  const auto depths = [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (live(uint32_t(i))) slots_[i].depth = depth_in_range(slots_[i], range[0], range[1]);
  };
  run_parallel(slots_.size(), kAreaGrain, range_task(depths));
}

// Every live slot's area (the stale ones computed) and every depth from
// their range: O(objects).
uint64_t CollisionWorld::refresh_all_thesis() {
  if (!any_stale_area_) return 0;
  double range[2];
  const uint64_t computed = compute_areas([&](uint32_t i) { return slots_[i].area_epoch != epoch_; },
                                          [&](Slot& s) { s.area_epoch = epoch_; }, range);
  set_depths_from(range);
  any_stale_area_ = false;
  return computed;
}

// The historic World rule: recompute the stale (or all) areas now; depths of
// the recomputed objects, or of every object when thesis or `all` (then from
// the range of every area).
uint64_t CollisionWorld::refresh_legacy(bool all) {
  all = all || legacy_all_;  // the camera or the LOD changed
  legacy_all_ = false;
  const auto stale = [&](uint32_t i) {
    if (!all && !cell_changed_[i]) return false;
    cell_changed_[i] = 0;  // taken: its area is computed now
    return true;
  };
  if (!all && settings_.lod.policy != LodPolicy::thesis)
    return compute_areas(stale, [&](Slot& s) { s.depth = depth_in_range(s, 0, 0); }, nullptr);
  double range[2];
  const uint64_t computed = compute_areas(stale, [](Slot&) {}, range);
  if (computed > 0) set_depths_from(range);
  return computed;
}

Result<int> CollisionWorld::depth(ObjectHandle h) {
  if (Status st = check(h); !st) return st.error();
  if (settings_.area_refresh == AreaRefresh::on_demand) refresh_depth(h.slot);
  return slots_[h.slot].depth;
}

Result<double> CollisionWorld::area(ObjectHandle h) {
  if (Status st = check(h); !st) return st.error();
  Slot& s = slots_[h.slot];
  if (settings_.area_refresh == AreaRefresh::on_demand) {
    refresh_depth(h.slot);
    if (settings_.lod.policy == LodPolicy::fixed || std::isnan(s.area))
      s.area = pixel_area(view_, root_box(h.slot));
  }
  return s.area;
}

PlacedTree CollisionWorld::placed(uint32_t i) const {
  const Slot& s = slots_[i];
  return {&tree_of(s), s.pose, s.depth};
}

void CollisionWorld::run_parallel(size_t count, size_t grain, RangeTask task) {
  if (settings_.executor)
    settings_.executor->parallel_for(count, grain, task);
  else if (pool_)
    pool_->parallel_for(count, grain, task);
  else
    run_inline(count, task);
}

void CollisionWorld::find_apart(size_t begin, size_t end) {
  for (size_t k = begin; k < end; ++k) {
    PairResult& r = results_[k];
    const auto [a, b] = pairs_[k];
    // A last hit's leaf pair is tried first (one box test that likely proves
    // the hit again), whatever the roots.
    const bool last_hit = r.last != kNone && last_results_[r.last].test.hit;
    r.apart = !last_hit && roots_apart(roots_[a], slots_[a].pose.position, roots_[b], slots_[b].pose.position);
  }
}

// Each pair not apart keeps last frame's record, or takes a free one; the
// records of last frame's pairs that are gone or apart are freed. Serial and
// before the pair tests: each record then belongs to one pair, which alone
// writes it.
void CollisionWorld::assign_records() {
  if (!settings_.coherence) {  // nothing is kept from last frame: the records in pair order
    uint32_t used = 0;
    for (PairResult& r : results_) r.record = r.apart ? kNone : used++;
    if (records_.size() < used) records_.resize(used);
    return;
  }
  for (PairResult& r : results_) {
    if (r.apart) {
      r.record = kNone;
    } else if (r.last != kNone) {
      r.record = std::exchange(last_results_[r.last].record, kNone);
    } else if (!free_records_.empty()) {
      r.record = free_records_.back();
      free_records_.pop_back();
    } else {
      r.record = uint32_t(records_.size());
      records_.emplace_back();
    }
  }
  for (PairResult& r : last_results_)
    if (r.record != kNone) free_records_.push_back(std::exchange(r.record, kNone));
}

// test_pairs' separation asks: the longest wait between two asks (in tests
// of the pair), and the box tests above which a miss counts as near.
constexpr uint8_t kLongestWait = 128;
constexpr uint64_t kNearMissBoxTests = 128;

void CollisionWorld::test_pairs(size_t begin, size_t end) {
  for (size_t k = begin; k < end; ++k) {
    const auto [a, b] = pairs_[k];
    PairResult& r = results_[k];
    if (r.apart) {
      r.test = PairTest{.hit = false, .box_tests = 1, .leaf = {}};
      r.reused = r.kept_apart = false;
      continue;
    }
    const PlacedTree pa = placed(a), pb = placed(b);
    TestRecord& tested = records_[r.record];
    // Tested last frame on the same trees, poses and depths: the same result
    // (collide is deterministic; a hit's leaf pair, tried first, would prove
    // it again), so none of it is redone, and the record (estimate and
    // placements) stays as it is.
    const PairResult* last = r.last != kNone ? &last_results_[r.last] : nullptr;
    // At most the positions changed since the test.
    const bool only_moved = last && same_but_position(tested.a, pa) && same_but_position(tested.b, pb);
    r.reused = only_moved && same_bits(tested.a.pose.position, pa.pose.position) &&
               same_bits(tested.b.pose.position, pb.pose.position);
    // Or kept apart: a miss whose objects only translated, by less than its
    // separation; the record keeps the placements it was tested at, which
    // later frames are measured from.
    r.kept_apart = !r.reused && only_moved && !last->test.hit && tested.separation > 0 &&
                   relative_move(tested.a, tested.b, pa, pb) < tested.separation;
    if (r.reused || r.kept_apart) {
      r.test = PairTest{.hit = last->test.hit, .box_tests = 0, .leaf = last->test.leaf};
      continue;
    }
    tested.separation = 0;
    if (last && last->test.hit) {
      PairCache hint{tested.a.tree, tested.b.tree, tested.a.depth, tested.b.depth, last->test.leaf};
      r.test = collide(pa, pb, hint);
    } else if (only_moved) {
      // Moving without turning: with collide()'s separation the next frames
      // may need no test. It is worth knowing only if it outlasts a step like
      // this one (the move since the last test); a pair whose separation did
      // not is not asked again for its next 8 tests, then 16, ... 128 (an
      // ask costs 0.3-0.4 of a test more in bench_pair's BM_Separation loop,
      // 0.5-0.7 inside bench_fcl's frames, where its code is cold).
      // A near miss, whose last test took more than kNearMissBoxTests, waits
      // the longest from the start: its separation seldom outlasts a step
      // (bench_fcl test1, asks after such tests: 66 of 312, 68% of the asks'
      // box tests, 6 of 208 frames kept apart), so it is tried once per
      // kLongestWait tests, and asked on while that pays.
      if (tested.separation_rest == 0 && tested.separation_wait < kLongestWait &&
          last->test.box_tests > kNearMissBoxTests)
        tested.separation_rest = tested.separation_wait = kLongestWait;
      if (tested.separation_rest > 0) {
        --tested.separation_rest;
        r.test = collide(pa, pb);
      } else {
        tested.separation = relative_move(tested.a, tested.b, pa, pb);
        r.test = collide(pa, pb, tested.separation);
        const bool lasts = r.test.hit || tested.separation > 0;
        tested.separation_wait = lasts ? 0 : uint8_t(std::clamp(2 * tested.separation_wait, 8, int(kLongestWait)));
        tested.separation_rest = tested.separation_wait;
      }
    } else {
      tested.separation_rest = tested.separation_wait = 0;  // (a record new to the pair holds another's)
      r.test = collide(pa, pb);
    }
    if (r.test.hit) tested.estimate = estimate_contact(leaf_box(pa, r.test.leaf.a), leaf_box(pb, r.test.leaf.b));
    tested.a = pa;
    tested.b = pb;
  }
}

void CollisionWorld::commit_poses() {
  // Which listed objects still change cells (one may have moved back since
  // it was listed), in parallel (dirty_ names each slot once, see create());
  // then the WorldTree's batch moves them (in parallel parts but for the
  // cells new to its table).
  const size_t n = dirty_.size();
  if (move_flags_.size() < n) move_flags_.resize(n);
  if (ranges_.size() < n) ranges_.resize(n);
  const auto check_cells = [&](size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) {
      const uint32_t i = dirty_[k];
      Slot& s = slots_[i];
      move_flags_[k] = kUnmoved;
      s.listed = false;
      if (!live(i) || !s.tree_dirty) continue;  // destroyed since
      s.tree_dirty = false;
      ranges_[k] = tree_.cell_range(boxes_[i]);
      if (tree_.needs_update(i, ranges_[k])) move_flags_[k] = kMoved;
    }
  };
  run_parallel(n, kCellCheckGrain, range_task(check_cells));
  // The moved ones, in order, to the front (dirty_ is cleared below).
  size_t moved = 0;
  for (size_t k = 0; k < n; ++k)
    if (move_flags_[k] == kMoved) {
      cell_changed_[dirty_[k]] = 1;
      dirty_[moved] = dirty_[k];
      ranges_[moved++] = ranges_[k];
    }
  struct OnWorld final : WorldTree::Parallel {
    CollisionWorld* world;
    explicit OnWorld(CollisionWorld* w) : world(w) {}
    void for_ranges(size_t count, size_t grain, void (*task)(const void*, size_t, size_t), const void* ctx) override {
      world->run_parallel(count, grain, RangeTask{task, ctx});
    }
  } on_world(this);
  // Inline: one pass over the cells; on threads, parts of disjoint cells
  // (runs of cell slots), two per pool thread: a frame's moves load the
  // parts unevenly, and a thread done with its own then helps with another
  // (10k objects, 2 threads: ~2% faster frames than one part per thread).
  const size_t parts = settings_.executor ? kCellParts
                       : pool_ ? std::min(kCellParts, 2 * std::bit_ceil(size_t(pool_->threads())))
                               : 1;
  tree_.update_cells(std::span(dirty_).first(moved), std::span(ranges_).first(moved), on_world, parts);
  dirty_.clear();
}

namespace {

// Takes the pair scan's blocks from every thread: room in `room` is reserved
// by an atomic counter; a block that does not fit (only in a frame with more
// pairs than room, i.e. than any frame before) goes to `spill` under a lock.
// The room filled is the prefix before the first block that did not fit.
class PairCollector final : public WorldTree::PairSink {
 public:
  PairCollector(std::span<std::pair<uint32_t, uint32_t>> room, std::vector<std::pair<uint32_t, uint32_t>>& spill)
      : room_(room), spill_(spill) {}
  void take(std::span<const std::pair<uint32_t, uint32_t>> pairs) override {
    const size_t at = used_.fetch_add(pairs.size(), std::memory_order_relaxed);
    if (at + pairs.size() <= room_.size()) {
      std::copy(pairs.begin(), pairs.end(), room_.begin() + ptrdiff_t(at));
      return;
    }
    std::lock_guard lock(mutex_);
    filled_ = std::min(filled_, at);
    spill_.insert(spill_.end(), pairs.begin(), pairs.end());
  }
  size_t filled() const { return std::min(filled_, used_.load()); }  // after the scan

 private:
  std::span<std::pair<uint32_t, uint32_t>> room_;
  std::vector<std::pair<uint32_t, uint32_t>>& spill_;
  std::atomic<size_t> used_{0};
  std::mutex mutex_;
  size_t filled_ = SIZE_MAX;
};

}  // namespace

void CollisionWorld::collect_pairs() {
  // Room for as many pairs as any frame had: filled without allocating, and
  // grown (value-initialised) only after a frame with more.
  if (pair_room_.size() < std::max<size_t>(pairs_.capacity(), 256))
    pair_room_.resize(std::max<size_t>(pairs_.capacity(), 256));
  spilled_pairs_.clear();
  PairCollector collector(pair_room_, spilled_pairs_);
  const auto scan = [&](size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) tree_.scan_part(k, boxes_, collector);
  };
  const size_t parts = tree_.scan_parts();
  if (live_ < kParallelScanObjects)  // see the declaration
    scan(0, parts);
  else
    run_parallel(parts, 1, range_task(scan));
  pairs_.assign(pair_room_.begin(), pair_room_.begin() + ptrdiff_t(collector.filled()));
  pairs_.insert(pairs_.end(), spilled_pairs_.begin(), spilled_pairs_.end());
  tree_.finish_pairs(boxes_, pairs_);
}

DetectStats CollisionWorld::detect(std::vector<Contact>& out) {
  DetectStats stats;
  stats.objects = live_;
  out.clear();

  // 1. The WorldTree follows the poses.
  commit_poses();

  // 2. Legacy LOD modes compute their areas before the pairs.
  if (settings_.area_refresh != AreaRefresh::on_demand)
    stats.area_computations = refresh_legacy(settings_.area_refresh == AreaRefresh::every_frame);

  // 3. Candidate pairs, pre-filtered by world AABBs: the cell scan in parts,
  // then one sort.
  collect_pairs();
  const size_t n = pairs_.size();
  stats.candidate_pairs = stats.pair_tests = n;

  // 4. Last frame's results (coherence), matched by a merge over the sorted
  // pairs: a hit's leaf pair is tried first; the pairs without one whose
  // root boxes are apart: collide() would end at its root test at any
  // depths, so they ask for no depth (one box test each, as collide()
  // counts it).
  results_.resize(n);
  {
    size_t j = 0;
    for (size_t k = 0; k < n; ++k) {
      while (j < last_pairs_.size() && last_pairs_[j] < pairs_[k]) ++j;
      results_[k].last =
          j < last_pairs_.size() && last_pairs_[j] == pairs_[k] && !last_results_[j].apart ? uint32_t(j) : kNone;
    }
  }
  run_parallel(n, kPairGrain, range_task([this](size_t b, size_t e) { find_apart(b, e); }));
  assign_records();

  // 5. Depths of the objects in the other pairs: each stale one once, in parallel.
  if (settings_.area_refresh == AreaRefresh::on_demand) {
    if (settings_.lod.policy == LodPolicy::thesis) {
      if (n > 0) stats.area_computations = refresh_all_thesis();
    } else {
      // Each stale object once, in slot order, from a bit per slot (sorting
      // the pairs' ends was ~5% of a frame with 3k pairs resting in contact).
      if (stale_bits_.size() * 64 < slots_.size()) stale_bits_.resize((slots_.size() + 63) / 64);
      size_t first_word = stale_bits_.size(), end_word = 0;
      for (size_t k = 0; k < n; ++k)
        if (!results_[k].apart)
          for (uint32_t i : {pairs_[k].first, pairs_[k].second})
            if (slots_[i].area_epoch != epoch_) {
              stale_bits_[i / 64] |= uint64_t(1) << (i % 64);
              first_word = std::min<size_t>(first_word, i / 64);
              end_word = std::max<size_t>(end_word, i / 64 + 1);
            }
      stale_.clear();
      for (size_t w = first_word; w < end_word; ++w)
        for (uint64_t bits = std::exchange(stale_bits_[w], 0); bits != 0; bits &= bits - 1)
          stale_.push_back(uint32_t(64 * w + size_t(std::countr_zero(bits))));
      std::atomic<uint64_t> computed{0};
      const auto refresh = [&](size_t b, size_t e) {
        uint64_t c = 0;
        for (size_t k = b; k < e; ++k) c += refresh_depth(stale_[k]);
        computed.fetch_add(c, std::memory_order_relaxed);
      };
      run_parallel(stale_.size(), kDepthGrain, range_task(refresh));
      stats.area_computations = computed.load();
    }
  }

#if OCTBAKE_HAS_LEVEL_CACHE
  // 6. Streamed trees: decode what the depths ask for, in TreeId order, then
  // clamp to what is held after every require (a later require may evict).
  streamed_.clear();
  for (size_t k = 0; k < n; ++k)
    if (!results_[k].apart)
      for (uint32_t i : {pairs_[k].first, pairs_[k].second})
        if (slots_[i].source.cache) streamed_.push_back(i);
  if (!streamed_.empty()) {
    std::sort(streamed_.begin(), streamed_.end(), [&](uint32_t x, uint32_t y) {
      const Slot &sx = slots_[x], &sy = slots_[y];
      if (sx.source.cache != sy.source.cache) return std::less<>()(sx.source.cache, sy.source.cache);
      if (sx.source.id != sy.source.id) return sx.source.id < sy.source.id;
      return x < y;
    });
    streamed_.erase(std::unique(streamed_.begin(), streamed_.end()), streamed_.end());
    for (size_t k = 0; k < streamed_.size();) {
      const Slot& first = slots_[streamed_[k]];
      int deepest = 0;
      size_t e = k;
      for (; e < streamed_.size() && slots_[streamed_[e]].source.cache == first.source.cache &&
             slots_[streamed_[e]].source.id == first.source.id;
           ++e)
        deepest = std::max(deepest, slots_[streamed_[e]].depth);
      // A failing decode leaves the levels held before it: the objects are
      // tested at that depth below (still conservative), and the app is told.
      Result<int> got = first.source.cache->require(first.source.id, deepest);
      if (!got) {
        ++stats.stream_errors;
        last_stream_error_ = got.error();
      }
      k = e;
    }
    for (uint32_t i : streamed_) {
      Slot& s = slots_[i];
      const int held = s.source.cache->held_depth(s.source.id);
      if (s.depth > held) {
        s.depth = held;
        s.area_epoch = 0;  // ask again next frame
        ++stats.depth_clamps;
      }
    }
  }
#endif

  // 7. Pair tests, one result slot per pair, merged in pair order.
  run_parallel(n, kPairGrain, range_task([this](size_t b, size_t e) { test_pairs(b, e); }));
  for (size_t k = 0; k < n; ++k) {
    const PairResult& r = results_[k];
    stats.box_tests += r.test.box_tests;
    stats.pairs_reused += r.reused;
    stats.pairs_kept_apart += r.kept_apart;
    if (!r.test.hit) continue;
    // The depths as tested (the record's), the generations from
    // live_generation_: no slot is read here.
    const auto [a, b] = pairs_[k];
    const TestRecord& tested = records_[r.record];
    Contact& c = out.emplace_back();
    c.a = {a, live_generation_[a], id_};
    c.b = {b, live_generation_[b], id_};
    c.depth_a = tested.a.depth;
    c.depth_b = tested.b.depth;
    c.box_tests = r.test.box_tests;
    c.estimate = tested.estimate;
  }
  if (settings_.coherence) {
    last_pairs_.swap(pairs_);
    last_results_.swap(results_);
  }
  stats.contacts = out.size();
  return stats;
}

// ---- queries ----

namespace {

// Ray or shape query inside one object's tree, depth first, children in
// octant order. `visit_leaf` returns true to stop.
struct Node {
  int d;
  uint32_t index, x, y, z;
};

}  // namespace

bool CollisionWorld::ray_leaves(uint32_t i, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_box,
                                double limit, double& local, BoxCoord& hit_box) const {
  const Slot& s = slots_[i];
  const ObjectTree& tree = tree_of(s);
  // Start the local ray where it enters the world box: local coordinates
  // stay small even for objects 1e7 away.
  const Eigen::Vector3d start = origin + dir * t_box;
  const Eigen::Matrix3d rt = rotation_matrix(s.pose.rotation).transpose();
  const Eigen::Vector3d o = rt * (start - s.pose.position) / s.pose.scale;
  const Eigen::Vector3d dl = rt * dir / s.pose.scale;
  const Aabb& root = tree.bounds();
  // Rounding of start, of the transform and of the box corners, in local units.
  const double world_mag = max_abs(origin) + max_abs(s.pose.position) + t_box;
  const double pad =
      kRelativePad * (max_abs_coordinate(root) + max_abs(o)) + kWorldRoundingPad * world_mag / s.pose.scale;
  double local_best = limit;
  bool found = false;
  Node stack[8 * kMaxDepth + 8];
  int top = 0;
  stack[top++] = {0, 0, 0, 0, 0};
  while (top > 0) {
    const Node nd = stack[--top];
    const double t = ray_box(o, dl, node_box(root, nd.d, nd.x, nd.y, nd.z, pad), 0, local_best);
    if (t < 0) continue;
    if (nd.d == s.depth) {
      if (!found || t < local_best) {  // ties: the first in octant order
        local_best = t;
        hit_box = {nd.x, nd.y, nd.z};
        found = true;
      }
      continue;
    }
    const uint8_t m = tree.mask(nd.d, nd.index);
    uint32_t child = tree.first_child(nd.d, nd.index);
    // Push in reverse octant order so octant 0 is visited first.
    Node kids[8];
    int nk = 0;
    for (int j = 0; j < 8; ++j)
      if (m & (1u << j))
        kids[nk++] = {nd.d + 1, child++, 2 * nd.x + (j & 1), 2 * nd.y + ((j >> 1) & 1), 2 * nd.z + ((j >> 2) & 1)};
    for (int k = nk - 1; k >= 0; --k) stack[top++] = kids[k];
  }
  local = local_best;
  return found;
}

namespace {

// The unit direction of a valid ray query, or why it is not one.
Result<Eigen::Vector3d> ray_direction(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                      double max_distance) {
  if (!origin.allFinite() || !direction.allFinite() || !(max_distance >= 0) || std::isnan(max_distance))
    return bad("ray_cast: non-finite origin or direction, or max_distance < 0");
  const double largest = direction.cwiseAbs().maxCoeff();
  if (!(largest > 0)) return bad("ray_cast: zero direction");
  // A direction of 1e-170 or 1e160 is fine, but its squared length under- or
  // overflows: such a one is scaled by its largest component first.
  const Eigen::Vector3d scaled = largest > 1e-100 && largest < 1e100 ? direction : Eigen::Vector3d(direction / largest);
  return Eigen::Vector3d(scaled / scaled.norm());
}

}  // namespace

Result<std::optional<RayHit>> CollisionWorld::ray_cast_scan(const Eigen::Vector3d& origin,
                                                            const Eigen::Vector3d& direction, double max_distance) {
  const Result<Eigen::Vector3d> unit = ray_direction(origin, direction, max_distance);
  if (!unit) return unit.error();
  const Eigen::Vector3d& dir = *unit;
  std::optional<RayHit> best;
  double best_t = max_distance;
  for (uint32_t i = 0; i < slots_.size(); ++i) {
    if (!live(i)) continue;
    const double t_box = ray_box(origin, dir, boxes_[i], 0, best_t);
    if (t_box < 0) continue;
    if (settings_.area_refresh == AreaRefresh::on_demand) refresh_depth(i);
    double local;
    BoxCoord hit_box;
    if (!ray_leaves(i, origin, dir, t_box, best_t - t_box, local, hit_box)) continue;
    const double t = t_box + local;
    if (!best || t < best_t) {
      best_t = t;
      best = RayHit{{i, slots_[i].generation, id_}, t, slots_[i].depth, hit_box};
    }
  }
  return best;
}

// The scan's answer (the nearest hit, ties to the smallest slot) in any visit
// order: the WorldTree's cells along the ray in order of entry, stopping once
// a cell is entered past the best hit (an object in a later cell only is
// entered later still, so it cannot win; one found here may be hit beyond
// this cell, hence no stop at the first hit).
Result<std::optional<RayHit>> CollisionWorld::ray_cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                                       double max_distance) {
  const Result<Eigen::Vector3d> unit = ray_direction(origin, direction, max_distance);
  if (!unit) return unit.error();
  const Eigen::Vector3d& dir = *unit;
  std::optional<RayHit> best;
  double best_t = max_distance;
  const auto consider = [&](uint32_t i) {
    const double t_box = ray_box(origin, dir, boxes_[i], 0, best_t);
    if (t_box < 0) return;  // entered after the best hit: cannot win or tie
    if (settings_.area_refresh == AreaRefresh::on_demand) refresh_depth(i);
    // Search a little past the best hit (rounding of best_t - t_box), so an
    // exact tie with a smaller slot is found whatever came first; never past
    // max_distance, as the scan.
    double limit = best_t - t_box;
    if (best) limit = std::min(max_distance - t_box, limit + 8 * std::numeric_limits<double>::epsilon() * best_t);
    double local;
    BoxCoord hit_box;
    if (!ray_leaves(i, origin, dir, t_box, limit, local, hit_box)) return;
    const double t = t_box + local;
    if (best && !(t < best_t || (t == best_t && i < best->object.slot))) return;
    best_t = t;
    best = RayHit{{i, slots_[i].generation, id_}, t, slots_[i].depth, hit_box};
  };
  if (visit_.size() < slots_.size()) visit_.resize(slots_.size(), 0);
  if (++visit_epoch_ == 0) {  // wrapped: forget every stamp
    std::fill(visit_.begin(), visit_.end(), 0);
    visit_epoch_ = 1;
  }
  const auto once = [&](uint32_t i) {
    if (visit_[i] == visit_epoch_) return false;
    visit_[i] = visit_epoch_;
    return true;
  };
  // Objects moved since the last commit: their tree entries are stale.
  for (uint32_t i : dirty_)
    if (live(i) && slots_[i].tree_dirty && once(i)) consider(i);
  for (uint32_t i : tree_.overflow_ids())
    if (!slots_[i].tree_dirty && once(i)) consider(i);
  WorldTree::RayWalk walk(tree_, origin, dir, max_distance);
  while (walk.next()) {
    if (walk.entry() > best_t) break;
    for (uint32_t i : walk.ids())
      if (!slots_[i].tree_dirty && once(i)) consider(i);
  }
  return best;
}

namespace {

// Does any leaf (at `depth`) of `tree` overlap the local-space shape?
template <class Overlaps>
bool any_leaf(const ObjectTree& tree, int depth, double pad, const Overlaps& overlaps_box) {
  const Aabb& root = tree.bounds();
  Node stack[8 * kMaxDepth + 8];
  int top = 0;
  stack[top++] = {0, 0, 0, 0, 0};
  while (top > 0) {
    const Node nd = stack[--top];
    if (!overlaps_box(node_box(root, nd.d, nd.x, nd.y, nd.z, pad))) continue;
    if (nd.d == depth) return true;
    const uint8_t m = tree.mask(nd.d, nd.index);
    uint32_t child = tree.first_child(nd.d, nd.index);
    for (int j = 0; j < 8; ++j)
      if (m & (1u << j))
        stack[top++] = {nd.d + 1, child++, 2 * nd.x + (j & 1), 2 * nd.y + ((j >> 1) & 1), 2 * nd.z + ((j >> 2) & 1)};
  }
  return false;
}

OrientedBox as_oriented(const Aabb& b) {
  OrientedBox o;
  o.center = 0.5 * (b.min + b.max);
  o.half = 0.5 * (b.max - b.min);
  return o;
}

bool bad_box(const Aabb& box) {
  return !box.min.allFinite() || !box.max.allFinite() || !(box.min.array() <= box.max.array()).all();
}

bool bad_sphere(const Eigen::Vector3d& center, double radius) {
  return !center.allFinite() || !std::isfinite(radius) || !(radius >= 0);
}

}  // namespace

bool CollisionWorld::box_leaves(uint32_t i, const Aabb& box) const {
  const Slot& s = slots_[i];
  // The query box in the object's local frame.
  const Eigen::Matrix3d rt = rotation_matrix(s.pose.rotation).transpose();
  OrientedBox q = as_oriented(box);
  q.center = rt * (q.center - s.pose.position) / s.pose.scale;
  q.axes = rt;
  q.half /= s.pose.scale;
  const Aabb& root = tree_of(s).bounds();
  const double world_mag = max_abs(box.min) + max_abs(box.max) + max_abs(s.pose.position);
  const double pad = kRelativePad * (max_abs_coordinate(root) + max_abs(q.center) + q.half.maxCoeff()) +
                     kWorldRoundingPad * world_mag / s.pose.scale;
  return any_leaf(tree_of(s), s.depth, pad, [&](const Aabb& node) { return sat(as_oriented(node), q).overlap >= 0; });
}

bool CollisionWorld::sphere_leaves(uint32_t i, const Eigen::Vector3d& center, double radius) const {
  const Slot& s = slots_[i];
  const Eigen::Matrix3d rt = rotation_matrix(s.pose.rotation).transpose();
  const Eigen::Vector3d c = rt * (center - s.pose.position) / s.pose.scale;
  const double r = radius / s.pose.scale;
  const Aabb& root = tree_of(s).bounds();
  const double world_mag = max_abs(center) + radius + max_abs(s.pose.position);
  const double pad =
      kRelativePad * (max_abs_coordinate(root) + max_abs(c) + r) + kWorldRoundingPad * world_mag / s.pose.scale;
  return any_leaf(tree_of(s), s.depth, pad, [&](const Aabb& node) {
    const Eigen::Vector3d closest = c.cwiseMax(node.min).cwiseMin(node.max);
    return (closest - c).norm() <= r;
  });
}

void CollisionWorld::query_candidates(const Aabb& box) {
  tree_.query_box(box, query_ids_);
  // Committed objects from the tree; the moved ones by their current box.
  size_t n = 0;
  for (uint32_t i : query_ids_)
    if (!slots_[i].tree_dirty) query_ids_[n++] = i;
  query_ids_.resize(n);
  for (uint32_t i : dirty_)
    if (live(i) && slots_[i].tree_dirty) query_ids_.push_back(i);
  // The two sets are disjoint and dirty_ names a slot once: sorting suffices.
  if (query_ids_.size() > n) std::sort(query_ids_.begin(), query_ids_.end());
}

namespace {
// Slots 0..n-1 as keep_overlapping's ids (std::views::iota does not compile
// with clang 14 and libstdc++ 12, the fuzz build's pair).
struct AllSlots {
  struct Iterator {
    uint32_t i;
    uint32_t operator*() const { return i; }
    Iterator& operator++() { return ++i, *this; }
    bool operator!=(const Iterator& o) const { return i != o.i; }
  };
  uint32_t n;
  Iterator begin() const { return {0}; }
  Iterator end() const { return {n}; }
};
}  // namespace

template <class Ids, class Leaves>
void CollisionWorld::keep_overlapping(const Ids& ids, const Aabb& bounds, Leaves leaves, std::vector<ObjectHandle>& out) {
  for (uint32_t i : ids) {
    if (!live(i) || !overlaps(boxes_[i], bounds)) continue;
    if (settings_.area_refresh == AreaRefresh::on_demand) refresh_depth(i);
    if (leaves(i)) out.push_back({i, slots_[i].generation, id_});
  }
}

Status CollisionWorld::overlap_box(const Aabb& box, std::vector<ObjectHandle>& out) {
  out.clear();
  if (bad_box(box)) return bad("overlap_box: non-finite box or min > max");
  query_candidates(box);
  keep_overlapping(query_ids_, box, [&](uint32_t i) { return box_leaves(i, box); }, out);
  return std::monostate{};
}

Status CollisionWorld::overlap_sphere(const Eigen::Vector3d& center, double radius, std::vector<ObjectHandle>& out) {
  out.clear();
  if (bad_sphere(center, radius)) return bad("overlap_sphere: non-finite center or radius, or radius < 0");
  const Aabb bounds{center.array() - radius, center.array() + radius};
  query_candidates(bounds);
  keep_overlapping(query_ids_, bounds, [&](uint32_t i) { return sphere_leaves(i, center, radius); }, out);
  return std::monostate{};
}

Status CollisionWorld::overlap_box_scan(const Aabb& box, std::vector<ObjectHandle>& out) {
  out.clear();
  if (bad_box(box)) return bad("overlap_box: non-finite box or min > max");
  keep_overlapping(AllSlots{uint32_t(slots_.size())}, box,
                   [&](uint32_t i) { return box_leaves(i, box); }, out);
  return std::monostate{};
}

Status CollisionWorld::overlap_sphere_scan(const Eigen::Vector3d& center, double radius, std::vector<ObjectHandle>& out) {
  out.clear();
  if (bad_sphere(center, radius)) return bad("overlap_sphere: non-finite center or radius, or radius < 0");
  const Aabb bounds{center.array() - radius, center.array() + radius};
  keep_overlapping(AllSlots{uint32_t(slots_.size())}, bounds,
                   [&](uint32_t i) { return sphere_leaves(i, center, radius); }, out);
  return std::monostate{};
}

}  // namespace octbake

// Shared pieces of the CollisionWorld tests: random trees, random poses, an
// independent box-box separating axis test, and brute force over leaf boxes.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "baked_test_util.h"
#include "octbake/collision_world.h"
#include "seeded_random.h"

namespace octbake::test {

#if defined(__SANITIZE_ADDRESS__) || !defined(NDEBUG)
constexpr int kWork = 1;  // sanitizer / debug builds: a tenth of the steps
#else
constexpr int kWork = 10;
#endif

// An executor that runs the ranges in reverse order, one item at a time:
// results must not depend on scheduling.
class Backwards final : public Executor {
 public:
  void parallel_for(size_t count, size_t, RangeTask task) override {
    ++calls;
    for (size_t i = count; i-- > 0;) task(i, i + 1);
  }
  int calls = 0;
};

inline ObjectTree make_tree(OctreeMasks m) {
  TreeInfo info;
  info.bounds = m.bounds;
  info.depth = m.depth();
  return ObjectTree(std::move(info), std::move(m));
}

// Sparse random trees, root boxes up to 20 wide.
inline std::vector<ObjectTree> random_trees(std::mt19937& rng, int count) {
  std::vector<ObjectTree> trees;
  for (int i = 0; i < count; ++i) trees.push_back(make_tree(random_masks(rng, 2 + i % 4, 0.75, 600)));
  return trees;
}

inline Eigen::Quaterniond maybe_rotation(std::mt19937& rng) {
  return below(rng, 4) == 0 ? Eigen::Quaterniond::Identity() : random_rotation(rng);
}

// Least overlap of two oriented boxes over the 15 axes (< 0: separated).
// Written independently of the library's.
inline double sat_overlap(const OrientedBox& a, const OrientedBox& b) {
  double best = INFINITY;
  const Eigen::Vector3d t = b.center - a.center;
  std::vector<Eigen::Vector3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.axes.col(i)), axes.push_back(b.axes.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) axes.push_back(a.axes.col(i).cross(b.axes.col(j)));
  for (Eigen::Vector3d l : axes) {
    if (l.norm() < 1e-9) continue;
    l.normalize();
    double ra = 0, rb = 0;
    for (int k = 0; k < 3; ++k) ra += a.half[k] * std::abs(a.axes.col(k).dot(l)), rb += b.half[k] * std::abs(b.axes.col(k).dot(l));
    best = std::min(best, ra + rb - std::abs(t.dot(l)));
  }
  return best;
}

inline OrientedBox inflate(OrientedBox b, double by) {
  b.half.array() += by;
  return b;
}

// Entry distance of a ray (unit dir) into an oriented box, < 0 for a miss.
inline double ray_obb(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const OrientedBox& b, double max_t) {
  const Eigen::Vector3d lo = b.axes.transpose() * (o - b.center), ld = b.axes.transpose() * d;
  double t0 = 0, t1 = max_t;
  for (int k = 0; k < 3; ++k) {
    if (ld[k] == 0) {
      if (std::abs(lo[k]) > b.half[k]) return -1;
      continue;
    }
    double ta = (-b.half[k] - lo[k]) / ld[k], tb = (b.half[k] - lo[k]) / ld[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return -1;
  }
  return t0;
}

// Every leaf box of an object at `depth`, in the world.
inline std::vector<OrientedBox> world_leaves(const ObjectTree& tree, const Pose& pose, int depth) {
  std::vector<OrientedBox> out;
  for (const BoxCoord& c : tree.masks().boxes(depth)) out.push_back(leaf_box({&tree, pose, depth}, c));
  return out;
}

// The items of a set_poses batch in a random order.
inline void shuffle_batch(std::vector<ObjectHandle>& handles, std::vector<Pose>& poses, std::mt19937& rng) {
  std::vector<size_t> order(handles.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<ObjectHandle> h;
  std::vector<Pose> p;
  for (size_t k : order) h.push_back(handles[k]), p.push_back(poses[k]);
  handles.swap(h), poses.swap(p);
}

// A set_poses of every object, each moved up to 3 (cells are ~1.3 wide) and
// a tenth turned, that the world must refuse, naming the bad item: by turns
// a bad scale on the last item, a stale handle three quarters in, and a bad
// position in a shuffled batch (which takes the duplicate pass first).
inline void send_refused_batch(CollisionWorld& world, const std::vector<ObjectHandle>& handles,
                               const std::vector<Pose>& poses, int frame, std::mt19937& rng) {
  std::vector<ObjectHandle> h = handles;
  std::vector<Pose> p = poses;
  for (Pose& pose : p) {
    pose.position += random_point(rng, -3, 3);
    if (below(rng, 10) == 0) pose.rotation = random_rotation(rng);
  }
  size_t bad = h.size() - 1;
  std::string why = "scale must be finite and > 0";
  switch (frame % 3) {
    case 0:
      p[bad].scale = 0;
      break;
    case 1:
      bad = h.size() * 3 / 4;
      ++h[bad].generation;
      why = "handle: object was destroyed";
      break;
    default:
      shuffle_batch(h, p, rng);
      bad = h.size() - 2;
      p[bad].position.y() = std::numeric_limits<double>::quiet_NaN();
      why = "position is not finite";
  }
  const Status st = world.set_poses(h, p);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("item " + std::to_string(bad) + ": "), std::string::npos) << st.error().message;
  EXPECT_NE(st.error().message.find(why), std::string::npos) << st.error().message;
}

// A crowd of `n` objects (4 random trees) in a cube, for `frames` frames: a
// third move each frame (a tenth of them turn), the camera moves two frames
// in three, every 4th frame a few are destroyed and created again (their
// slots reused) and moved before their first detect, and every 5th frame a
// few are moved halfway first (so they wait in the WorldTree's list when the
// frame's poses arrive).
// Poses go in by one set_poses (batch) or a set_pose loop. Returns a hash of
// every frame's contacts (all fields), stats and WorldTree counts (cells in
// use, reinsertions), for comparing runs. With
// `refused_batches`, each frame's poses follow a set_poses that must be
// refused (a bad pose or handle late in a batch that moves every object, in
// handle order or shuffled): the hash must not change.
inline uint64_t crowd_hash(int n, int frames, int threads, bool batch, Executor* executor = nullptr,
                           LodPolicy policy = LodPolicy::screen, AreaRefresh refresh = AreaRefresh::on_demand,
                           bool refused_batches = false) {
  std::mt19937 rng(11), refused_rng(13);
  const std::vector<ObjectTree> trees = random_trees(rng, 4);
  const double side = 2.5 * std::cbrt(double(n));
  CollisionSettings s;
  s.bounds = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(side)};
  s.world_depth = 5;
  s.lod.policy = policy;
  s.lod.max_depth = 5;
  s.area_refresh = refresh;
  s.threads = threads;
  s.executor = executor;
  CollisionWorld world(s);
  std::vector<ObjectHandle> handles;
  std::vector<Pose> poses;
  const auto random_pose = [&] {
    Pose p;
    p.position = random_point(rng, 0, side);
    p.rotation = maybe_rotation(rng);
    p.scale = uniform(rng, 0.05, 0.12);
    return p;
  };
  for (int i = 0; i < n; ++i) {
    poses.push_back(random_pose());
    handles.push_back(world.create(TreeSource::fixed(&trees[size_t(i) % trees.size()]), poses.back()).value());
  }
  uint64_t hash = 1469598103934665603ull;
  const auto mix = [&](const auto& v) {
    unsigned char b[sizeof(v)];
    std::memcpy(b, &v, sizeof(v));
    for (unsigned char c : b) hash = (hash ^ c) * 1099511628211ull;
  };
  std::vector<Contact> contacts;
  uint64_t total_contacts = 0;
  Eigen::Vector3d camera_jitter = Eigen::Vector3d::Zero();
  for (int f = 0; f < frames; ++f) {
    for (size_t i = 0; i < poses.size(); ++i) {
      if (below(rng, 3) != 0) continue;
      poses[i].position += random_point(rng, -0.3, 0.3);
      if (below(rng, 10) == 0) poses[i].rotation = random_rotation(rng);
    }
    if (f % 4 == 3)
      for (int k = 0; k < 3; ++k) {
        const size_t i = below(rng, uint32_t(handles.size()));
        EXPECT_TRUE(world.destroy(handles[i]).ok());
        poses[i] = random_pose();
        handles[i] = world.create(TreeSource::fixed(&trees[i % trees.size()]), poses[i]).value();
        poses[i].position.x() += 0.2;  // moved again before its first detect
      }
    // Some objects already moved this frame (listed for the WorldTree)
    // before the frame's poses arrive.
    if (f % 5 == 1)
      for (int k = 0; k < 20; ++k) {
        const size_t i = below(rng, uint32_t(handles.size()));
        Pose midway = poses[i];
        midway.position.y() -= 0.7;
        EXPECT_TRUE(world.set_pose(handles[i], midway).ok());
      }
    if (refused_batches) send_refused_batch(world, handles, poses, f, refused_rng);
    if (batch) {
      EXPECT_TRUE(world.set_poses(handles, poses).ok());
    } else {
      for (size_t i = 0; i < handles.size(); ++i) EXPECT_TRUE(world.set_pose(handles[i], poses[i]).ok());
    }
    // The camera stays put one frame in three: areas then stay current.
    if (f % 3 != 2) camera_jitter = random_point(rng, -1, 1);
    Camera camera;
    camera.position = Eigen::Vector3d(side / 2, side / 2, -side) + camera_jitter;
    camera.look_at = Eigen::Vector3d::Constant(side / 2);
    world.set_camera(camera);
    const DetectStats st = world.detect(contacts);
    mix(st.candidate_pairs), mix(st.box_tests), mix(st.contacts), mix(st.area_computations);
    mix(world.world_tree().cells_in_use()), mix(world.world_tree().reinsertions());
    total_contacts += st.contacts;
    for (const Contact& c : contacts) {
      mix(c.a.slot), mix(c.a.generation), mix(c.b.slot), mix(c.b.generation), mix(c.depth_a), mix(c.depth_b);
      mix(c.box_tests), mix(c.estimate.normal), mix(c.estimate.penetration), mix(c.estimate.overlap);
    }
    for (const ObjectHandle& h : handles) mix(world.bounds(h));
  }
  EXPECT_GT(total_contacts, uint64_t(frames));  // a crowd that touches
  // and whose pair scan goes parallel on threads (it runs inline in small worlds)
  EXPECT_GE(world.size(), CollisionWorld::kParallelScanObjects);
  return hash;
}

}  // namespace octbake::test

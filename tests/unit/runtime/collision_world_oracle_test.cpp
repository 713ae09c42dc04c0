// CollisionWorld::detect against brute force: random sequences of create /
// destroy / set_pose / set_camera / set_lod, every frame's contacts equal to
// collide() on every pair of live objects at the depths the world chose, and
// those depths equal to choose_depths over freshly computed pixel areas.
#if defined(__linux__)
#include <sched.h>
#endif
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <set>

#include "collision_world_util.h"

namespace octbake {
namespace {

using test::Backwards;
using test::below;
using test::kWork;
using test::uniform;

struct Totals {
  uint64_t frames = 0, pair_tests = 0, pairs_reused = 0, contacts = 0, far_contacts = 0, outside_contacts = 0, skipped_depths = 0;
  uint64_t hash = 1469598103934665603ull;
  template <class T>
  void mix(const T& v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (unsigned char c : b) hash = (hash ^ c) * 1099511628211ull;
  }
};

// A world of random trees driven by random calls. `check` runs the oracles
// every frame (else only the hash of the results is kept).
class Driver {
 public:
  // With `coherence` the box-test counts depend on the previous frame's
  // contacts, so the oracle compares them only without it.
  Driver(uint32_t seed, int threads, Executor* executor, bool coherence = true)
      : rng_(seed), trees_(test::random_trees(rng_, 5)), coherence_(coherence) {
    CollisionSettings s;
    s.coherence = coherence;
    s.bounds = {Eigen::Vector3d::Constant(-10), Eigen::Vector3d::Constant(10)};
    s.world_depth = 3;
    s.lod.policy = LodPolicy::screen;
    s.lod.max_depth = 5;
    s.lod.pixel_tolerance = 4;
    s.threads = threads;
    s.executor = executor;
    world_ = std::make_unique<CollisionWorld>(s);
  }

  Pose random_pose() {
    Pose p;
    const uint32_t where = below(rng_, 10);
    if (where == 0)
      // Outside the world box [-10, 10]^3: just beyond a face, or far away.
      p.position = (below(rng_, 2) ? Eigen::Vector3d(14, 0, 0) : Eigen::Vector3d(-45, 45, -45)) +
                   test::random_point(rng_, -2, 2);
    else if (where == 1)
      p.position = Eigen::Vector3d(1e7, -1e7, 1e7) + test::random_point(rng_, -2, 2);  // huge offset
    else
      p.position = test::random_point(rng_, -6, 6);
    p.rotation = test::maybe_rotation(rng_);
    p.scale = uniform(rng_, 0.05, 0.15);
    return p;
  }

  void random_calls() {
    const int calls = 1 + int(below(rng_, 4));
    for (int k = 0; k < calls; ++k) {
      const uint32_t op = below(rng_, 10);
      if ((op < 2 && live_.size() < 40) || live_.size() < 3) {
        const ObjectTree* t = &trees_[below(rng_, uint32_t(trees_.size()))];
        Result<ObjectHandle> h = world_->create(TreeSource::fixed(t), random_pose());
        ASSERT_TRUE(h.ok());
        live_.push_back(*h);
        tree_of_[h->slot] = t;
      } else if (op == 2) {
        const size_t i = below(rng_, uint32_t(live_.size()));
        ASSERT_TRUE(world_->destroy(live_[i]).ok());
        live_.erase(live_.begin() + ptrdiff_t(i));
      } else {
        const ObjectHandle h = live_[below(rng_, uint32_t(live_.size()))];
        Pose p = world_->pose(h).value();
        if (below(rng_, 3) == 0) {
          p = random_pose();
        } else {
          p.position += test::random_point(rng_, -0.4, 0.4);
          if (below(rng_, 2) == 0) p.rotation = test::random_rotation(rng_);
        }
        ASSERT_TRUE(world_->set_pose(h, p).ok());
      }
    }
    if (below(rng_, 10) != 0) {  // the camera moves most frames
      Camera c;
      c.position = test::random_point(rng_, -40, 40);
      c.look_at = test::random_point(rng_, -5, 5);
      world_->set_camera(c);
    }
    if (below(rng_, 50) == 0) {
      LodSettings lod;
      lod.policy = LodPolicy(below(rng_, 3));
      lod.min_depth = int(below(rng_, 3));
      lod.max_depth = lod.min_depth + int(below(rng_, 4));
      // Now and then an infinite tolerance: every depth the shallowest.
      lod.pixel_tolerance = below(rng_, 4) == 0 ? std::numeric_limits<double>::infinity() : uniform(rng_, 0.5, 8);
      ASSERT_TRUE(world_->set_lod(lod).ok());
    }
  }

  PlacedTree placed(ObjectHandle h, int depth) { return {tree_of_[h.slot], world_->pose(h).value(), depth}; }

  // Is `box` exactly the box of `p`'s tree at p.depth that holds its centre?
  // A contact's estimate must be made of its own objects' leaves at the
  // depths tested (not, say, another pair's, kept from an earlier frame).
  static bool is_leaf_of(const OrientedBox& box, const PlacedTree& p) {
    const Eigen::Vector3d local = p.pose.rotation.conjugate() * (box.center - p.pose.position) / p.pose.scale;
    const Aabb& bounds = p.tree->bounds();
    const double side = double(1 << p.depth);
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
      const double extent = bounds.max[k] - bounds.min[k];
      const double t = extent > 0 ? std::floor((local[k] - bounds.min[k]) / extent * side) : 0;
      c[k] = uint32_t(std::clamp(t, 0.0, side - 1));
    }
    const OrientedBox leaf = leaf_box(p, BoxCoord{c[0], c[1], c[2]});
    return leaf.center == box.center && leaf.axes == box.axes && leaf.half == box.half;
  }

  void frame(bool check, Totals& totals) {
    ASSERT_NO_FATAL_FAILURE(random_calls());
    const DetectStats stats = world_->detect(contacts_);
    // Pair records are freed with their pairs: the pool never outgrows the
    // pair tests of two consecutive frames.
    most_pairs_ = std::max(most_pairs_, last_pair_tests_ + stats.pair_tests);
    last_pair_tests_ = stats.pair_tests;
    EXPECT_LE(world_->pair_records(), most_pairs_) << "frame " << totals.frames;
    ++totals.frames;
    totals.pair_tests += stats.pair_tests;
    totals.pairs_reused += stats.pairs_reused;
    totals.contacts += stats.contacts;
    for (const Contact& c : contacts_) {
      totals.mix(c.a.slot), totals.mix(c.a.generation), totals.mix(c.b.slot), totals.mix(c.b.generation), totals.mix(c.depth_a), totals.mix(c.depth_b), totals.mix(c.box_tests);
      totals.mix(c.estimate.normal), totals.mix(c.estimate.penetration), totals.mix(c.estimate.overlap);
    }
    totals.mix(stats.box_tests), totals.mix(stats.area_computations), totals.mix(stats.pairs_reused);
    if (!check) return;

    std::vector<ObjectHandle> sorted = live_;
    std::sort(sorted.begin(), sorted.end(), [](auto x, auto y) { return x.slot < y.slot; });
    ASSERT_EQ(stats.objects, sorted.size());

    // Depths of the objects in candidate pairs (world AABBs overlap) whose
    // root boxes are not apart are choose_depths over fresh pixel areas, read
    // before anything refreshes (a pair whose roots are apart may skip them).
    std::set<uint32_t> in_pairs, needed;
    uint64_t candidates = 0;
    for (size_t i = 0; i < sorted.size(); ++i)
      for (size_t j = i + 1; j < sorted.size(); ++j) {
        const Aabb &a = world_->bounds(sorted[i]), &b = world_->bounds(sorted[j]);
        if (!((a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all())) continue;
        in_pairs.insert(sorted[i].slot), in_pairs.insert(sorted[j].slot), ++candidates;
        if (!roots_apart(placed(sorted[i], 0), placed(sorted[j], 0)))
          needed.insert(sorted[i].slot), needed.insert(sorted[j].slot);
      }
    ASSERT_EQ(stats.candidate_pairs, candidates);
    const LodSettings& lod = world_->lod();
    std::vector<double> areas;
    std::vector<int> max_depths;
    for (ObjectHandle h : sorted) {
      areas.push_back(pixel_area(world_->camera(), place(tree_of_[h.slot]->bounds(), world_->pose(h).value())));
      max_depths.push_back(tree_of_[h.slot]->loaded_depth());
    }
    const std::vector<int> expected = choose_depths(lod, areas, max_depths);
    for (size_t i = 0; i < sorted.size(); ++i)
      if (needed.count(sorted[i].slot)) {
        ASSERT_EQ(world_->cached_depth(sorted[i]), expected[i]) << "slot " << sorted[i].slot;
      }
    totals.skipped_depths += in_pairs.size() - needed.size();
    if (lod.policy == LodPolicy::fixed) {
      EXPECT_EQ(stats.area_computations, 0u);
    } else if (lod.policy == LodPolicy::screen) {
      EXPECT_LE(stats.area_computations, in_pairs.size());
    } else {
      EXPECT_LE(stats.area_computations, sorted.size());
    }

    // Contacts: collide() on every live pair at the chosen depths; without
    // coherence, the box tests of the candidate pairs too.
    std::vector<std::tuple<uint32_t, uint32_t, int, int, uint64_t>> want, got;
    uint64_t box_tests = 0;
    for (size_t i = 0; i < sorted.size(); ++i)
      for (size_t j = i + 1; j < sorted.size(); ++j) {
        const int da = world_->depth(sorted[i]).value(), db = world_->depth(sorted[j]).value();
        const PairTest t = collide(placed(sorted[i], da), placed(sorted[j], db));
        if (t.hit) want.emplace_back(sorted[i].slot, sorted[j].slot, da, db, coherence_ ? 0 : t.box_tests);
        const Aabb &a = world_->bounds(sorted[i]), &b = world_->bounds(sorted[j]);
        if ((a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all()) box_tests += t.box_tests;
      }
    if (!coherence_) {
      EXPECT_EQ(stats.box_tests, box_tests) << "frame " << totals.frames;
      EXPECT_EQ(stats.pairs_reused, 0u);
    }
    for (const Contact& c : contacts_) {
      got.emplace_back(c.a.slot, c.b.slot, c.depth_a, c.depth_b, coherence_ ? 0 : c.box_tests);
      ASSERT_TRUE(world_->alive(c.a) && world_->alive(c.b));
      if (world_->pose(c.a)->position.x() > 1e6) ++totals.far_contacts;
      const Eigen::Vector3d pa = world_->pose(c.a)->position;
      if (pa.cwiseAbs().maxCoeff() > 11 && pa.cwiseAbs().maxCoeff() < 1e6) ++totals.outside_contacts;
      // The estimate: two overlapping leaves; moving b by normal * penetration
      // (a hair more) separates them.
      const ContactEstimate& e = c.estimate;
      EXPECT_TRUE(is_leaf_of(e.leaf_a, placed(c.a, c.depth_a))) << "frame " << totals.frames;
      EXPECT_TRUE(is_leaf_of(e.leaf_b, placed(c.b, c.depth_b))) << "frame " << totals.frames;
      EXPECT_NEAR(e.normal.norm(), 1.0, 1e-12);
      EXPECT_GE(e.penetration, 0.0);
      const double size = e.leaf_a.half.maxCoeff() + e.leaf_b.half.maxCoeff();
      EXPECT_GE(test::sat_overlap(e.leaf_a, e.leaf_b), -1e-6 * size);
      OrientedBox moved = e.leaf_b;
      moved.center += e.normal * (e.penetration + 1e-6 * size);
      EXPECT_LE(test::sat_overlap(e.leaf_a, moved), 1e-9 * (size + moved.center.cwiseAbs().maxCoeff()));
      EXPECT_TRUE((e.overlap.min.array() <= e.overlap.max.array()).all());
    }
    ASSERT_EQ(got, want) << "frame " << totals.frames;
  }

  CollisionWorld& world() { return *world_; }

 private:
  std::mt19937 rng_;
  std::vector<ObjectTree> trees_;
  bool coherence_ = true;
  uint64_t last_pair_tests_ = 0, most_pairs_ = 0;
  std::unique_ptr<CollisionWorld> world_;
  std::vector<ObjectHandle> live_;
  std::map<uint32_t, const ObjectTree*> tree_of_;
  std::vector<Contact> contacts_;
};

TEST(CollisionWorldOracle, RandomCallsGiveBruteForceContactsEveryFrame) {
  Totals totals;
  for (uint32_t seed : {1u, 2u, 3u, 4u}) {
    Driver d(seed, 1, nullptr, /*coherence=*/seed % 2 == 0);
    for (int f = 0; f < 100 * kWork; ++f) {
      ASSERT_NO_FATAL_FAILURE(d.frame(true, totals));
    }
  }
  // Not vacuous: a good share of the tested pairs hit, including objects
  // outside the world box and at 1e7.
  const double rate = double(totals.contacts) / double(totals.pair_tests);
  EXPECT_GT(rate, 0.3);
  EXPECT_LT(rate, 0.7);
  EXPECT_GT(totals.far_contacts, 0u);
  EXPECT_GT(totals.outside_contacts, 0u);
  EXPECT_GT(totals.skipped_depths, 0u);  // objects only in pairs whose roots are apart
  // With coherence (seeds 2 and 4), pairs whose objects kept their poses and
  // depths answer from last frame, and still equal brute force above.
  EXPECT_GT(totals.pairs_reused, totals.pair_tests / 20);
  std::printf("frames %llu, pair tests %llu (reused %llu), contacts %llu (far %llu, outside %llu), depths not needed %llu\n",
              (unsigned long long)totals.frames, (unsigned long long)totals.pair_tests,
              (unsigned long long)totals.pairs_reused, (unsigned long long)totals.contacts, (unsigned long long)totals.far_contacts,
              (unsigned long long)totals.outside_contacts, (unsigned long long)totals.skipped_depths);
}

TEST(CollisionWorldOracle, BitIdenticalAcrossRepeatsThreadCountsAndExecutors) {
  auto run = [](int threads, Executor* executor) {
    Totals t;
    Driver d(7, threads, executor);
    for (int f = 0; f < 50 * kWork; ++f) d.frame(false, t);
    EXPECT_GT(t.contacts, 0u);
    return t.hash;
  };
  const uint64_t reference = run(1, nullptr);
  EXPECT_EQ(run(1, nullptr), reference);
  for (int threads : {2, 3, 8}) EXPECT_EQ(run(threads, nullptr), reference) << threads << " threads";
  Backwards backwards;
  EXPECT_EQ(run(1, &backwards), reference);
  EXPECT_GT(backwards.calls, 0);
}

#if defined(__linux__)
// The default thread count follows the process's CPU affinity (taskset, a
// container's cpuset), not the machine's core count.
TEST(CollisionWorldOracle, UsableCoresFollowTheCpuAffinity) {
  cpu_set_t before;
  ASSERT_EQ(sched_getaffinity(0, sizeof before, &before), 0);
  EXPECT_EQ(usable_cores(), CPU_COUNT(&before));
  int first = 0;
  while (!CPU_ISSET(first, &before)) ++first;
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(first, &one);
  ASSERT_EQ(sched_setaffinity(0, sizeof one, &one), 0);
  const int pinned = usable_cores();
  ASSERT_EQ(sched_setaffinity(0, sizeof before, &before), 0);
  EXPECT_EQ(pinned, 1);
  EXPECT_GE(usable_cores(), 1);
}
#endif

TEST(CollisionWorldOracle, ThreadPoolCoversEveryItemOnce) {
  for (int threads : {1, 2, 3, 8}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    // Fewer chunks than threads (15 items: 3 chunks of 7), shares of one
    // chunk, uneven shares.
    for (size_t count : {size_t{0}, size_t{1}, size_t{8}, size_t{15}, size_t{63}, size_t{64}, size_t{1000}}) {
      std::vector<std::atomic<int>> seen(count);
      std::atomic<int> bad_chunks{0};
      struct Ctx {
        std::vector<std::atomic<int>>* seen;
        std::atomic<int>* bad_chunks;
      } ctx{&seen, &bad_chunks};
      pool.parallel_for(count, 7, {[](const void* c, size_t b, size_t e) {
                                     const Ctx& x = *static_cast<const Ctx*>(c);
                                     // On workers, whole chunks: from a multiple of the grain, at most
                                     // a grain long (inline: one call for everything).
                                     if (b % 7 != 0 || e <= b || e - b > 7) ++*x.bad_chunks;
                                     for (size_t i = b; i < e; ++i) (*x.seen)[i]++;
                                   },
                                   &ctx});
      if (threads > 1 && count > 7) {
        EXPECT_EQ(bad_chunks.load(), 0) << threads << " threads, " << count << " items";
      }
      for (size_t i = 0; i < count; ++i) ASSERT_EQ(seen[i].load(), 1) << threads << " threads, item " << i;
    }
  }
}

// Cubes of edge 2^-10 (and 1) in a row at the origin, 1e6 and 1e7: cubes that
// touch (exactly, in doubles) are a candidate pair and a contact at every
// depth; cubes 1/16 of an edge apart are neither, however far out (the world
// boxes' padding for rounding must not swallow small objects).
TEST(CollisionWorldOracle, TinyCubesFarOutAreCandidatesOnlyWhenNear) {
  OctreeMasks m;
  m.bounds = {Eigen::Vector3d::Constant(-0.5), Eigen::Vector3d::Constant(0.5)};
  for (int d = 0; d < 4; ++d) m.masks.emplace_back(size_t(1) << (3 * d), uint8_t{0xFF});
  const ObjectTree cube = test::make_tree(std::move(m));
  for (double offset : {0.0, 1e6, 1e7})
    for (double edge : {std::ldexp(1.0, -10), 1.0})
      for (int depth = 0; depth <= 4; ++depth) {
        CollisionSettings s;
        s.bounds = {Eigen::Vector3d::Constant(offset - 1), Eigen::Vector3d::Constant(offset + 1)};
        s.lod.policy = LodPolicy::fixed;
        s.lod.min_depth = 0;
        s.lod.max_depth = depth;
        CollisionWorld world(s);
        // Along x: 0 and 1 touch, 2 is a gap past 1; 3 is a gap above 0 (and 1).
        const double gap = edge / 16;
        const double xs[3] = {offset, offset + edge, offset + 2 * edge + gap};
        std::vector<ObjectHandle> h;
        for (double x : xs) {
          Pose p;
          p.position = {x, offset, offset};
          p.scale = edge;
          h.push_back(world.create(TreeSource::fixed(&cube), p).value());
        }
        Pose above;  // over cube 0, one gap up
        above.position = {offset, offset + edge + gap, offset};
        above.scale = edge;
        h.push_back(world.create(TreeSource::fixed(&cube), above).value());
        std::vector<Contact> contacts;
        const DetectStats st = world.detect(contacts);
        SCOPED_TRACE(testing::Message() << "offset " << offset << ", edge " << edge << ", depth " << depth);
        EXPECT_EQ(st.candidate_pairs, 1u);
        ASSERT_EQ(contacts.size(), 1u);
        EXPECT_EQ(contacts[0].a.slot, h[0].slot);
        EXPECT_EQ(contacts[0].b.slot, h[1].slot);
        EXPECT_EQ(contacts[0].depth_a, depth);
      }
}

}  // namespace
}  // namespace octbake

namespace octbake {
namespace {

// The overlap of two oriented boxes along one unit axis.
double overlap_along(const OrientedBox& a, const OrientedBox& b, const Eigen::Vector3d& n) {
  const double ra = (a.axes.transpose() * n).cwiseAbs().dot(a.half);
  const double rb = (b.axes.transpose() * n).cwiseAbs().dot(b.half);
  return ra + rb - std::abs((b.center - a.center).dot(n));
}

// estimate_contact against the independent separating axis test: the axis it
// names is one of least overlap, points from a to b, and that overlap is the
// penetration; on boxes from thin to wide, axis-aligned, nearly parallel and
// rotated, at the origin and at 1e6.
TEST(EstimateContact, NamesTheAxisOfLeastOverlapOfAnIndependentSat) {
  std::mt19937 rng(11);
  int overlapping = 0, edge_axes = 0;
  for (int k = 0; k < 20000 * kWork / 10; ++k) {
    const double offset = k % 2 ? 1e6 : 0;
    OrientedBox a, b;
    a.center = Eigen::Vector3d::Constant(offset) + test::random_point(rng, -1, 1);
    b.center = a.center + test::random_point(rng, -3, 3);
    for (int i = 0; i < 3; ++i) {
      a.half[i] = below(rng, 8) == 0 ? 0.0 : uniform(rng, 1e-3, 2);
      b.half[i] = below(rng, 8) == 0 ? 0.0 : uniform(rng, 1e-3, 2);
    }
    const Eigen::Quaterniond qa = below(rng, 4) == 0 ? Eigen::Quaterniond::Identity() : test::random_rotation(rng);
    const int kind = below(rng, 3);  // b: aligned with a, almost aligned, rotated
    const Eigen::Quaterniond qb = kind == 0   ? qa
                                  : kind == 1 ? qa * Eigen::Quaterniond(Eigen::AngleAxisd(1e-12, Eigen::Vector3d::UnitX()))
                                              : test::random_rotation(rng);
    a.axes = qa.toRotationMatrix();
    b.axes = qb.toRotationMatrix();
    const double size = a.half.maxCoeff() + b.half.maxCoeff() + 1e-3;
    const double tol = 1e-9 * (size + offset * 1e-6);
    const double least = test::sat_overlap(a, b);
    const ContactEstimate e = estimate_contact(a, b);
    ASSERT_NEAR(e.normal.norm(), 1.0, 1e-12) << k;
    ASSERT_NEAR(e.penetration, std::max(0.0, least), tol) << k;
    // The named axis is a least-overlap axis and points from a towards b.
    ASSERT_NEAR(overlap_along(a, b, e.normal), least, tol) << k;
    ASSERT_GE(e.normal.dot(b.center - a.center), -tol) << k;
    edge_axes += std::abs(e.normal.dot(a.axes.col(0))) < 0.999 && std::abs(e.normal.dot(a.axes.col(1))) < 0.999 &&
                 std::abs(e.normal.dot(a.axes.col(2))) < 0.999 && std::abs(e.normal.dot(b.axes.col(0))) < 0.999 &&
                 std::abs(e.normal.dot(b.axes.col(1))) < 0.999 && std::abs(e.normal.dot(b.axes.col(2))) < 0.999;
    if (least <= 0) continue;
    ++overlapping;
    OrientedBox moved = b;
    moved.center += e.normal * (e.penetration + 1e-6 * size);
    ASSERT_LE(test::sat_overlap(a, moved), tol) << k;
  }
  // Not vacuous: many pairs overlap, and some are decided on edge axes.
  EXPECT_GT(overlapping, 20000 * kWork / 10 / 5);
  EXPECT_GT(edge_axes, 20);
}

}  // namespace
}  // namespace octbake

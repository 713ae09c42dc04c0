// plan_world_depth (what `octscene plan` suggests as the WorldTree depth):
// its counts against a real WorldTree and brute force, its expected cell
// changes against the average over random starting points, and the
// suggestion's rule.
#include "world_depth.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "../../seeded_random.h"
#include "helpers.h"
#include "octbake/baked_file.h"
#include "octbake/pose.h"
#include "octbake/world.h"
#include "octbake/world_tree.h"
#include "run.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;
const std::string kOctscene = OCTSCENE_BIN;
using octbake::test::random_point;
using octbake::test::random_rotation;
using octbake::test::uniform;
using octbake::test::uniform01;

const Aabb kWorld{{-50, -20, -30}, {50, 40, 70}};

// Boxes whose sizes span ~1000x (log-uniform), some reaching out of the world
// and a few large enough to overflow deep grids; `next` moves and grows each a little.
void random_boxes(std::mt19937& rng, size_t n, std::vector<Aabb>& now, std::vector<Aabb>& next) {
  now.clear(), next.clear();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d centre = random_point(rng, -60, 80);
    Eigen::Vector3d half;
    for (int k = 0; k < 3; ++k) half[k] = 0.02 * std::pow(1000.0, uniform01(rng)) * uniform(rng, 0.5, 1.5);
    now.push_back({centre - half, centre + half});
    const Eigen::Vector3d shift = random_point(rng, -1, 1), grow = random_point(rng, 0, 0.2);
    next.push_back({centre + shift - half - grow, centre + shift + half + grow});
  }
}

TEST(WorldDepth, CountsMatchAWorldTreeAndBruteForce) {
  std::mt19937 rng(11);
  std::vector<Aabb> now, next;
  for (int round = 0; round < 4; ++round) {
    random_boxes(rng, 300, now, next);
    const WorldDepthPlan plan = plan_world_depth(kWorld, now, next);
    ASSERT_EQ(plan.depths.size(), 11u);
    for (const WorldDepthCost& c : plan.depths) {
      SCOPED_TRACE("depth " + std::to_string(c.depth));
      WorldTree tree(kWorld, c.depth);
      std::vector<WorldTree::CellRange> ranges;
      uint64_t overflow = 0, memberships = 0;
      std::map<uint64_t, uint64_t> occupants;  // packed cell -> objects
      for (uint32_t i = 0; i < now.size(); ++i) {
        tree.update(i, now[i]);
        const WorldTree::CellRange r = tree.cell_range(now[i]);
        ranges.push_back(r);
        if (tree.in_overflow(i)) {
          ++overflow;
          continue;
        }
        for (uint64_t z = r.lo[2]; z <= r.hi[2]; ++z)
          for (uint64_t y = r.lo[1]; y <= r.hi[1]; ++y)
            for (uint64_t x = r.lo[0]; x <= r.hi[0]; ++x, ++memberships) ++occupants[x | y << 16 | z << 32];
      }
      // Pairs sharing a cell, once per shared cell: the ranges' intersections.
      uint64_t pairs = 0;
      for (size_t i = 0; i < now.size(); ++i)
        for (size_t j = i + 1; j < now.size(); ++j) {
          if (ranges[i].overflow || ranges[j].overflow) continue;
          uint64_t shared = 1;
          for (int k = 0; k < 3; ++k) {
            const int lo = std::max(ranges[i].lo[k], ranges[j].lo[k]), hi = std::min(ranges[i].hi[k], ranges[j].hi[k]);
            shared *= uint64_t(std::max(0, hi - lo + 1));
          }
          pairs += shared;
        }
      uint64_t scan = 0;
      for (const auto& [cell, k] : occupants) scan += k <= 32 ? k * (k - 1) / 2 : k * uint64_t(std::ceil(std::log2(double(k))));
      EXPECT_TRUE(c.counted);
      EXPECT_EQ(c.overflow, overflow);
      EXPECT_EQ(c.memberships, memberships);
      EXPECT_EQ(c.cells, tree.cells_in_use());
      EXPECT_EQ(c.cells, occupants.size());
      EXPECT_EQ(c.cell_pairs, pairs);
      EXPECT_EQ(c.scan_checks, scan);
      const uint64_t plain = overflow * now.size();
      EXPECT_EQ(c.overflow_checks, plain < WorldTree::kCoarseFrom ? plain : std::min<uint64_t>(plain, 20 * now.size()));
      EXPECT_DOUBLE_EQ(c.estimate_us,
                       (kCostScanCheck * double(c.scan_checks) + kCostOverflowCheck * double(c.overflow_checks) +
                        kCostCellChange * c.cell_changes + kCostReinsertion * c.reinsertions) / 1000);
    }
    // Deep grids overflow some of these boxes, shallow ones none: both paths ran.
    EXPECT_EQ(plan.depths[0].overflow, 0u);
    EXPECT_GT(plan.depths[10].overflow, 0u);
  }
}

// The expected cell changes and reinsertions a frame against the actual ones
// averaged over many random starting points of the same motion.
TEST(WorldDepth, ExpectedChangesAreTheAverageOverStartingPoints) {
  const Aabb world{{0, 0, 0}, {64, 64, 64}};  // depth 6: unit cells
  struct Motion {
    Eigen::Vector3d size, shift, grow;  // in cells; grow: each max face moves out by this much more
    double tolerance;  // relative: moves along two axes at once double-count the corner they share
  };
  const Motion motions[] = {
      {{2.5, 1.7, 0.9}, {0.3, 0, 0}, {0, 0, 0}, 0.02},    // one axis, faces never cross at once
      {{3.5, 2.5, 1.5}, {0, -0.2, 0}, {0, 0.1, 0}, 0.02},  // one axis, growing
      {{2.3, 1.2, 4.1}, {0.13, 0.07, -0.05}, {0.02, 0, 0.01}, 0.05},
  };
  std::mt19937 rng(5);
  for (const Motion& m : motions) {
    WorldTree grid(world, 6);
    double changes = 0, reinsertions = 0, expected_changes = 0, expected_reinsertions = 0;
    const int samples = 20000;
    for (int s = 0; s < samples; ++s) {
      const Eigen::Vector3d lo = random_point(rng, 10, 40);
      const Aabb a{lo, lo + m.size}, b{lo + m.shift, lo + m.shift + m.size + m.grow};
      const std::vector<Aabb> now{a}, next{b};
      const WorldDepthCost c = plan_world_depth(world, now, next).depths[6];
      expected_changes += c.cell_changes;
      expected_reinsertions += c.reinsertions;
      const WorldTree::CellRange ra = grid.cell_range(a), rb = grid.cell_range(b);
      uint64_t in_a = 1, in_b = 1, shared = 1;
      for (int k = 0; k < 3; ++k) {
        in_a *= uint64_t(ra.hi[k] - ra.lo[k] + 1);
        in_b *= uint64_t(rb.hi[k] - rb.lo[k] + 1);
        shared *= uint64_t(std::max(0, std::min(ra.hi[k], rb.hi[k]) - std::max(ra.lo[k], rb.lo[k]) + 1));
      }
      changes += double(in_a - shared + in_b - shared);
      reinsertions += in_a != shared || in_b != shared;
    }
    EXPECT_GT(changes, 0);
    EXPECT_NEAR(expected_changes / changes, 1.0, m.tolerance) << m.size.transpose() << " by " << m.shift.transpose();
    if (m.shift.cwiseAbs().maxCoeff() == m.shift.cwiseAbs().sum() && m.grow.isZero()) {
      EXPECT_NEAR(expected_reinsertions / reinsertions, 1.0, m.tolerance);
    }
  }
}

TEST(WorldDepth, SuggestsTheShallowestDepthNearTheLowestEstimate) {
  std::mt19937 rng(3);
  std::vector<Aabb> now, next;
  for (int round = 0; round < 20; ++round) {
    random_boxes(rng, 50 + 50 * size_t(round), now, next);
    // Some rounds static, some with every object moving far.
    if (round % 3 == 0) next = now;
    const uint64_t cap = round % 2 ? kCountedMemberships : 2000;
    const WorldDepthPlan plan = plan_world_depth(kWorld, now, next, cap);
    double best = INFINITY;
    for (const WorldDepthCost& c : plan.depths) {
      EXPECT_EQ(c.counted, c.memberships <= cap);
      if (!c.counted) {
        EXPECT_EQ(c.cells + c.cell_pairs + c.scan_checks, 0u);
      }
      if (c.counted) best = std::min(best, c.estimate_us);
    }
    const WorldDepthCost& s = plan.depths[size_t(plan.suggested)];
    EXPECT_TRUE(s.counted);
    const double limit = std::max(best * 1.1, best + 2);
    EXPECT_LE(s.estimate_us, limit);
    for (int d = 0; d < plan.suggested; ++d)
      EXPECT_FALSE(plan.depths[size_t(d)].counted && plan.depths[size_t(d)].estimate_us <= limit);
  }
}

// The scene form takes each object's box at frame 0 and after one step: the
// same boxes as a World stepped once (no response, everything well inside).
TEST(WorldDepth, SceneBoxesAreThoseOfTheFirstTwoFrames) {
  Result<ModelLibrary> library = ModelLibrary::open((scratch_with_trees() / "baked").string());
  ASSERT_TRUE(library) << library.error().message;
  std::mt19937 rng(8);
  Scene scene;
  scene.world = {{-100, -100, -100}, {100, 100, 100}};
  scene.timestep = 0.05;
  for (int i = 0; i < 200; ++i) {
    SceneObject o;
    o.name = "o" + std::to_string(i);
    o.model = i % 3 ? "cube" : "slab";
    o.pose.position = random_point(rng, -80, 80);
    o.pose.rotation = random_rotation(rng);
    o.pose.scale = std::pow(10.0, uniform(rng, -1, 1));
    if (i % 2) o.velocity = random_point(rng, -20, 20);
    if (i % 5 == 0) o.angular_velocity = random_point(rng, -3, 3);
    scene.objects.push_back(o);
  }
  Result<SceneModels> models = load_scene_models(scene, *library, 12);
  ASSERT_TRUE(models) << models.error().message;

  WorldSettings settings;
  settings.bounds = scene.world;
  settings.timestep = scene.timestep;
  settings.response = Response::none;
  std::vector<ObjectDesc> objects;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    objects.push_back({o.name, &models->trees[models->tree_of_object[i]], o.pose, o.velocity, o.angular_velocity});
  }
  World world(settings, objects);
  const auto boxes = [&] {
    std::vector<Aabb> out;
    for (size_t i = 0; i < world.size(); ++i)
      out.push_back(world_bounds(place(world.object(i).tree->bounds(), world.object(i).pose)));
    return out;
  };
  const std::vector<Aabb> now = boxes();
  std::vector<Collision> collisions;
  world.step(collisions);
  const std::vector<Aabb> next = boxes();

  const WorldDepthPlan from_scene = plan_world_depth(scene, *models), from_world = plan_world_depth(scene.world, now, next);
  EXPECT_EQ(from_scene.suggested, from_world.suggested);
  ASSERT_EQ(from_scene.depths.size(), from_world.depths.size());
  for (size_t d = 0; d < from_scene.depths.size(); ++d) {
    const WorldDepthCost &a = from_scene.depths[d], &b = from_world.depths[d];
    EXPECT_EQ(a.memberships, b.memberships);
    EXPECT_EQ(a.cells, b.cells);
    EXPECT_EQ(a.cell_pairs, b.cell_pairs);
    EXPECT_EQ(a.cell_changes, b.cell_changes) << "depth " << d;
    EXPECT_EQ(a.reinsertions, b.reinsertions) << "depth " << d;
  }
  EXPECT_GT(from_scene.depths[8].cell_changes, 0);
}

// A scene of cubes and slabs for the command line: sizes 100x apart, half moving.
std::string cli_scene(int depth) {
  std::mt19937 rng(4);
  nlohmann::json objects = nlohmann::json::array();
  for (int i = 0; i < 120; ++i) {
    const Eigen::Vector3d p = random_point(rng, -40, 40), v = random_point(rng, -6, 6);
    nlohmann::json o = {{"name", "o" + std::to_string(i)},
                        {"model", i % 4 ? "cube" : "slab"},
                        {"position", {p.x(), p.y(), p.z()}},
                        {"scale", std::pow(10.0, uniform(rng, -1, 1))}};
    if (i % 2) o["velocity"] = {v.x(), v.y(), v.z()};
    objects.push_back(o);
  }
  return nlohmann::json{{"format", "octbake-scene/1"},
                        {"baked", "baked"},
                        {"camera", {{"position", {0, 5, -90}}, {"look_at", {0, 0, 0}}}},
                        {"world", {{"min", {-50, -50, -50}}, {"max", {50, 50, 50}}, {"depth", depth}}},
                        {"timestep", 0.05},
                        {"frames", 60},
                        {"objects", objects}}
      .dump();
}

// `plan --json` reports what the library computes; the table marks the
// scene's depth and the suggestion.
TEST(WorldDepth, PlanCommandReportsEveryDepth) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "depths.json", cli_scene(9));
  Command c = run_command(kOctscene + " plan " + (dir / "depths.json").string() + " --frames 2 --json", dir);
  ASSERT_EQ(c.status, 0) << c.err;
  const nlohmann::json scene = nlohmann::json::parse(c.out)["scenes"][0];
  Result<Scene> loaded = load_scene((dir / "depths.json").string());
  ASSERT_TRUE(loaded);
  Result<ModelLibrary> library = ModelLibrary::open(loaded->baked);
  ASSERT_TRUE(library);
  Result<SceneModels> models = load_scene_models(*loaded, *library, 12);
  ASSERT_TRUE(models);
  const WorldDepthPlan plan = plan_world_depth(*loaded, *models);
  EXPECT_EQ(scene["world_depth"], 9);
  EXPECT_EQ(scene["suggested_world_depth"], plan.suggested);
  EXPECT_LT(plan.suggested, 9);  // sizes 100x apart in a world this deep: a shallower depth pays
  ASSERT_EQ(scene["world_depths"].size(), 11u);
  for (size_t d = 0; d < 11; ++d) {
    const nlohmann::json& j = scene["world_depths"][d];
    const WorldDepthCost& cost = plan.depths[d];
    EXPECT_EQ(j["depth"], cost.depth);
    EXPECT_EQ(j["cells"], cost.cells);
    EXPECT_EQ(j["memberships"], cost.memberships);
    EXPECT_EQ(j["overflow"], cost.overflow);
    EXPECT_EQ(j["scan_checks"], cost.scan_checks);
    EXPECT_DOUBLE_EQ(j["cell_changes"].get<double>(), cost.cell_changes);
    EXPECT_DOUBLE_EQ(j["estimate_us"].get<double>(), cost.estimate_us);
  }
  c = run_command(kOctscene + " plan " + (dir / "depths.json").string() + " --frames 2", dir);
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_NE(c.out.find("world depth 9, suggested " + std::to_string(plan.suggested)), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("<- scene"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("<- suggested"), std::string::npos) << c.out;
}

// --world-depth runs the scene as if its file said that depth: the same log
// and summary counts, byte for byte; out of range is a usage error.
TEST(WorldDepth, OptionEqualsTheSceneFilesDepth) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "depth9.json", cli_scene(9));
  write_text(dir / "depth3.json", cli_scene(3));
  const std::string common = " --summary json --threads 1 --log ";
  Command a = run_command(kOctscene + " run " + (dir / "depth9.json").string() + " --world-depth 3" + common +
                              (dir / "a.csv").string(), dir);
  Command b = run_command(kOctscene + " run " + (dir / "depth3.json").string() + common + (dir / "b.csv").string(), dir);
  Command c = run_command(kOctscene + " run " + (dir / "depth9.json").string() + common + (dir / "c.csv").string(), dir);
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_EQ(read_text(dir / "a.csv"), read_text(dir / "b.csv"));
  const nlohmann::json ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out), jc = nlohmann::json::parse(c.out);
  for (const char* key : {"collisions", "box_tests", "pair_tests", "depth_pairs"}) EXPECT_EQ(ja[key], jb[key]) << key;
  EXPECT_EQ(ja["options"]["world_depth"], 3);
  EXPECT_EQ(jc["options"]["world_depth"], 9);
  EXPECT_GT(ja["collisions"].get<int>(), 0);
  for (const char* bad : {" --world-depth 11", " --world-depth -1"}) {
    Command r = run_command(kOctscene + " run " + (dir / "depth9.json").string() + bad, dir);
    EXPECT_EQ(r.status, 2) << bad;
    EXPECT_EQ(r.err.rfind("octscene: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find("--world-depth"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace octbake::scene

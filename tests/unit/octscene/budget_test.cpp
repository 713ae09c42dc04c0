// Start-up budgets: the counters are deterministic, a recorded budget passes,
// and one a single unit too small fails naming the counter.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "budget.h"
#include "helpers.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;
using nlohmann::json;

const std::string kOctscene = OCTSCENE_BIN;

StartupCounters sample() { return StartupCounters{5, 21904, 30, 32373, 360}; }

TEST(Budget, TextRoundTrips) {
  const StartupCounters c = sample();
  Result<StartupCounters> back = parse_budget(budget_text(c), "b.json");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(counter_list(*back), counter_list(c));
  const json j = json::parse(budget_text(c));
  EXPECT_EQ(j["format"], "octbake-startup-budget");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["counters"]["bytes_decompressed"], 32373);
}

TEST(Budget, OneUnitTooSmallFailsNamingTheCounter) {
  const StartupCounters measured = sample();
  EXPECT_TRUE(budget_excess(measured, measured, "b.json").empty());
  const auto names = counter_list(measured);
  for (size_t i = 0; i < names.size(); ++i) {
    StartupCounters budget = measured;
    uint64_t* fields[] = {&budget.files_opened, &budget.bytes_mapped, &budget.levels_decoded,
                          &budget.bytes_decompressed, &budget.heap_allocations};
    *fields[i] -= 1;
    const std::vector<std::string> excess = budget_excess(measured, budget, "b.json");
    ASSERT_EQ(excess.size(), 1u) << names[i].first;
    EXPECT_EQ(excess[0], "budget exceeded: " + names[i].first + " " + std::to_string(names[i].second) + " > " +
                             std::to_string(names[i].second - 1) + " (b.json)");
    // A larger budget is never exceeded.
    *fields[i] += 2;
    EXPECT_TRUE(budget_excess(measured, budget, "b.json").empty());
  }
}

TEST(Budget, BadFilesAreErrorsNamingTheKey) {
  const std::string good = budget_text(sample());
  struct Case {
    std::string text, expect;
  };
  json missing = json::parse(good);
  missing["counters"].erase("heap_allocations");
  json unknown = json::parse(good);
  unknown["counters"]["frames"] = 3;
  json negative = json::parse(good);
  negative["counters"]["files_opened"] = -1;
  json fraction = json::parse(good);
  fraction["counters"]["bytes_mapped"] = 1.5;
  json newer = json::parse(good);
  newer["version"] = 2;
  json format = json::parse(good);
  format["format"] = "octbake-scene/1";
  for (const Case& c : std::vector<Case>{
           {"{", "b.json: not valid JSON"},
           {missing.dump(), "b.json: counters.heap_allocations: missing"},
           {unknown.dump(), "b.json: counters.frames: unknown counter"},
           {negative.dump(), "b.json: counters.files_opened: expected a non-negative integer"},
           {fraction.dump(), "b.json: counters.bytes_mapped: expected a non-negative integer"},
           {newer.dump(), "b.json: version 2, this build reads version 1"},
           {format.dump(), "b.json: format: expected \"octbake-startup-budget\""}}) {
    Result<StartupCounters> r = parse_budget(c.text, "b.json");
    ASSERT_FALSE(r) << c.text;
    EXPECT_EQ(r.error().message, c.expect);
  }
}

// A scene of the scratch trees (cube and slab, depth 4).
std::string two_tree_scene() {
  return json{{"format", "octbake-scene/1"},
              {"baked", "baked"},
              {"camera", {{"position", {0, 5, -30}}, {"look_at", {0, 0, 0}}}},
              {"world", {{"min", {-50, -50, -50}}, {"max", {50, 50, 50}}, {"depth", 3}}},
              {"timestep", 0.1},
              {"frames", 10},
              {"objects",
               {{{"name", "a"}, {"model", "cube"}, {"position", {0, 0, 0}}},
                {{"name", "b"}, {"model", "cube"}, {"position", {5, 0, 0}}},
                {{"name", "c"}, {"model", "slab"}, {"position", {-9, 0, 0}}}}}}
      .dump();
}

TEST(Budget, CountersAreIdenticalAcrossRunsAndCountTheLoad) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "budget_scene.json", two_tree_scene());
  const std::string run = kOctscene + " run " + (dir / "budget_scene.json").string() + " --frames 0 ";
  std::vector<std::string> budgets;
  for (int i = 0; i < 3; ++i) {
    const fs::path path = dir / ("recorded" + std::to_string(i) + ".json");
    Command c = run_command(run + "--write-budget " + path.string() + " --summary json", dir);
    ASSERT_EQ(c.status, 0) << c.err;
    budgets.push_back(read_text(path));
    const json summary = json::parse(c.out);
    Result<StartupCounters> recorded = parse_budget(budgets.back(), path.string());
    ASSERT_TRUE(recorded) << recorded.error().message;
    // The summary reports the same counters the budget records.
    for (const auto& [name, value] : counter_list(*recorded)) EXPECT_EQ(summary["startup"][name], value) << name;
    EXPECT_EQ(recorded->files_opened, 2u);  // cube.oct and slab.oct, each once
    EXPECT_EQ(recorded->levels_decoded, 8u);  // 4 levels each
    EXPECT_GT(recorded->bytes_decompressed, 0u);
    EXPECT_GT(recorded->heap_allocations, 10u);
  }
  EXPECT_EQ(budgets[1], budgets[0]);
  EXPECT_EQ(budgets[2], budgets[0]);
}

TEST(Budget, CommandPassesTheRecordedBudgetAndFailsOneByteLess) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "budget_scene.json", two_tree_scene());
  const std::string run = kOctscene + " run " + (dir / "budget_scene.json").string() + " --frames 0 ";
  const fs::path budget = dir / "budget.json";
  ASSERT_EQ(run_command(run + "--write-budget " + budget.string(), dir).status, 0);
  Command c = run_command(run + "--budget " + budget.string(), dir);
  EXPECT_EQ(c.status, 0) << c.err;
  EXPECT_EQ(c.err, "");

  Result<StartupCounters> recorded = read_budget(budget.string());
  ASSERT_TRUE(recorded);
  StartupCounters tight = *recorded;
  tight.bytes_decompressed -= 1;
  tight.heap_allocations -= 1;
  const fs::path small = dir / "small.json";
  write_text(small, budget_text(tight));
  c = run_command(run + "--budget " + small.string(), dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_EQ(c.err, "octscene: error: budget exceeded: bytes_decompressed " +
                       std::to_string(recorded->bytes_decompressed) + " > " + std::to_string(tight.bytes_decompressed) +
                       " (" + small.string() + ")\noctscene: error: budget exceeded: heap_allocations " +
                       std::to_string(recorded->heap_allocations) + " > " + std::to_string(tight.heap_allocations) +
                       " (" + small.string() + ")\n");
  // A missing budget file is an error naming it.
  c = run_command(run + "--budget " + (dir / "nope.json").string(), dir);
  EXPECT_EQ(c.status, 1);
  EXPECT_EQ(c.err, "octscene: error: " + (dir / "nope.json").string() + ": cannot open: No such file or directory\n");
}

// The summary keeps deterministic counts apart from timings and says which
// options were used.
TEST(Budget, JsonSummaryHasFormatOptionsCountersAndTimingsApart) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "budget_scene.json", two_tree_scene());
  Command c = run_command(kOctscene + " run " + (dir / "budget_scene.json").string() +
                              " --summary json --lod thesis --max-depth 3 --response none",
                          dir);
  ASSERT_EQ(c.status, 0) << c.err;
  const json j = json::parse(c.out);
  EXPECT_EQ(j["format"], "octscene-run-summary");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["options"]["lod"], "thesis");
  EXPECT_EQ(j["options"]["max_depth"], 3);
  EXPECT_EQ(j["options"]["response"], "none");
  EXPECT_EQ(j["options"]["frames"], 10);
  EXPECT_EQ(j["startup"]["levels_decoded"], 6);  // 3 levels of 2 trees
  for (const char* key : {"load_ms", "run_ms", "frames_per_second", "frame_ms_mean", "frame_ms_p99", "peak_rss_mb"}) {
    EXPECT_TRUE(j["timings"].contains(key)) << key;
    EXPECT_EQ(j[key], j["timings"][key]) << key;  // docs/interface.md's top-level keys stay
  }
  EXPECT_FALSE(j["startup"].contains("load_ms"));
}

}  // namespace
}  // namespace octbake::scene

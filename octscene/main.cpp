// octscene: runs scenes of baked ObjectTrees (docs/interface.md section 5).
// Exit status: 0 ok, 1 bad scene, load failure or budget exceeded, 2 bad usage.
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "alloc_counter.h"
#include "budget.h"
#include "cli_util.h"
#include "gen.h"
#include "octbake/collision_world.h"
#include "octbake/version.h"
#include "plan.h"
#include "world_depth.h"
#include "run.h"
#include "scene.h"
#ifdef OCTSCENE_WITH_ANALYSIS
#include "picture.h"
#include "trade.h"
#endif

namespace octbake::scene {
namespace {

int fail(const std::string& message) {
  std::fprintf(stderr, "octscene: error: %s\n", message.c_str());
  return 1;
}
int usage_fail(const std::string& message) {
  fail(message);
  return 2;
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: KiB
}

// Options `run` and `plan` share: how the scene is run.
struct SceneArgs {
  std::string baked;     // overrides the scene's "baked" when set
  int world_depth = -1;  // overrides the scene's world depth when >= 0
  RunOptions options;
};

void add_scene_options(CLI::App* cmd, SceneArgs& a) {
  const auto policies = names_of(kLodPolicies);
  const auto responses = names_of(kResponses);
  cmd->add_option("--lod", a.options.lod.policy, "fixed | thesis | screen (default: screen)")
      ->transform(CLI::CheckedTransformer(policies));
  cmd->add_option("--min-depth", a.options.lod.min_depth, "shallowest depth the LOD picks")
      ->check(CLI::Range(0, 12))->capture_default_str();
  cmd->add_option("--max-depth", a.options.lod.max_depth, "deepest depth the LOD picks (default: each tree's baked depth)")
      ->check(CLI::Range(0, 12));
  cmd->add_option("--pixel-tolerance", a.options.lod.pixel_tolerance, "for --lod screen: pixels a leaf box may span")
      ->check(CLI::PositiveNumber)->check(kFiniteNumber)->capture_default_str();
  cmd->add_option("--response", a.options.response, "none | thesis | separate (default: separate)")
      ->transform(CLI::CheckedTransformer(responses));
  cmd->add_option("--frames", a.options.frames, "override the scene's frame count")
      ->check(CLI::Range(int64_t{0}, kMaxFrames));
  cmd->add_flag("--areas-every-frame", a.options.areas_every_frame,
                "recompute pixel areas every frame, not only when an object changes leaf set");
  cmd->add_option("--baked", a.baked, "folder or pack of trees (default: the scene's \"baked\")")->check(kNonEmptyPath);
  cmd->add_option("--world-depth", a.world_depth, "WorldTree depth (default: the scene's world.depth)")
      ->check(CLI::Range(0, 10));
  a.options.threads = usable_cores();
  cmd->add_option("--threads", a.options.threads, "worker threads (results do not depend on it; default: all cores the process may run on)")
      ->check(CLI::Range(1, 4096));
}

nlohmann::ordered_json options_json(const SceneArgs& a, const Scene& scene) {
  nlohmann::ordered_json j;
  j["baked"] = scene.baked;
  j["lod"] = to_string(a.options.lod.policy);
  j["min_depth"] = a.options.lod.min_depth;
  j["max_depth"] = a.options.lod.max_depth;
  j["pixel_tolerance"] = a.options.lod.pixel_tolerance;
  j["response"] = to_string(a.options.response);
  j["frames"] = a.options.frames >= 0 ? a.options.frames : scene.frames;
  j["areas_every_frame"] = a.options.areas_every_frame;
  j["threads"] = a.options.threads;
  j["world_depth"] = scene.world_depth;
  return j;
}

// A scene and its trees, loaded with the start-up counted.
struct Loaded {
  Scene scene;
  std::optional<ModelLibrary> library;
  SceneModels models;
  StartupCounters counters;
};

Result<Loaded> load(const std::string& scene_path, const SceneArgs& a) {
  Result<Scene> scene = load_scene(scene_path);
  if (!scene) return scene.error();
  Loaded l{std::move(scene).value(), std::nullopt, {}, {}};
  if (!a.baked.empty()) l.scene.baked = a.baked;
  if (a.world_depth >= 0) l.scene.world_depth = a.world_depth;

  start_counting_allocations();
  Result<ModelLibrary> library = ModelLibrary::open(l.scene.baked);
  // Only the depths the LOD can reach are decoded.
  Result<SceneModels> models = library ? load_scene_models(l.scene, *library, a.options.lod.max_depth)
                                       : Result<SceneModels>(library.error());
  l.counters.heap_allocations = stop_counting_allocations();
  if (!library) return Error{library.error().code, scene_path + ": baked: " + library.error().message};
  if (!models) return Error{models.error().code, scene_path + ": " + models.error().message};
  const uint64_t heap = l.counters.heap_allocations;
  l.counters = counters_from(library->stats());
  l.counters.heap_allocations = heap;
  l.library.emplace(std::move(library).value());
  l.models = std::move(models).value();
  return l;
}

// ---- run ----


struct RunArgs {
  std::string scene_path;
  SceneArgs scene;
  std::string log_path;
  std::string summary = "table";
  std::string budget_path, write_budget_path;
};

// The thesis's table always shows 1-1 .. 3-3; other pairs when they occur.
std::map<std::pair<int, int>, uint64_t> depth_table(const RunResult& r) {
  std::map<std::pair<int, int>, uint64_t> table = r.depth_pairs;
  for (int lo = 1; lo <= 3; ++lo)
    for (int hi = lo; hi <= 3; ++hi) table.try_emplace({lo, hi}, 0);
  return table;
}

void print_summary(const RunArgs& args, const Loaded& l, const RunResult& r) {
  const double per_pair = r.pair_tests ? static_cast<double>(r.box_tests) / static_cast<double>(r.pair_tests) : 0;
  const double fps = r.run_ms > 0 ? static_cast<double>(r.frames) * 1000.0 / r.run_ms : 0;
  const double rss = peak_rss_mb();
  auto table = depth_table(r);
  if (args.summary == "json") {
    // Deterministic counts first (identical on every run), timings apart.
    nlohmann::ordered_json j;
    j["format"] = "octscene-run-summary";
    j["version"] = 1;
    j["scene"] = args.scene_path;
    j["options"] = options_json(args.scene, l.scene);
    j["frames"] = r.frames;
    j["objects"] = l.scene.objects.size();
    j["collisions"] = r.collisions;
    nlohmann::ordered_json pairs = nlohmann::ordered_json::object();
    for (const auto& [key, n] : table) pairs[std::to_string(key.first) + "-" + std::to_string(key.second)] = n;
    j["depth_pairs"] = pairs;
    j["box_tests"] = r.box_tests;
    j["pair_tests"] = r.pair_tests;
    j["pairs_reused"] = r.pairs_reused;
    j["pairs_kept_apart"] = r.pairs_kept_apart;
    j["box_tests_per_pair_test"] = per_pair;
    nlohmann::ordered_json startup;
    for (const auto& [name, value] : counter_list(l.counters)) startup[name] = value;
    j["startup"] = startup;
    nlohmann::ordered_json timings;
    timings["load_ms"] = r.load_ms;
    timings["run_ms"] = r.run_ms;
    timings["frames_per_second"] = fps;
    timings["frame_ms_mean"] = r.frame_ms_mean;
    timings["frame_ms_p99"] = r.frame_ms_p99;
    timings["peak_rss_mb"] = rss;
    j["timings"] = timings;
    // docs/interface.md section 5 names these at the top level: kept there too.
    for (const auto& [key, value] : timings.items()) j[key] = value;
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  const StartupCounters& s = l.counters;
  std::printf("scene            %s (%zu objects, %lld frames)\n", args.scene_path.c_str(), l.scene.objects.size(),
              static_cast<long long>(r.frames));
  std::printf("collisions       %llu\n", static_cast<unsigned long long>(r.collisions));
  std::printf("depth pairs     ");
  for (const auto& [key, n] : table) std::printf(" %d-%d: %llu", key.first, key.second, static_cast<unsigned long long>(n));
  std::printf("\n");
  std::printf("pair tests       %llu (%llu reused)\n", static_cast<unsigned long long>(r.pair_tests),
              static_cast<unsigned long long>(r.pairs_reused));
  std::printf("kept apart       %llu (pair tests answered by a miss's separation)\n",
              static_cast<unsigned long long>(r.pairs_kept_apart));
  std::printf("box tests        %llu (%.2f per pair test)\n", static_cast<unsigned long long>(r.box_tests), per_pair);
  std::printf("start-up         %llu files, %llu B mapped, %llu levels, %llu B decompressed, %llu allocations\n",
              static_cast<unsigned long long>(s.files_opened), static_cast<unsigned long long>(s.bytes_mapped),
              static_cast<unsigned long long>(s.levels_decoded), static_cast<unsigned long long>(s.bytes_decompressed),
              static_cast<unsigned long long>(s.heap_allocations));
  std::printf("load             %.3f ms\n", r.load_ms);
  std::printf("frame time       mean %.4f ms, p99 %.4f ms\n", r.frame_ms_mean, r.frame_ms_p99);
  std::printf("run loop         %.1f ms, %.0f frames/s\n", r.run_ms, fps);
  std::printf("peak RSS         %.1f MB\n", rss);
}

int run_command(const RunArgs& args) {
  Result<Loaded> loaded = load(args.scene_path, args.scene);
  if (!loaded) return fail(loaded.error().message);
  const Scene& scene = loaded->scene;
  if (!args.write_budget_path.empty()) {
    if (auto w = write_budget(args.write_budget_path, loaded->counters); !w) return fail(w.error().message);
  }
  std::optional<StartupCounters> budget;
  if (!args.budget_path.empty()) {
    Result<StartupCounters> b = read_budget(args.budget_path);
    if (!b) return fail(b.error().message);
    budget = *b;
  }

  std::FILE* log = nullptr;
  if (!args.log_path.empty()) {
    log = std::fopen(args.log_path.c_str(), "wb");
    if (!log) return fail(args.log_path + ": cannot write: " + std::strerror(errno));
    std::fprintf(log, "%s\n", kLogHeader);
  }
  std::string pending;
  const bool progress = isatty(STDERR_FILENO);
  const int64_t total = args.scene.options.frames >= 0 ? args.scene.options.frames : scene.frames;
  auto last_progress = std::chrono::steady_clock::now();
  Result<RunResult> result = run_scene(scene, loaded->models, args.scene.options, [&](const FrameReport& frame) {
    if (log) {
      append_log_lines(scene, frame, pending);
      if (pending.size() > (1 << 20)) {
        std::fwrite(pending.data(), 1, pending.size(), log);
        pending.clear();
      }
    }
    if (progress && (frame.frame & 1023) == 0) {
      auto now = std::chrono::steady_clock::now();
      if (now - last_progress > std::chrono::milliseconds(250)) {
        std::fprintf(stderr, "\roctscene: frame %lld/%lld", static_cast<long long>(frame.frame),
                     static_cast<long long>(total));
        last_progress = now;
      }
    }
  });
  if (progress) std::fprintf(stderr, "\r\033[K");
  if (log) {
    std::fwrite(pending.data(), 1, pending.size(), log);
    bool write_failed = std::ferror(log) != 0;
    write_failed = (std::fclose(log) != 0) || write_failed;
    if (write_failed) return fail(args.log_path + ": write failed");
  }
  if (!result) return fail(args.scene_path + ": " + result.error().message);
  print_summary(args, *loaded, *result);
  if (!stdout_written()) return fail("stdout: write failed");
  if (budget) {
    const std::vector<std::string> excess = budget_excess(loaded->counters, *budget, args.budget_path);
    for (const std::string& message : excess) fail(message);
    if (!excess.empty()) return 1;
  }
  return 0;
}

// ---- plan ----

struct PlanArgs {
  std::vector<std::string> scene_paths;
  SceneArgs scene;
  bool json = false;
};

nlohmann::ordered_json plan_json(const ModelPlan& m) {
  nlohmann::ordered_json j;
  j["model"] = m.model;
  j["objects"] = m.objects;
  j["baked_depth"] = m.baked_depth;
  j["lod_top"] = m.lod_top;
  j["deepest"] = m.deepest;
  j["needed"] = m.needed;
  j["bytes_needed"] = m.bytes_needed;
  j["bytes_loaded"] = m.bytes_loaded;
  j["reaches_baked_depth"] = m.reaches_baked();
  return j;
}

void print_plan(const std::string& path, const SceneArgs& a, const Loaded& l, const ScenePlan& plan) {
  const LodSettings& lod = a.options.lod;
  std::printf("%s: %zu objects, %lld frames, LOD %s %d..%d", path.c_str(), l.scene.objects.size(),
              static_cast<long long>(plan.frames), to_string(lod.policy), lod.min_depth, lod.max_depth);
  if (lod.policy == LodPolicy::screen) std::printf(" (%g px)", lod.pixel_tolerance);
  std::printf(", response %s\n", to_string(a.options.response));
  std::printf("  %-16s %7s %6s %8s %6s %14s %14s\n", "model", "objects", "baked", "deepest", "needs", "bytes needed",
              "bytes loaded");
  for (const ModelPlan& m : plan.models) {
    std::printf("  %-16s %7zu %6d %8d %6d %14llu %14llu%s\n", m.model.c_str(), m.objects, m.baked_depth, m.deepest,
                m.needed, static_cast<unsigned long long>(m.bytes_needed),
                static_cast<unsigned long long>(m.bytes_loaded),
                m.reaches_baked() ? "  reaches the baked depth: a deeper bake would be used" : "");
  }
  if (lod.policy == LodPolicy::thesis)
    std::printf("  (thesis LOD: its formula scales with the top depth, so a model needs its top depth)\n");
}

nlohmann::ordered_json world_depth_json(const WorldDepthCost& c) {
  nlohmann::ordered_json j;
  j["depth"] = c.depth;
  j["memberships"] = c.memberships;
  j["overflow"] = c.overflow;
  j["cells"] = c.counted ? nlohmann::ordered_json(c.cells) : nlohmann::ordered_json();
  j["scan_checks"] = c.counted ? nlohmann::ordered_json(c.scan_checks) : nlohmann::ordered_json();
  j["overflow_checks"] = c.overflow_checks;
  j["reinsertions"] = c.reinsertions;
  j["cell_changes"] = c.cell_changes;
  j["estimate_us"] = c.estimate_us;
  return j;
}

void print_world_depths(int scene_depth, const WorldDepthPlan& plan) {
  std::printf("  world depth %d, suggested %d; the WorldTree's share of a frame at each depth, estimated from frame 0:\n",
              scene_depth, plan.suggested);
  std::printf("  %5s %10s %12s %8s %12s %14s %12s\n", "depth", "cells", "memberships", "overflow", "scan checks",
              "cell changes", "estimate us");
  for (const WorldDepthCost& c : plan.depths) {
    const std::string cells = c.counted ? std::to_string(c.cells) : "-";
    const std::string scan = c.counted ? std::to_string(c.scan_checks) : "-";
    std::printf("  %5d %10s %12llu %8llu %12s %14.1f %12.1f%s\n", c.depth, cells.c_str(),
                static_cast<unsigned long long>(c.memberships), static_cast<unsigned long long>(c.overflow),
                scan.c_str(), c.cell_changes, c.estimate_us,
                c.depth == plan.suggested ? (c.depth == scene_depth ? "  <- scene, suggested" : "  <- suggested")
                : c.depth == scene_depth ? "  <- scene"
                                         : "");
  }
}

int plan_command(const PlanArgs& args) {
  nlohmann::ordered_json scenes = nlohmann::ordered_json::array();
  for (const std::string& path : args.scene_paths) {
    Result<Loaded> loaded = load(path, args.scene);
    if (!loaded) return fail(loaded.error().message);
    Result<ScenePlan> plan = plan_scene(loaded->scene, loaded->models, args.scene.options);
    if (!plan) return fail(path + ": " + plan.error().message);
    const WorldDepthPlan depths = plan_world_depth(loaded->scene, loaded->models);
    if (!args.json) {
      print_plan(path, args.scene, *loaded, *plan);
      print_world_depths(loaded->scene.world_depth, depths);
      continue;
    }
    nlohmann::ordered_json s;
    s["scene"] = path;
    s["options"] = options_json(args.scene, loaded->scene);
    s["frames"] = plan->frames;
    s["objects"] = loaded->scene.objects.size();
    nlohmann::ordered_json models = nlohmann::ordered_json::array();
    for (const ModelPlan& m : plan->models) models.push_back(plan_json(m));
    s["models"] = models;
    s["world_depth"] = loaded->scene.world_depth;
    s["suggested_world_depth"] = depths.suggested;
    nlohmann::ordered_json world_depths = nlohmann::ordered_json::array();
    for (const WorldDepthCost& c : depths.depths) world_depths.push_back(world_depth_json(c));
    s["world_depths"] = world_depths;
    scenes.push_back(s);
  }
  if (args.json) {
    nlohmann::ordered_json j;
    j["format"] = "octscene-plan";
    j["version"] = 1;
    j["scenes"] = scenes;
    std::printf("%s\n", j.dump(2).c_str());
  }
  return stdout_written() ? 0 : fail("stdout: write failed");
}

// ---- gen ----

struct GenArgs {
  GenOptions options;
  std::string baked = "baked";
  std::string baked_as;
};

int gen_command(GenArgs& args) {
  // A bad combination of values is a usage error, like a bad value.
  if (auto st = check_gen_options(args.options); !st) return usage_fail(st.error().message);
  Result<ModelLibrary> library = ModelLibrary::open(args.baked);
  if (!library) return fail(args.baked + ": " + library.error().message);
  Result<Scene> scene = generate_scene(args.options, *library);
  if (!scene) return fail(scene.error().message);
  std::string text = write_scene(*scene, args.baked_as.empty() ? args.baked : args.baked_as);
  // Extreme options (a world of 1e308) can give values `run` rejects, such
  // as a far plane that overflows: read the scene back as `run` would.
  if (Result<Scene> back = parse_scene(text, "."); !back)
    return usage_fail("these options give a scene octscene run rejects: " + back.error().message);
  std::fwrite(text.data(), 1, text.size(), stdout);
  return stdout_written() ? 0 : fail("stdout: write failed");
}

// Subcommands that parse their own arguments (octscene/analysis).
struct Tool {
  const char* name;
  const char* help;
  int (*main)(int, char**);
};

const std::vector<Tool>& tools() {
#ifdef OCTSCENE_WITH_ANALYSIS
  static const std::vector<Tool> list{
      {"trade", "score every LOD setting against an exact mesh-mesh answer (FCL)", trade_main},
      {"picture", "PNG pictures of baked trees and scene frames", picture_main}};
#else
  static const std::vector<Tool> list{
      {"trade", "score every LOD setting against an exact answer (not built: -DOCTBAKE_ANALYSIS=ON)", nullptr},
      {"picture", "PNG pictures of trees and frames (not built: -DOCTBAKE_ANALYSIS=ON)", nullptr}};
#endif
  return list;
}

int cli_main(int argc, char** argv) {
  CLI::App app{"octscene: run scenes of baked ObjectTrees", "octscene"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("octscene ") + kLibraryVersion);

  RunArgs run;
  CLI::App* run_cmd = app.add_subcommand("run", "run a scene and report its collisions");
  run_cmd->add_option("scene", run.scene_path, "scene file (JSON)")->required();
  add_scene_options(run_cmd, run.scene);
  run_cmd->add_option("--log", run.log_path, "collision log (CSV)")->check(kNonEmptyPath);
  run_cmd->add_option("--summary", run.summary, "table | json")
      ->check(CLI::IsMember({"table", "json"}))->capture_default_str();
  run_cmd->add_option("--budget", run.budget_path,
                      "start-up budget (JSON): exit 1 when a start-up counter exceeds it")->check(kNonEmptyPath);
  run_cmd->add_option("--write-budget", run.write_budget_path, "record this run's start-up counters as a budget")
      ->check(kNonEmptyPath);

  PlanArgs plan;
  CLI::App* plan_cmd =
      app.add_subcommand("plan", "per model a scene names: the deepest depth its LOD reaches over the run");
  plan_cmd->add_option("scene", plan.scene_paths, "scene files (JSON)")->required();
  add_scene_options(plan_cmd, plan.scene);
  plan_cmd->add_flag("--json", plan.json, "print JSON instead of a table");

  GenArgs gen;
  CLI::App* gen_cmd = app.add_subcommand("gen", "write a random scene to stdout");
  gen_cmd->add_option("--static", gen.options.static_count, "static objects")->required()->check(CLI::NonNegativeNumber);
  gen_cmd->add_option("--moving", gen.options.moving_count, "moving objects")->required()->check(CLI::NonNegativeNumber);
  gen_cmd->add_option("--seed", gen.options.seed, "random seed")->required();
  gen_cmd->add_option("--models", gen.options.models, "model names, comma separated")->required()->delimiter(',');
  gen_cmd->add_option("--baked", gen.baked, "folder or pack holding the models")->check(kNonEmptyPath)->capture_default_str();
  gen_cmd->add_option("--baked-as", gen.baked_as, "\"baked\" as written in the scene (default: --baked)")
      ->check(kNonEmptyPath);
  gen_cmd->add_option("--world", gen.options.world_size, "edge of the cubic world box")
      ->check(CLI::PositiveNumber)->check(kFiniteNumber)->capture_default_str();
  gen_cmd->add_option("--world-depth", gen.options.world_depth, "WorldTree depth")->check(CLI::Range(0, 10))->capture_default_str();
  gen_cmd->add_option("--speed", gen.options.speed, "top speed of moving objects")
      ->check(CLI::NonNegativeNumber)->check(kFiniteNumber)->capture_default_str();
  gen_cmd->add_option("--frames", gen.options.frames, "frame count")
      ->check(CLI::Range(int64_t{0}, kMaxFrames))->capture_default_str();
  gen_cmd->add_option("--timestep", gen.options.timestep, "seconds per frame")
      ->check(CLI::PositiveNumber)->check(kFiniteNumber);
  std::vector<double> scale_range;
  gen_cmd->add_option("--scale-range", scale_range, "MIN,MAX: scales log-uniform in [MIN, MAX] (default 1,1)")
      ->delimiter(',')->expected(2)->check(CLI::PositiveNumber)->check(kFiniteNumber);
  gen_cmd->add_option("--rotated-share", gen.options.rotated_share, "share of objects with a random 3D orientation")
      ->check(CLI::Range(0.0, 1.0))->check(kFiniteNumber);
  gen_cmd->add_option("--spin-share", gen.options.spin_share, "share of objects that spin")
      ->check(CLI::Range(0.0, 1.0))->check(kFiniteNumber);
  gen_cmd->add_option("--spin-rate", gen.options.spin_rate, "top spin rate, radians per second")
      ->check(CLI::NonNegativeNumber)->check(kFiniteNumber)->capture_default_str();
  gen_cmd->add_option("--camera-path", gen.options.camera_keys, "KEYS: a camera path of KEYS keys through the world")
      ->check(CLI::Range(2, 10000));
  gen_cmd->add_option("--resting-share", gen.options.resting_share,
                      "share of static objects placed against an earlier static (world boxes overlapping)")
      ->check(CLI::Range(0.0, 1.0))->check(kFiniteNumber);

  // Listed in --help; main() hands them their arguments before CLI11 parses.
  for (const Tool& tool : tools()) app.add_subcommand(tool.name, tool.help)->allow_extras();

  // Name an unknown subcommand rather than CLI11's "not expected" message.
  bool known = false;
  for (const CLI::App* sub : app.get_subcommands({})) known = known || (argc >= 2 && sub->get_name() == argv[1]);
  if (argc >= 2 && argv[1][0] != '-' && !known) {
    std::fprintf(stderr, "octscene: error: unknown subcommand \"%s\" (run, plan, gen, trade or picture; see "
                         "octscene --help)\n", argv[1]);
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::string command = "octscene";
    for (CLI::App* sub : app.get_subcommands()) command += " " + sub->get_name();
    return parse_error_exit(app, e, command);
  }
  for (const RunOptions* o : {&run.scene.options, &plan.scene.options})
    if (depth_range_error(o->lod.min_depth, o->lod.max_depth)) return 2;
  if (*run_cmd) return run_command(run);
  if (*plan_cmd) return plan_command(plan);
  if (scale_range.size() == 2) gen.options.scale_min = scale_range[0], gen.options.scale_max = scale_range[1];
  return gen_command(gen);
}

}  // namespace
}  // namespace octbake::scene

int main(int argc, char** argv) {
  using namespace octbake::scene;
  // trade and picture parse their own arguments.
  for (const Tool& tool : tools()) {
    if (argc < 2 || std::strcmp(argv[1], tool.name) != 0) continue;
    if (!tool.main) {
      std::fprintf(stderr, "octscene: error: %s: not built (configure with -DOCTBAKE_ANALYSIS=ON)\n", tool.name);
      return 2;
    }
    return tool.main(argc - 1, argv + 1);
  }
  return cli_main(argc, argv);
}

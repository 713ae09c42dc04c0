// octscene: runs scenes of baked ObjectTrees (docs/interface.md section 5).
// Exit status: 0 ok, 1 bad scene or load failure, 2 bad usage.
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "gen.h"
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

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: KiB
}

struct RunArgs {
  std::string scene_path;
  std::string lod = "screen";
  int min_depth = 1;
  int max_depth = 12;  // clamped to each tree's baked depth
  double pixel_tolerance = 1.0;
  std::string response = "separate";
  int64_t frames = -1;
  std::string log_path;
  std::string summary = "table";
  bool areas_every_frame = false;
};

// The thesis's table always shows 1-1 .. 3-3; other pairs when they occur.
std::map<std::pair<int, int>, uint64_t> depth_table(const RunResult& r) {
  std::map<std::pair<int, int>, uint64_t> table = r.depth_pairs;
  for (int lo = 1; lo <= 3; ++lo)
    for (int hi = lo; hi <= 3; ++hi) table.try_emplace({lo, hi}, 0);
  return table;
}

void print_summary(const RunArgs& args, const Scene& scene, const RunResult& r) {
  const double per_pair = r.pair_tests ? static_cast<double>(r.box_tests) / static_cast<double>(r.pair_tests) : 0;
  const double fps = r.run_ms > 0 ? static_cast<double>(r.frames) * 1000.0 / r.run_ms : 0;
  auto table = depth_table(r);
  if (args.summary == "json") {
    nlohmann::ordered_json j;
    j["frames"] = r.frames;
    j["objects"] = scene.objects.size();
    j["collisions"] = r.collisions;
    nlohmann::ordered_json pairs = nlohmann::ordered_json::object();
    for (const auto& [key, n] : table) pairs[std::to_string(key.first) + "-" + std::to_string(key.second)] = n;
    j["depth_pairs"] = pairs;
    j["box_tests"] = r.box_tests;
    j["pair_tests"] = r.pair_tests;
    j["box_tests_per_pair_test"] = per_pair;
    j["load_ms"] = r.load_ms;
    j["run_ms"] = r.run_ms;
    j["frames_per_second"] = fps;
    j["frame_ms_mean"] = r.frame_ms_mean;
    j["frame_ms_p99"] = r.frame_ms_p99;
    j["peak_rss_mb"] = peak_rss_mb();
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("scene            %s (%zu objects, %lld frames)\n", args.scene_path.c_str(), scene.objects.size(),
              static_cast<long long>(r.frames));
  std::printf("collisions       %llu\n", static_cast<unsigned long long>(r.collisions));
  std::printf("depth pairs     ");
  for (const auto& [key, n] : table) std::printf(" %d-%d: %llu", key.first, key.second, static_cast<unsigned long long>(n));
  std::printf("\n");
  std::printf("pair tests       %llu\n", static_cast<unsigned long long>(r.pair_tests));
  std::printf("box tests        %llu (%.2f per pair test)\n", static_cast<unsigned long long>(r.box_tests), per_pair);
  std::printf("load             %.3f ms\n", r.load_ms);
  std::printf("frame time       mean %.4f ms, p99 %.4f ms\n", r.frame_ms_mean, r.frame_ms_p99);
  std::printf("run loop         %.1f ms, %.0f frames/s\n", r.run_ms, fps);
  std::printf("peak RSS         %.1f MB\n", peak_rss_mb());
}

int run_command(const RunArgs& args) {
  Result<Scene> scene = load_scene(args.scene_path);
  if (!scene) return fail(scene.error().message);
  Result<ModelLibrary> library = ModelLibrary::open(scene->baked);
  if (!library) return fail(args.scene_path + ": baked: " + library.error().message);

  RunOptions options;
  options.lod.policy = args.lod == "fixed" ? LodPolicy::fixed : args.lod == "thesis" ? LodPolicy::thesis : LodPolicy::screen;
  options.lod.min_depth = args.min_depth;
  options.lod.max_depth = args.max_depth;
  options.lod.pixel_tolerance = args.pixel_tolerance;
  options.response = args.response == "none"     ? Response::none
                     : args.response == "thesis" ? Response::thesis
                                                 : Response::separate;
  options.frames = args.frames;
  options.areas_every_frame = args.areas_every_frame;

  // Only the depths the LOD can reach are decoded.
  Result<SceneModels> models = load_scene_models(*scene, *library, args.max_depth);
  if (!models) return fail(args.scene_path + ": " + models.error().message);

  std::FILE* log = nullptr;
  if (!args.log_path.empty()) {
    log = std::fopen(args.log_path.c_str(), "wb");
    if (!log) return fail(args.log_path + ": cannot write: " + std::strerror(errno));
    std::fprintf(log, "%s\n", kLogHeader);
  }
  std::string pending;
  const bool progress = isatty(STDERR_FILENO);
  const int64_t total = args.frames >= 0 ? args.frames : scene->frames;
  auto last_progress = std::chrono::steady_clock::now();
  Result<RunResult> result = run_scene(*scene, *models, options, [&](const FrameReport& frame) {
    if (log) {
      append_log_lines(*scene, frame, pending);
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
  print_summary(args, *scene, *result);
  return 0;
}

struct GenArgs {
  GenOptions options;
  std::string baked = "baked";
  std::string baked_as;
};

int gen_command(GenArgs& args) {
  Result<ModelLibrary> library = ModelLibrary::open(args.baked);
  if (!library) return fail(args.baked + ": " + library.error().message);
  Result<Scene> scene = generate_scene(args.options, *library);
  if (!scene) return fail(scene.error().message);
  std::string text = write_scene(*scene, args.baked_as.empty() ? args.baked : args.baked_as);
  std::fwrite(text.data(), 1, text.size(), stdout);
  return std::fflush(stdout) == 0 ? 0 : fail("stdout: write failed");
}

int cli_main(int argc, char** argv) {
  CLI::App app{"octscene: run scenes of baked ObjectTrees"};
  app.require_subcommand(1);

  RunArgs run;
  CLI::App* run_cmd = app.add_subcommand("run", "run a scene and report its collisions");
  run_cmd->add_option("scene", run.scene_path, "scene file (JSON)")->required();
  run_cmd->add_option("--lod", run.lod, "fixed | thesis | screen")
      ->check(CLI::IsMember({"fixed", "thesis", "screen"}))->capture_default_str();
  run_cmd->add_option("--min-depth", run.min_depth, "shallowest depth the LOD picks")
      ->check(CLI::Range(0, 12))->capture_default_str();
  run_cmd->add_option("--max-depth", run.max_depth, "deepest depth the LOD picks (default: each tree's baked depth)")
      ->check(CLI::Range(0, 12));
  run_cmd->add_option("--pixel-tolerance", run.pixel_tolerance, "for --lod screen: pixels a leaf box may span")
      ->check(CLI::PositiveNumber)->capture_default_str();
  run_cmd->add_option("--response", run.response, "none | thesis | separate")
      ->check(CLI::IsMember({"none", "thesis", "separate"}))->capture_default_str();
  run_cmd->add_option("--frames", run.frames, "override the scene's frame count")->check(CLI::NonNegativeNumber);
  run_cmd->add_option("--log", run.log_path, "collision log (CSV)");
  run_cmd->add_option("--summary", run.summary, "table | json")
      ->check(CLI::IsMember({"table", "json"}))->capture_default_str();
  run_cmd->add_flag("--areas-every-frame", run.areas_every_frame,
                    "recompute pixel areas every frame, not only when an object changes leaf set");

  GenArgs gen;
  CLI::App* gen_cmd = app.add_subcommand("gen", "write a random scene to stdout");
  gen_cmd->add_option("--static", gen.options.static_count, "static objects")->required()->check(CLI::NonNegativeNumber);
  gen_cmd->add_option("--moving", gen.options.moving_count, "moving objects")->required()->check(CLI::NonNegativeNumber);
  gen_cmd->add_option("--seed", gen.options.seed, "random seed")->required();
  gen_cmd->add_option("--models", gen.options.models, "model names, comma separated")->required()->delimiter(',');
  gen_cmd->add_option("--baked", gen.baked, "folder or pack holding the models")->capture_default_str();
  gen_cmd->add_option("--baked-as", gen.baked_as, "\"baked\" as written in the scene (default: --baked)");
  gen_cmd->add_option("--world", gen.options.world_size, "edge of the cubic world box")
      ->check(CLI::PositiveNumber)->capture_default_str();
  gen_cmd->add_option("--world-depth", gen.options.world_depth, "WorldTree depth")->check(CLI::Range(0, 10))->capture_default_str();
  gen_cmd->add_option("--speed", gen.options.speed, "top speed of moving objects")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  gen_cmd->add_option("--frames", gen.options.frames, "frame count")->check(CLI::NonNegativeNumber)->capture_default_str();
  gen_cmd->add_option("--timestep", gen.options.timestep, "seconds per frame")->check(CLI::PositiveNumber);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  if (run.min_depth > run.max_depth) {
    std::fprintf(stderr, "octscene: --min-depth %d is above --max-depth %d\n", run.min_depth, run.max_depth);
    return 2;
  }
  if (*run_cmd) return run_command(run);
  return gen_command(gen);
}

}  // namespace
}  // namespace octbake::scene

int main(int argc, char** argv) {
  // trade and picture parse their own arguments.
#ifdef OCTSCENE_WITH_ANALYSIS
  if (argc >= 2 && std::strcmp(argv[1], "trade") == 0) return octbake::scene::trade_main(argc - 1, argv + 1);
  if (argc >= 2 && std::strcmp(argv[1], "picture") == 0) return octbake::scene::picture_main(argc - 1, argv + 1);
#else
  for (const char* tool : {"trade", "picture"})
    if (argc >= 2 && std::strcmp(argv[1], tool) == 0) {
      std::fprintf(stderr, "octscene: error: %s: not built (configure with -DOCTBAKE_ANALYSIS=ON)\n", tool);
      return 2;
    }
#endif
  return octbake::scene::cli_main(argc, argv);
}

// octbake: bakes meshes into ObjectTree files (docs/interface.md, "octbake").
// Exit status: 0 all baked, 1 an input failed, 2 bad usage.
#include <fcntl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstring>

#include "bake.h"
#include "cli.h"
#include "cli_util.h"  // octscene's: kFiniteNumber
#include "for_scene.h"
#include "import_child.h"
#include "octbake/collision_world.h"
#include "octbake/version.h"

int main(int argc, char** argv) {
  using namespace octbake;
  // This executable started again by itself to import one mesh (import_child.h).
  // _exit: its answer is written; no exit-time work (static destructors, a
  // sanitizer's leak report on what assimp left) can change its status.
  if (argc == 3 && std::strcmp(argv[1], kImportChildFlag) == 0) ::_exit(run_import_child(argv[2], STDOUT_FILENO));
  // Children are waited for (import_child.h): an inherited "ignore SIGCHLD"
  // would make the kernel reap them and hide how they ended.
  ::signal(SIGCHLD, SIG_DFL);
  CLI::App app{"Bakes meshes (any format assimp reads) into conservative octree files (.oct).", "octbake"};
  app.set_version_flag("--version", kLibraryVersion);

  BakeConfig config;
  config.jobs = usable_cores();
  std::vector<std::string> info_files;
  std::string occupancy = "surface", compress = "zstd:19";
  std::vector<std::string> occupancy_names;
  for (Occupancy mode : kOccupancies) occupancy_names.push_back(to_string(mode));
  bool quiet = false, json = false;

  // A path option given as '' is an error, not a silent default ("none" is the option left out).
  const CLI::Validator non_empty([](std::string& v) { return v.empty() ? std::string("an empty path") : std::string(); },
                                 "PATH");
  app.add_option("FILE", config.inputs, "Mesh files to bake");
  auto* out = app.add_option("-o,--out", config.out_dir, "One baked file per input: DIR/<stem>.oct")
                  ->check(non_empty)
                  ->capture_default_str();
  app.add_option("--pack", config.pack, "All inputs into this one pack file instead")->check(non_empty)->excludes(out);
  app.add_option("-d,--depth", config.options.depth, "Deepest level baked, 1..12")
      ->check(CLI::Range(1, 12))
      ->capture_default_str();
  app.add_option("--occupancy", occupancy, "surface|solid|vertices")
      ->check(CLI::IsMember(occupancy_names))
      ->capture_default_str();
  app.add_option("--compress", compress, "zstd[:LEVEL] (LEVEL 1..22) or none")
      ->check(CLI::Validator(
          [](std::string& v) { return parse_compression(v) ? std::string() : "expected zstd[:1..22] or none, got " + v; },
          "zstd[:LEVEL]|none"))
      ->capture_default_str();
  app.add_option("-j,--jobs", config.jobs,
                 "Threads: files baked in parallel, a large file's octants on the idle ones (default: all cores the process may run on)")->check(CLI::Range(1, 4096));
  app.add_flag("--force", config.force, "Rebake even when the output is up to date");
  auto* info = app.add_option("--info", info_files, "Print what baked files hold and exit");
  app.add_flag("--json", json, "With --info: one JSON document on stdout instead of text")->needs(info);
  app.add_option("--export-obj", config.export_obj_dir, "Also write each tree's boxes per depth as DIR/<stem>_d<depth>.obj")
      ->check(non_empty);
  app.add_flag("-q,--quiet", quiet, "No progress display and no summary line");
  std::string for_scene;
  app.add_option("--for-scene", for_scene, "Bake only the FILEs whose model SCENE.json names, each to the depth its run needs")
      ->check(non_empty);
  app.add_option("--import-timeout", config.import_timeout_s,
                 "Seconds an input's import may take before it fails (0: no limit); each import runs in a child process")
      ->check(CLI::NonNegativeNumber)
      ->check(scene::kFiniteNumber)
      ->capture_default_str();
  app.add_option("--depfile", config.depfile, "Also write FILE: a Make rule OUTPUT: every file the import read (one input; implies --force)")
      ->check(non_empty);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForVersion&) {
    std::printf("octbake %s\n", kLibraryVersion);
    return 0;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::string message = e.what();
    std::replace(message.begin(), message.end(), '\n', ' ');
    std::fprintf(stderr, "octbake: error: %s (see octbake --help)\n", message.c_str());
    return 2;
  }

  if (!info_files.empty()) {
    info_files.insert(info_files.end(), config.inputs.begin(), config.inputs.end());
    return print_info(info_files, stdout, stderr, json);
  }
  if (config.inputs.empty()) {
    std::fputs("octbake: error: no input files (see octbake --help)\n", stderr);
    return 2;
  }
  if (!config.depfile.empty() && (config.inputs.size() != 1 || !config.pack.empty())) {
    std::fputs("octbake: error: --depfile needs exactly one input and no --pack (see octbake --help)\n", stderr);
    return 2;
  }
  config.force = config.force || !config.depfile.empty();  // a build system asked: the output must change time
  config.options.occupancy = *parse_occupancy(occupancy);
  std::tie(config.options.compression, config.options.compression_level) = *parse_compression(compress);
  // Each import in a child process of this executable: an importer crash or
  // hang on one malformed file then fails that input alone.
  // Started through a descriptor opened now, not by path: the program file
  // may be deleted or replaced (a rebuild, an install) while this runs.
  // Under qemu-user the open gives the emulated program, not the emulator.
  const int self = ::open("/proc/self/exe", O_RDONLY | O_CLOEXEC);  // kept open to the end
  if (self >= 0) config.import_helper = "/proc/self/fd/" + std::to_string(self);
  config.progress = !quiet && ::isatty(STDERR_FILENO);
  config.summary = !quiet;
  if (!for_scene.empty()) return bake_for_scene(for_scene, config, stderr);
  const BakeSummary summary = run_bake(config, stderr);
  return summary.failed == 0 ? 0 : 1;
}

// octscene's command line: every subcommand in --help, --version, unknown
// subcommands named, every error one "octscene: error:" line, numbers
// range-checked.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <nlohmann/json.hpp>

#include "helpers.h"
#include "octbake/version.h"

namespace octbake::scene {
namespace {

using namespace octbake::scene::testing;
using nlohmann::json;

const std::string kOctscene = OCTSCENE_BIN;

std::string small_scene() {
  return json{{"format", "octbake-scene/1"},
              {"baked", "baked"},
              {"camera", {{"position", {0, 5, -30}}, {"look_at", {0, 0, 0}}}},
              {"world", {{"min", {-50, -50, -50}}, {"max", {50, 50, 50}}, {"depth", 3}}},
              {"timestep", 0.1},
              {"frames", 20},
              {"objects", {{{"name", "a"}, {"model", "cube"}, {"position", {0, 0, 0}}}}}}
      .dump();
}

// `r` exited with `status` and printed exactly one "octscene: error: " line
// holding `names`.
void expect_one_error(const Command& r, int status, const std::string& args, const std::string& names) {
  EXPECT_EQ(r.status, status) << args << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("octscene: error: ", 0), 0u) << args << "\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(names), std::string::npos) << args << "\n" << r.err;
}

TEST(Cli, HelpListsEverySubcommand) {
  const fs::path& dir = scratch_with_trees();
  Command c = run_command(kOctscene + " --help", dir);
  EXPECT_EQ(c.status, 0);
  for (const char* sub : {"run", "plan", "gen", "trade", "picture"})
    EXPECT_NE(c.out.find(std::string("\n  ") + sub + " "), std::string::npos) << sub << " missing in:\n" << c.out;
  for (const char* sub : {"run", "plan", "gen", "trade", "picture"})
    EXPECT_EQ(run_command(kOctscene + " " + sub + " --help", dir).status, 0) << sub;
}

TEST(Cli, VersionPrintsTheLibraryVersion) {
  Command c = run_command(kOctscene + " --version", scratch_with_trees());
  EXPECT_EQ(c.status, 0);
  EXPECT_EQ(c.out, std::string("octscene ") + kLibraryVersion + "\n");
}

TEST(Cli, UnknownSubcommandIsNamed) {
  Command c = run_command(kOctscene + " frobnicate x", scratch_with_trees());
  EXPECT_EQ(c.status, 2);
  EXPECT_EQ(c.err.rfind("octscene: error: unknown subcommand \"frobnicate\"", 0), 0u) << c.err;
}

// Each bad usage: exit 2 and exactly one line starting "octscene: error: ".
TEST(Cli, UsageErrorsAreOnePrefixedLine) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "cli.json", small_scene());
  const std::string scene = (dir / "cli.json").string();
  const std::string gen = "gen --static 1 --moving 1 --seed 1 --models cube --baked " + (dir / "baked").string();
  struct Case {
    std::string args, names;  // `names`: a part of the message
  };
  for (const Case& c : std::vector<Case>{
           {"", "subcommand"},
           {"run", "scene"},
           {"run " + scene + " --frames -5", "--frames"},
           {"run " + scene + " --frames 1000000000000", "--frames"},
           {"run " + scene + " --lod best", "--lod"},
           {"run " + scene + " --min-depth 13", "--min-depth"},
           {"run " + scene + " --min-depth 3 --max-depth 2", "--min-depth 3 is above --max-depth 2"},
           {"run " + scene + " --pixel-tolerance 0", "--pixel-tolerance"},
           {"plan " + scene + " --frames -1", "--frames"},
           {"gen --static 1 --moving 1 --seed 1", "--models"},
           {"gen --static -1 --moving 1 --seed 1 --models cube", "--static"},
           {"trade " + scene + " --frames -1", "--frames"},
           {"trade", "scene"},
           {"picture scene " + scene + " --out x.png --frame -1", "--frame"},
           {"picture scene " + scene + " --out x.png --frame 20", "--frame 20: past the scene's end"},
           {"picture", "subcommand"},
           // NaN passes CLI11's range checks (every comparison is false).
           {"run " + scene + " --pixel-tolerance nan", "--pixel-tolerance"},
           {"picture scene " + scene + " --out x.png --pixel-tolerance nan", "--pixel-tolerance"},
           {"picture scene " + scene + " --out x.png --min-depth 5 --max-depth 2",
            "--min-depth 5 is above --max-depth 2"},
           {gen + " --timestep nan", "--timestep"},
           {gen + " --world nan", "--world"},
           {gen + " --spin-share nan", "--spin-share"},
           {gen + " --scale-range 2,1", "--scale-range"},
           {gen + " --scale-range nan,1", "--scale-range"},
           // An empty path is refused, not taken as "none" or a default.
           {"run " + scene + " --log ''", "--log: an empty path"},
           {"run " + scene + " --baked ''", "--baked: an empty path"},
           {"run " + scene + " --write-budget ''", "--write-budget: an empty path"},
           {"trade " + scene + " --csv ''", "--csv: an empty path"},
           {"picture scene " + scene + " --out ''", "--out: an empty path"},
           {"gen --static 1 --moving 1 --seed 1 --models cube --baked ''", "--baked: an empty path"},
           // Options whose scene `run` would refuse (a far plane of 1e308 * 10).
           {gen + " --world 1e308", "run rejects"},
           {gen + " --spin-share 1 --spin-rate 1e308", "run rejects"}}) {
    expect_one_error(run_command(kOctscene + " " + c.args, dir), 2, c.args, c.names);
  }
}

// Inputs that are not files, or endless, are one error line, not a hang: a
// FIFO where a model or the scene should be, /dev/zero as the scene or the
// budget, and a scene's frame count beyond --frames' limit.
TEST(Cli, DevicesFifosAndHugeFrameCountsAreErrorsNotHangs) {
  const fs::path& dir = scratch_with_trees();
  const fs::path fifo_dir = dir / "fifo_baked";
  fs::create_directories(fifo_dir);
  fs::remove(fifo_dir / "cube.oct");
  ASSERT_EQ(::mkfifo((fifo_dir / "cube.oct").c_str(), 0600), 0);
  json scene = json::parse(small_scene());
  scene["baked"] = "fifo_baked";
  write_text(dir / "fifo.json", scene.dump());
  write_text(dir / "cli.json", small_scene());
  scene = json::parse(small_scene());
  scene["frames"] = int64_t{1} << 40;
  write_text(dir / "many_frames.json", scene.dump());
  fs::remove(dir / "scene.fifo");
  ASSERT_EQ(::mkfifo((dir / "scene.fifo").c_str(), 0600), 0);
  const std::string cli = (dir / "cli.json").string();
  struct Case {
    std::string args, names;
  };
  for (const Case& c : std::vector<Case>{
           {"run " + (dir / "fifo.json").string(), "cube.oct: not a regular file"},
           {"plan " + (dir / "fifo.json").string(), "cube.oct: not a regular file"},
           {"run /dev/zero", "/dev/zero: not a regular file or a pipe"},
           {"run " + cli + " --budget /dev/zero", "/dev/zero: not a regular file or a pipe"},
           {"run " + dir.string(), "not a regular file or a pipe"},
           {"run " + (dir / "many_frames.json").string(), "frames: must be in 0..100000000"},
           {"plan " + (dir / "many_frames.json").string(), "frames: must be in 0..100000000"}}) {
    // timeout: a regression hangs; it must not hang the suite.
    expect_one_error(run_command("timeout 60 " + kOctscene + " " + c.args, dir), 1, c.args, c.names);
  }
  // A pipe is read like a file (`octscene run <(...)`).
  Command piped = run_command("cat " + cli + " > " + (dir / "scene.fifo").string() + " & timeout 60 " + kOctscene +
                                  " run " + (dir / "scene.fifo").string() + " --summary json",
                              dir);
  EXPECT_EQ(piped.status, 0) << piped.err;
  EXPECT_NE(piped.out.find("\"collisions\""), std::string::npos) << piped.out;
}

// A write that fails on stdout or on --csv is an error, not exit 0.
TEST(Cli, FullDiskOnStdoutOrCsvIsAnError) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "cli.json", small_scene());
  const std::string scene = (dir / "cli.json").string();
  for (const std::string& args : {"run " + scene + " > /dev/full", "run " + scene + " --summary json > /dev/full",
                                  "plan " + scene + " --json > /dev/full", "plan " + scene + " > /dev/full",
                                  "trade " + scene + " --meshes " + dir.string() + " --frames 3 > /dev/full",
                                  "trade " + scene + " --meshes " + dir.string() + " --frames 3 --csv /dev/full > /dev/null"}) {
    const std::string line = kOctscene + " " + args + " 2>" + (dir / "full.err").string();
    const int raw = std::system(line.c_str());
    EXPECT_TRUE(WIFEXITED(raw) && WEXITSTATUS(raw) == 1) << args;
    const std::string err = read_text(dir / "full.err");
    EXPECT_NE(err.find("octscene: error: "), std::string::npos) << args << "\n" << err;
  }
}

// The last frame is drawable; the range check is not off by one.
TEST(Cli, LastFrameOfTheSceneIsAccepted) {
  const fs::path& dir = scratch_with_trees();
  write_text(dir / "cli.json", small_scene());
  Command c = run_command(kOctscene + " picture scene " + (dir / "cli.json").string() + " --meshes " + dir.string() +
                              " --frame 19 --width 64 --out " + (dir / "last.png").string(),
                          dir);
  EXPECT_EQ(c.status, 0) << c.err;
  EXPECT_TRUE(fs::exists(dir / "last.png"));
  c = run_command(kOctscene + " run " + (dir / "cli.json").string() + " --frames 0", dir);
  EXPECT_EQ(c.status, 0) << c.err;
}

}  // namespace
}  // namespace octbake::scene

// octscene's command line: every subcommand in --help, --version, unknown
// subcommands named, every error one "octscene: error:" line, numbers
// range-checked.
#include <gtest/gtest.h>

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
           {"picture", "subcommand"}}) {
    Command r = run_command(kOctscene + " " + c.args, dir);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("octscene: error: ", 0), 0u) << c.args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.names), std::string::npos) << c.args << "\n" << r.err;
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

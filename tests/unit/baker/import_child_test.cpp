// load_mesh_in_child: the same answer as load_mesh in process, byte for
// byte, on real and malformed files; and one error, never a crash or a hang,
// when the child crashes, hangs, or answers with garbage (helpers that do
// just that, as shell scripts).
#include "import_child.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>

#include "cli_test_util.h"

namespace octbake {
namespace {

using test::TempDir;
using test::write_text;
namespace fs = std::filesystem;

const fs::path kModels = "/usr/share/assimp/models";

// A /bin/sh helper whose body is `script`, executable.
std::string helper_script(const TempDir& t, const std::string& name, const std::string& script) {
  const std::string path = t / name;
  write_text(path, "#!/bin/sh\n" + script + "\n");
  ::chmod(path.c_str(), 0755);
  return path;
}

void expect_same(const Result<Mesh>& in_child, const std::vector<std::string>& child_files,
                 const Result<Mesh>& in_process, const std::vector<std::string>& process_files,
                 const std::string& path) {
  ASSERT_EQ(in_child.ok(), in_process.ok()) << path << ": " << (in_child ? in_process.error().message : in_child.error().message);
  EXPECT_EQ(child_files, process_files) << path;
  if (!in_process.ok()) {
    EXPECT_EQ(in_child.error().code, in_process.error().code) << path;
    EXPECT_EQ(in_child.error().message, in_process.error().message) << path;
    return;
  }
  ASSERT_EQ(in_child->positions.size(), in_process->positions.size()) << path;
  ASSERT_EQ(in_child->triangles.size(), in_process->triangles.size()) << path;
  // Bitwise: a bake's output depends on every bit of every position.
  EXPECT_EQ(std::memcmp(in_child->positions.data(), in_process->positions.data(),
                        in_process->positions.size() * sizeof(Eigen::Vector3d)), 0) << path;
  EXPECT_TRUE(in_child->triangles == in_process->triangles) << path;
}

TEST(ImportChild, AnswersExactlyAsTheImportInProcess) {
  TempDir t;
  std::vector<std::string> inputs;
  for (const auto& entry : fs::directory_iterator(fs::path(OCTBAKE_SOURCE_DIR) / "assets"))
    if (entry.path().extension() == ".obj") inputs.push_back(entry.path());
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    inputs.push_back(t / ("soup" + std::to_string(seed) + ".obj"));
    write_text(inputs.back(), test::random_obj(seed, 50 * int(seed), 0.2));
  }
  // Refusals travel too: code and message.
  write_text(t / "nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write_text(t / "lines.obj", "v 0 0 0\nv 1 1 1\nl 1 2\n");
  write_text(t / "garbage.ply", "ply\nformat ascii 1.0\nelement vertex 99\n");
  for (const char* name : {"nan.obj", "lines.obj", "garbage.ply", "missing.obj"}) inputs.push_back(t / name);
  for (const char* name : {"ply_no_end_header_segv.ply", "ply_no_end_header_hang.ply"})
    inputs.push_back(std::string(OCTBAKE_SOURCE_DIR) + "/tests/hostile/" + name);
  // Real meshes nobody here made, and assimp's own invalid files.
  if (fs::exists(kModels))
    for (const char* dir : {"OBJ", "PLY", "STL", "OFF", "invalid"})
      for (const auto& entry : fs::recursive_directory_iterator(kModels / dir))
        if (entry.is_regular_file() && entry.path().filename() != "OutOfMemory.off" && entry.file_size() < (1 << 20))
          inputs.push_back(entry.path());
  ASSERT_GT(inputs.size(), 15u);

  int meshes = 0;
  for (const std::string& path : inputs) {
    std::vector<std::string> child_files, process_files;
    const Result<Mesh> in_child = load_mesh_in_child(OCTBAKE_BIN, path, &child_files, 60);
    const Result<Mesh> in_process = load_mesh(path, &process_files);
    expect_same(in_child, child_files, in_process, process_files, path);
    meshes += in_process.ok();
  }
  EXPECT_GE(meshes, 10) << "too few inputs imported to compare meshes";
}

TEST(ImportChild, ACrashHangOrGarbageIsOneErrorNamingTheFile) {
  TempDir t;
  const std::string mesh = t / "mesh.obj";
  write_text(mesh, test::random_obj(3, 10, 0.2));
  struct Case {
    std::string helper, script;
    std::string reason;  // the message after "PATH: "
  };
  const std::string real = OCTBAKE_BIN;
  const std::string unparented = "env -u OCTBAKE_IMPORT_PARENT \"" + real + "\" \"$1\" \"$2\"";
  const Case cases[] = {
      {"segv", "kill -SEGV $$", "the importer crashed on this file (SIGSEGV)"},
      {"abort", "echo 'ai_assert failure' >&2; kill -ABRT $$", "the importer crashed on this file (SIGABRT)"},
      {"other_signal", "kill -USR1 $$", "the importer crashed on this file (signal 10)"},
      {"hang", "exec sleep 30", "the importer did not finish within 0.3 s (see --import-timeout)"},
      {"silent_hang", "exec sleep 30 >/dev/null", "the importer did not finish within 0.3 s (see --import-timeout)"},
      {"exit3", "exit 3", "the importer stopped without a result (exit status 3)"},
      {"garbage", "echo hello", "the importer gave a malformed answer"},
      {"nothing", "exit 0", "the importer gave a malformed answer"},
      // A real answer cut short, and one with a byte too many (the real
      // child below the shell is not the test's child: it is told so).
      {"truncated", unparented + " | head -c 100", "the importer gave a malformed answer"},
      {"trailing", unparented + "; printf x", "the importer gave a malformed answer"},
      // A child whose parent is not the one that started it stops at once.
      {"orphan", "\"" + real + "\" \"$1\" \"$2\"", "the importer stopped without a result (exit status 1)"},
  };
  for (const Case& c : cases) {
    const std::string helper = helper_script(t, c.helper, c.script);
    std::vector<std::string> files;
    const Result<Mesh> r = load_mesh_in_child(helper, mesh, &files, 0.3);
    ASSERT_FALSE(r.ok()) << c.helper;
    EXPECT_EQ(r.error().code, ErrorCode::invalid_argument) << c.helper;
    EXPECT_EQ(r.error().message, mesh + ": " + c.reason) << c.helper;
    EXPECT_TRUE(files.empty()) << c.helper << ": files read came from a failed child";
  }
  // A helper that is a real answer passed through: the mesh arrives, also
  // with limits so long that they would overflow the clock (no limit).
  const std::string relay = helper_script(t, "relay", "exec \"" + real + "\" \"$1\" \"$2\"");
  for (const double timeout_s : {30.0, 1e10, 1e300}) {
    std::vector<std::string> files;
    const Result<Mesh> relayed = load_mesh_in_child(relay, mesh, &files, timeout_s);
    ASSERT_TRUE(relayed.ok()) << timeout_s << ": " << relayed.error().message;
    EXPECT_EQ(relayed->triangles.size(), 10u);
    EXPECT_EQ(files, std::vector<std::string>{fs::path(mesh).lexically_normal().string()});
  }
}

TEST(ImportChild, NoChildMeansTheImportRunsInProcess) {
  TempDir t;
  const std::string mesh = t / "mesh.obj";
  write_text(mesh, test::random_obj(4, 12, 0.2));
  // A helper that is a folder, and one that starts but cannot run (what a
  // failed exec looks like under qemu-user: status 127, no answer).
  const std::string cannot_run = helper_script(t, "cannot_run", "exit 127");
  for (const std::string& helper : {t / "no_such_helper", t.path().string(), cannot_run}) {
    const Result<Mesh> r = load_mesh_in_child(helper, mesh, nullptr, 1);
    ASSERT_TRUE(r.ok()) << helper << ": " << r.error().message;
    EXPECT_EQ(r->triangles.size(), 12u);
  }
}

}  // namespace
}  // namespace octbake

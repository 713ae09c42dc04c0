// Mesh import in a child process. assimp can crash (a segfault, an
// ai_assert abort) or never finish on a malformed file; in a child that
// costs only that input: the parent reports one error and bakes the rest.
// The child is the octbake executable itself, started again as
// `octbake --internal-import PATH`, so it holds no lock of the parent's.
#pragma once
#include <string>
#include <vector>

#include "octbake/baker.h"  // Mesh, load_mesh

namespace octbake {

// argv[1] of a child started by load_mesh_in_child.
inline constexpr const char* kImportChildFlag = "--internal-import";

// The child's side: load_mesh(path), its files read and its result written
// to `out_fd` (a pipe). Returns the exit status (0 when the result, success
// or error, was written whole).
int run_import_child(const char* path, int out_fd);

// What load_mesh(path, files_read) returns, worked out by `helper`
// (an executable that runs run_import_child for `helper kImportChildFlag
// PATH`). A child killed by a signal, gone without a result, or still
// running after `timeout_s` (0: no limit; it is then killed) gives an
// invalid_argument error naming `path`. When no child can be started (no
// such helper, a process limit, an emulator that cannot start one: exit
// status 127 without an answer), the mesh is loaded in this process.
Result<Mesh> load_mesh_in_child(const std::string& helper, const std::string& path,
                                std::vector<std::string>* files_read, double timeout_s);

}  // namespace octbake

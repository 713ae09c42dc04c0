// `octbake --for-scene SCENE FILE...`: bakes, of the given files, only those
// whose model the scene names (model "x" comes from a file with stem "x",
// as `octbake -o DIR` names DIR/x.oct), each only to the depth the scene's
// run needs (octscene plan, with `octscene run`'s default options).
//
// How: the chosen files are baked to config.options.depth into a temporary
// folder, the scene is run on those trees (octscene_driver's plan_scene),
// then each file is baked into config.out_dir at its planned depth (at least
// 1). When a file fails to bake or a model has no file, the scene cannot be
// planned: the files that bake are then baked to config.options.depth, with
// a note each. Levels 1..d of a tree do not depend on the depth it was baked to
// (surface and vertices occupancy), so a run of the scene on the reduced
// files gives the same log as on full ones.
//
// Lives in the octbake executable, not the octbake_baker library: it needs
// the scene parser and run loop (octscene_driver), which the baker library
// must not depend on (octscene's analysis tools link the baker library).
#pragma once
#include <cstdio>
#include <string>

#include "bake.h"

namespace octbake {

// Prints one "octbake: note: PATH: ..." line per skipped file and per baked
// model (its depth and decoded bytes), and "octbake: error: PATH: REASON"
// lines for failures (a bad scene, a model no input provides, a failed bake).
// Returns the exit status: 0 all needed files baked, 1 a failure, 2 bad usage
// (--pack, which would hold every tree at one depth).
int bake_for_scene(const std::string& scene_path, const BakeConfig& config, std::FILE* err);

}  // namespace octbake

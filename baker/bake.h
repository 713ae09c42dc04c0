// The baker's job logic behind `octbake FILE...` (docs/interface.md, "octbake"):
// per-input bake on a small thread pool, up-to-date check, pack mode, OBJ
// export, progress. main.cpp only parses the command line.
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "octbake/format.h"
#include "octbake/result.h"

namespace octbake {

struct BakeConfig {
  std::vector<std::string> inputs;
  std::string out_dir = "baked";   // one DIR/<stem>.oct per input
  std::string pack;                // non-empty: all trees in this one file instead
  BakeOptions options;
  int jobs = 1;                    // >= 1 threads in all: files in parallel, and the
                                   // octants of a file on threads no file needs
  bool force = false;              // rebake even when up to date
  std::string export_obj_dir;      // non-empty: also DIR/<stem>_d<depth>.obj
  bool progress = false;           // updating progress line on the error stream (a terminal)
  bool summary = false;            // one summary line on the error stream at the end
  std::string depfile;             // non-empty (one input, no pack): write "OUTPUT: FILES READ" here
  std::string import_helper;       // non-empty: import each mesh in a child process of this
                                   // executable (import_child.h), so a crash costs one input
  double import_timeout_s = 120;   // with import_helper: a child still importing is killed (0: never)
};

struct BakeSummary {
  int baked = 0;
  int up_to_date = 0;
  int failed = 0;                  // inputs (and a pack) that failed
  uint64_t triangles = 0;          // of the meshes baked in this run
  std::vector<std::string> errors; // the lines printed, in input order
};

// Bakes every input. Each failure prints exactly one line
// "octbake: error: PATH: REASON" to `err`, in input order, and every other
// input is still baked. Output bytes depend only on the inputs and options,
// never on `jobs` or scheduling. The same file named twice is baked once;
// two inputs that would write the same output (or, for a pack, the same tree
// name) both fail and neither is written.
BakeSummary run_bake(const BakeConfig& config, std::FILE* err);

// Writes DIR/<name>_d<d>.obj for d = 0..masks.depth(): every occupied box of
// depth d as 8 vertices and 6 outward quads. Deterministic text.
Result<uint64_t> export_obj(const OctreeMasks& masks, const std::string& name, const std::string& dir);
// The OBJ text of one depth (what export_obj writes).
std::string obj_text(const OctreeMasks& masks, const std::string& name, int depth);

}  // namespace octbake

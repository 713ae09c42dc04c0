// Command-line pieces of `octbake` that are not baking: option values,
// --info, and the text of the progress and summary lines. (main.cpp wires
// them to CLI11; bake.h does the baking.)
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "octbake/format.h"
#include "octbake/result.h"

namespace octbake {

// The reason of `e` without a leading "PATH: " (runtime messages name the
// file; the baker's error lines put the path in front themselves).
std::string error_reason(const Error& e, const std::string& path);

// "zstd" (level 19), "zstd:LEVEL" (1..22) or "none" (level 0); nullopt when
// malformed or out of range.
std::optional<std::pair<Compression, int>> parse_compression(const std::string& text);

// "surface", "solid" or "vertices".
std::optional<Occupancy> parse_occupancy(const std::string& text);

// Prints, for every file, what the runtime sees in it (read through
// BakedFile, every level decoded): per tree its name, source hash, bounds,
// options, baker and format version, and per depth the occupied boxes, stored
// and raw bytes and the leaf box size. A file that cannot be read prints
// nothing to `out` and one line "octbake: error: PATH: REASON" to `err`.
// Returns the exit status: 0, or 1 when any file failed.
//
// With `json`, `out` gets one JSON document instead (always, even when every
// file failed; errors still go to `err` as lines):
//   {"files": [{"path", "format_version", "baker_version", "trees": [{
//      "name", "source_hash", "depth", "triangles", "vertices",
//      "options": {"depth", "occupancy", "compression", "compression_level"},
//      "bounds": {"min": [x, y, z], "max": [x, y, z]},
//      "levels": [{"depth", "boxes", "stored_bytes", "raw_bytes",
//                  "leaf_size": [x, y, z]}, ...],   // depth 0..depth
//      "stored_bytes", "raw_bytes"}]}]}              // totals over the levels
// Numbers are exact: integers as integers, doubles with round-trip precision.
int print_info(const std::vector<std::string>& files, std::FILE* out, std::FILE* err, bool json = false);

// 1234 -> "1234", 12345 -> "12.3K", 1.5e6 -> "1.5M" (rates and counts).
std::string human_count(double n);

// 42 -> "42 s", 125 -> "2 min 05 s", 7300 -> "2 h 01 min" (rounded down).
std::string human_duration(double seconds);

// What the progress line shows: files, and triangles of the meshes being or
// already baked in this run (a mesh in progress counts the finished share of
// its triangles), `seconds` after the start.
struct ProgressCounts {
  size_t files_done = 0, files_total = 0;
  size_t files_waiting = 0;      // not imported yet, so their size is unknown
  double triangles_done = 0;
  double triangles_known = 0;    // of the finished and the in-progress meshes
  size_t files_writing = 0;      // built, being compressed and written (not timed)
  double seconds = 0;
};

// The updating line on a terminal, e.g.
//   "baking 1/3 files, 35.2K/70.3K tri, 12.1K tri/s, ETA 3 s".
// The rate is triangles_done / seconds (none before any triangle is done);
// the ETA, (triangles_known - triangles_done) / rate, of the octree builds
// left, only once no file is waiting (the work of files not yet read is
// unknown) and while some build is left. Files past their build add
// ", writing N" (compression time is not predicted).
std::string progress_line(const ProgressCounts& c);

// The final line, e.g. "octbake: 5 baked, 0 up to date, 1 failed in 0.42 s (1.2M tri/s)":
// the rate is the triangles of the meshes baked over the whole run's time.
std::string summary_line(int baked, int up_to_date, int failed, double seconds, uint64_t triangles);

}  // namespace octbake

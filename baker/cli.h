// Command-line pieces of `octbake` that are not baking: option values and
// --info. (main.cpp wires them to CLI11; bake.h does the baking.)
#pragma once
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
int print_info(const std::vector<std::string>& files, std::FILE* out, std::FILE* err);

}  // namespace octbake

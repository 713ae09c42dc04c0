// Output side of the baker: the source hash and crash-safe file writes.
#pragma once
#include <cstdint>
#include <span>
#include <string>

#include "octbake/result.h"

namespace octbake {

// Hex XXH3-128 of the file's bytes (32 lowercase hex digits, canonical big
// endian, so the same on every machine). Only this file is hashed: files it
// refers to (an OBJ's .mtl, a glTF's .bin) are not. Errors: not_found, io_error
// (including "is a directory"); the message is the reason, without the path.
Result<std::string> hash_file(const std::string& path);
// The same hash of bytes in memory.
std::string hash_bytes(std::span<const uint8_t> bytes);

// Writes `bytes` to `path` atomically: a temp file `.<name>.tmp.<pid>.<n>` in
// the same folder (O_EXCL), fsync, rename over `path`, fsync the folder. A
// reader (or a crash) sees the old file or the complete new one, never a part.
// On failure the temp file is removed and `path` is untouched. Returns the
// number of bytes written; the error message is the reason, without the path.
Result<uint64_t> write_file_atomic(const std::string& path, std::span<const uint8_t> bytes);

// True for names of our own temp pattern, `.<name>.tmp.<pid>.<n>`; `pid` gets
// the writer's process id.
bool is_temp_name(const std::string& file_name, long* pid);

// Removes temp files of our pattern in `dir` whose writer process is gone
// (left by a killed baker). Best effort; returns how many were removed.
int remove_stale_temps(const std::string& dir);

}  // namespace octbake

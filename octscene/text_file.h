// Reading a text input (a scene, a budget) whole, safely: the path must be a
// regular file or a pipe (`octscene run <(octscene gen ...)`), and no more than
// max_bytes are read, so /dev/zero, a directory or an endless pipe is one
// clear error instead of a hang or an exhausted memory.
#pragma once
#include <cstddef>
#include <string>

#include "octbake/result.h"

namespace octbake::scene {

// Errors: "PATH: cannot open: REASON", "PATH: not a regular file or a pipe",
// "PATH: larger than N bytes", "PATH: read failed: REASON".
Result<std::string> read_text_file(const std::string& path, size_t max_bytes);

}  // namespace octbake::scene

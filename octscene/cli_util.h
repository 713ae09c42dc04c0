// Command-line conventions shared by every octscene subcommand (main.cpp,
// trade, picture): errors are one line "octscene: error: ..." on stderr.
#pragma once
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

namespace octbake::scene {

// What a CLI11 parse error becomes: --help and --version print and give 0;
// anything else is one error line pointing at `command --help`, exit 2.
inline int parse_error_exit(const CLI::App& app, const CLI::ParseError& e, const std::string& command) {
  if (e.get_exit_code() == 0) return app.exit(e);
  std::string message = e.what();
  std::replace(message.begin(), message.end(), '\n', ' ');
  std::fprintf(stderr, "octscene: error: %s (see %s --help)\n", message.c_str(), command.c_str());
  return 2;
}

// name -> value for CLI11's CheckedTransformer, from the enum's own list and
// to_string (octbake/lod.h, world.h): one place for each vocabulary.
template <class Enum, size_t N>
std::map<std::string, Enum> names_of(const Enum (&values)[N]) {
  std::map<std::string, Enum> m;
  for (Enum v : values) m.emplace(to_string(v), v);
  return m;
}

// CLI11's number validators let NaN through (every comparison with NaN is
// false): options that take a real number also check this.
inline const CLI::Validator kFiniteNumber(
    [](std::string& text) -> std::string {
      double value = 0;
      if (!CLI::detail::lexical_cast(text, value)) return "not a number: " + text;
      return std::isfinite(value) ? std::string() : "must be a finite number, got " + text;
    },
    "FINITE");

// Whether everything printed to stdout reached it: a write that failed while
// the buffer drained (a full disk, /dev/full) leaves only the error flag.
inline bool stdout_written() { return std::fflush(stdout) == 0 && !std::ferror(stdout); }

// A path option given as '' is an error, not silently "no file" (the
// defaults that mean "none" are the option left out).
inline const CLI::Validator kNonEmptyPath(
    [](std::string& text) { return text.empty() ? std::string("an empty path") : std::string(); }, "PATH");

// --min-depth above --max-depth is a usage error wherever both are taken.
inline bool depth_range_error(int min_depth, int max_depth) {
  if (min_depth <= max_depth) return false;
  std::fprintf(stderr, "octscene: error: --min-depth %d is above --max-depth %d\n", min_depth, max_depth);
  return true;
}

}  // namespace octbake::scene

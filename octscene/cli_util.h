// Command-line conventions shared by every octscene subcommand (main.cpp,
// trade, picture): errors are one line "octscene: error: ..." on stderr.
#pragma once
#include <CLI/CLI.hpp>
#include <algorithm>
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

// Largest --frames / --frame accepted: run keeps one time per frame.
constexpr int64_t kMaxFrames = 100'000'000;

}  // namespace octbake::scene

// Command-line conventions shared by every octscene subcommand (main.cpp,
// trade, picture): errors are one line "octscene: error: ..." on stderr.
#pragma once
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
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

// Largest --frames / --frame accepted: run keeps one time per frame.
constexpr int64_t kMaxFrames = 100'000'000;

}  // namespace octbake::scene

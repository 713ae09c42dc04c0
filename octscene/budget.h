// Start-up budgets (`octscene run --frames 0 --budget FILE.json`): the
// deterministic work of loading a scene's trees, compared with ceilings
// committed next to an app so a regression fails its tests.
//
// Budget file:
//   {"format": "octbake-startup-budget", "version": 1,
//    "counters": {"files_opened": 5, "bytes_mapped": 51234, ...}}
// with every counter of StartupCounters, each a non-negative integer.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "octbake/baked_file.h"
#include "octbake/result.h"

namespace octbake::scene {

// Work done while loading (ModelLibrary::open through load_scene_models).
// Every counter is the same on every run of the same scene and files.
struct StartupCounters {
  uint64_t files_opened = 0;
  uint64_t bytes_mapped = 0;
  uint64_t levels_decoded = 0;
  uint64_t bytes_decompressed = 0;
  uint64_t heap_allocations = 0;  // operator new calls (counted by the octscene executable)
};

// The counters a library's stats hold (heap_allocations left 0).
StartupCounters counters_from(const LoadStats& stats);

// (name, value) of every counter, in the budget file's order.
std::vector<std::pair<std::string, uint64_t>> counter_list(const StartupCounters& c);

// The budget file text for `c` (ends with '\n').
std::string budget_text(const StartupCounters& c);

// Strict: wrong format or version, a missing, unknown, negative or
// non-integer counter are errors naming `label` and the key.
Result<StartupCounters> parse_budget(const std::string& text, const std::string& label);
Result<StartupCounters> read_budget(const std::string& path);
// Error io_error naming the path when it cannot be written.
Result<bool> write_budget(const std::string& path, const StartupCounters& c);

// One message per counter above its budget, in counter order, e.g.
// "budget exceeded: bytes_decompressed 4242 > 4241 (budget.json)"; empty
// when every counter is within budget.
std::vector<std::string> budget_excess(const StartupCounters& measured, const StartupCounters& budget,
                                       const std::string& budget_label);

}  // namespace octbake::scene

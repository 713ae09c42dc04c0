// `octscene trade SCENE [options]`: the speed/accuracy trade of every LOD
// setting against an exact mesh-mesh answer. Parses its own arguments
// (argv[0] == "trade"); returns the exit status.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "octbake/baked_file.h"
#include "octbake/lod.h"
#include "octbake/result.h"
#include "scene.h"

namespace octbake::scene {

int trade_main(int argc, char** argv);

// The same measurement as a library call (tests use it).
struct TradeOptions {
  std::string meshes = "assets";  // folder of source meshes
  int64_t frames = -1;            // < 0: the scene's
  int max_depth = 0;              // 0: deepest baked depth of the scene's trees
  int threads = 1;                // World::step() workers (>= 1); scores do not depend on it
};

// One LOD setting's score over all frames.
struct TradeRow {
  std::string label;  // "fixed 3", "thesis 1-5", "screen 2px"
  LodSettings lod;
  uint64_t true_positives = 0, false_positives = 0, false_negatives = 0;
  std::map<std::pair<int, int>, uint64_t> false_positives_by_depth;  // (lo, hi)
  double box_tests_per_frame = 0;
  double ms_per_frame = 0;  // World::step() alone
  double precision() const;  // 1 when nothing was reported
  double recall() const;     // 1 when nothing was to be found
};

// A reported pair the exact test finds but a setting missed: always a bug.
struct Miss {
  std::string setting;
  int64_t frame = 0;
  uint32_t a = 0, b = 0;  // object indices
  int depth_a = 0, depth_b = 0;
};

struct TradeReport {
  int64_t frames = 0;
  uint64_t exact_contacts = 0;  // pairs in contact, summed over frames
  uint64_t exact_tests = 0;     // pairs whose world boxes overlapped (tested exactly)
  std::vector<TradeRow> rows;
  std::vector<Miss> misses;     // first few false negatives, for the report
  std::vector<std::string> warnings;  // e.g. mesh hash differs from the baked one
};

Result<TradeReport> run_trade(const Scene& scene, ModelLibrary& library, const TradeOptions& options);

// The --plot SVG: cost (box tests, and time) per frame on a log axis against
// precision, one point per setting coloured by policy, with a legend, a title
// computed from the report, and labels placed so none overlaps another label
// or a point, and none leaves its plot (labels are class='label' text).
std::string trade_svg(const TradeReport& report, const std::string& scene_name);

}  // namespace octbake::scene

// `octscene trade`: every LOD setting scored against FCL's exact mesh-mesh
// answer. With --response none every setting sees the same motion, so the
// exact answer is computed once per frame (during the first setting's run)
// and reused; later runs check that the poses really are the same.
#include "trade.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <span>
#include <sstream>

#include "cli_util.h"
#include "exact.h"
#include "octbake/collision_world.h"
#include "run.h"

namespace octbake::scene {

double TradeRow::precision() const {
  const uint64_t reported = true_positives + false_positives;
  return reported == 0 ? 1.0 : double(true_positives) / double(reported);
}

double TradeRow::recall() const {
  const uint64_t real = true_positives + false_negatives;
  return real == 0 ? 1.0 : double(true_positives) / double(real);
}

namespace {

constexpr int kDefaultDepthCap = 8;  // deeper fixed runs cost much and teach little
constexpr size_t kMissesKept = 20;
constexpr double kScreenTolerances[] = {0.5, 1, 2, 4, 8};

std::vector<TradeRow> settings_for(int max_depth) {
  std::vector<TradeRow> rows;
  for (int d = 1; d <= max_depth; ++d) {
    TradeRow r;
    r.label = "fixed " + std::to_string(d);
    r.lod = {LodPolicy::fixed, /*min_depth=*/d, /*max_depth=*/d, /*pixel_tolerance=*/1.0};
    rows.push_back(r);
  }
  TradeRow thesis;
  thesis.label = "thesis 1-" + std::to_string(max_depth);
  thesis.lod = {LodPolicy::thesis, /*min_depth=*/1, max_depth, /*pixel_tolerance=*/1.0};
  rows.push_back(thesis);
  for (double px : kScreenTolerances) {
    TradeRow r;
    char label[32];
    std::snprintf(label, sizeof label, "screen %gpx", px);
    r.label = label;
    r.lod = {LodPolicy::screen, /*min_depth=*/1, max_depth, px};
    rows.push_back(r);
  }
  return rows;
}

uint64_t hash_poses(std::span<const Pose> poses) {
  uint64_t h = 1469598103934665603ull;  // FNV-1a
  auto mix = [&h](double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    for (int i = 0; i < 8; ++i) {
      h ^= (bits >> (8 * i)) & 0xffu;
      h *= 1099511628211ull;
    }
  };
  for (const Pose& p : poses) {
    for (int i = 0; i < 3; ++i) mix(p.position[i]);
    mix(p.rotation.x()), mix(p.rotation.y()), mix(p.rotation.z()), mix(p.rotation.w()), mix(p.scale);
  }
  return h;
}

std::string depth_pairs_text(const std::map<std::pair<int, int>, uint64_t>& counts) {
  std::string s;
  for (const auto& [dp, n] : counts) {
    if (!s.empty()) s += ' ';
    s += std::to_string(dp.first) + '-' + std::to_string(dp.second) + ':' + std::to_string(n);
  }
  return s.empty() ? "-" : s;
}

// Where the scene reaches past what the exact side computes reliably
// (kExactCoordinateLimit): an object's scaled mesh, its start, the distance
// it can travel in the run, or the world box it moves in. The score would
// otherwise count FCL's overflow as octbake's misses.
std::optional<std::string> beyond_exact_range(const Scene& scene, std::span<const int> mesh_of_object,
                                              std::span<const Aabb> local_bounds) {
  auto limit_text = [](double v) {
    std::ostringstream s;
    s << std::setprecision(3) << v;
    return s.str();
  };
  const double world = std::max(scene.world.min.cwiseAbs().maxCoeff(), scene.world.max.cwiseAbs().maxCoeff());
  if (!(world <= kExactCoordinateLimit))
    return "world box reaches " + limit_text(world) + ", past the " + limit_text(kExactCoordinateLimit) +
           " the exact reference (FCL) computes with reliably";
  const double duration = double(scene.frames) * scene.timestep;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    const Aabb& b = local_bounds[size_t(mesh_of_object[i])];
    const double mesh = o.pose.scale * std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff());
    const double reach = mesh + o.pose.position.cwiseAbs().maxCoeff() + o.velocity.cwiseAbs().maxCoeff() * duration;
    if (!(reach <= kExactCoordinateLimit))
      return "object \"" + o.name + "\" reaches " + limit_text(reach) + ", past the " +
             limit_text(kExactCoordinateLimit) + " the exact reference (FCL) computes with reliably";
  }
  return std::nullopt;
}

}  // namespace

Result<TradeReport> run_trade(const Scene& scene, ModelLibrary& library, const TradeOptions& options) {
  auto models = load_scene_models(scene, library, /*depth=*/12);
  if (!models) return models.error();
  int baked_depth = 0;
  for (const ObjectTree& t : models->trees) baked_depth = std::max(baked_depth, t.info().depth);
  const int max_depth = options.max_depth > 0 ? std::min(options.max_depth, baked_depth)
                                              : std::min(baked_depth, kDefaultDepthCap);
  if (max_depth < 1) return Error{ErrorCode::invalid_argument, "no depth to test (baked depth 0)"};

  TradeReport report;
  // Source meshes, one per model name, in the order of models->names.
  ExactMeshes meshes;
  std::vector<Aabb> local_bounds;
  for (size_t k = 0; k < models->names.size(); ++k) {
    const std::string& name = models->names[k];
    const std::string path = find_mesh(options.meshes, name);
    if (path.empty()) {
      return Error{ErrorCode::not_found, "no mesh for model \"" + name + "\" in " + options.meshes +
                                             " (tried .obj .ply .stl .off .gltf .glb .dae .fbx); use --meshes DIR"};
    }
    auto mesh = load_mesh(path);  // the error names the path
    if (!mesh) return mesh.error();
    const std::string& baked_hash = models->trees[k].info().source_hash;
    auto hash = source_hash(path);
    if (hash && *hash != baked_hash) {
      report.warnings.push_back("mesh " + path + " hashes to " + *hash + " but tree \"" + name +
                                "\" was baked from a file hashing to " + baked_hash);
    }
    // The tree's root box is the baked mesh's bounds: a mismatch means the
    // mesh is not the one that was baked, and the score would be meaningless.
    const Aabb bounds = mesh_bounds(*mesh);
    const Aabb& baked = models->trees[k].info().bounds;
    if (!bounds.min.isApprox(baked.min, 1e-9) || !bounds.max.isApprox(baked.max, 1e-9)) {
      report.warnings.push_back("mesh " + path + " has other bounds than the baked tree \"" + name +
                                "\": the score compares different shapes");
    }
    local_bounds.push_back(bounds);
    meshes.add(std::move(*mesh));
  }
  std::vector<int> mesh_of_object(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) mesh_of_object[i] = static_cast<int>(models->tree_of_object[i]);
  if (auto problem = beyond_exact_range(scene, mesh_of_object, local_bounds)) return Error{ErrorCode::invalid_argument, *problem};

  std::vector<PairList> exact;        // per frame
  std::vector<uint64_t> pose_hashes;  // per frame, from the first run
  report.rows = settings_for(max_depth);
  for (size_t s = 0; s < report.rows.size(); ++s) {
    TradeRow& row = report.rows[s];
    RunOptions run;
    run.lod = row.lod;
    run.response = Response::none;
    run.frames = options.frames;
    run.report_poses = true;
    run.threads = options.threads;
    bool motion_differs = false;
    auto on_frame = [&](const FrameReport& f) {
      const size_t fi = static_cast<size_t>(f.frame);
      if (s == 0) {
        ExactFrame e = exact_frame(f.poses, mesh_of_object, local_bounds, meshes);
        report.exact_tests += e.tested;
        report.exact_contacts += e.contacts.size();
        exact.push_back(std::move(e.contacts));
        pose_hashes.push_back(hash_poses(f.poses));
      } else if (fi >= pose_hashes.size() || pose_hashes[fi] != hash_poses(f.poses)) {
        motion_differs = true;
        return;
      }
      // Merge the sorted reported pairs with the sorted exact ones.
      const PairList& truth = exact[fi];
      size_t t = 0;
      for (const Collision& c : f.collisions) {
        const std::pair<uint32_t, uint32_t> p{c.a, c.b};
        for (; t < truth.size() && truth[t] < p; ++t) {
          ++row.false_negatives;
          if (report.misses.size() < kMissesKept) {
            report.misses.push_back({row.label, f.frame, truth[t].first, truth[t].second,
                                     f.world->depth(truth[t].first), f.world->depth(truth[t].second)});
          }
        }
        if (t < truth.size() && truth[t] == p) {
          ++row.true_positives;
          ++t;
        } else {
          ++row.false_positives;
          ++row.false_positives_by_depth[{std::min(c.depth_a, c.depth_b), std::max(c.depth_a, c.depth_b)}];
        }
      }
      for (; t < truth.size(); ++t) {
        ++row.false_negatives;
        if (report.misses.size() < kMissesKept) {
          report.misses.push_back({row.label, f.frame, truth[t].first, truth[t].second,
                                   f.world->depth(truth[t].first), f.world->depth(truth[t].second)});
        }
      }
    };
    auto result = run_scene(scene, *models, run, on_frame);
    if (!result) return result.error();
    if (motion_differs) {
      return Error{ErrorCode::invalid_argument, "setting \"" + row.label +
                                                    "\" saw other poses than the first run: motion under "
                                                    "--response none must not depend on the LOD"};
    }
    report.frames = result->frames;
    const double frames = std::max<double>(1.0, double(result->frames));
    row.box_tests_per_frame = double(result->box_tests) / frames;
    row.ms_per_frame = result->frame_ms_mean;
  }
  return report;
}

namespace {

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

const char* policy_color(LodPolicy p) {
  switch (p) {
    case LodPolicy::fixed: return "#1f77b4";
    case LodPolicy::thesis: return "#2ca02c";
    case LodPolicy::screen: return "#ff7f0e";
  }
  return "#000";
}

// Shortest text of a double for SVG attributes (locale independent).
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

struct Box {
  double x0, y0, x1, y1;
  bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  bool inside(const Box& o) const { return x0 >= o.x0 && x1 <= o.x1 && y0 >= o.y0 && y1 <= o.y1; }
};

// Places each point's label where it overlaps no other label, no point and
// stays inside `area`: next to the point first, then further up or down with
// a leader line. Greedy, in row order; deterministic.
struct LabelPlacer {
  Box area;
  std::vector<Box> taken;  // points and placed labels

  // Returns the label's box; `leader` is set when it sits away from the point.
  Box place(double px, double py, double w, double h, bool* leader) {
    const double gap = 6;
    std::vector<std::pair<double, double>> corners;  // top-left candidates, nearest first
    corners.push_back({px + gap, py - h / 2});         // right
    corners.push_back({px - gap - w, py - h / 2});     // left
    corners.push_back({px - w / 2, py - gap - h});     // above
    corners.push_back({px - w / 2, py + gap});         // below
    corners.push_back({px + gap, py - gap - h});       // upper right
    corners.push_back({px + gap, py + gap});           // lower right
    corners.push_back({px - gap - w, py - gap - h});   // upper left
    corners.push_back({px - gap - w, py + gap});       // lower left
    const size_t near = corners.size();
    for (int k = 1; k <= 24; ++k)
      for (double dir : {-1.0, 1.0})
        for (double side : {1.0, -1.0})
          corners.push_back({side > 0 ? px + 3 * gap : px - 3 * gap - w, py - h / 2 + dir * k * (h + 2)});
    for (size_t i = 0; i < corners.size(); ++i) {
      const Box b{corners[i].first, corners[i].second, corners[i].first + w, corners[i].second + h};
      if (!b.inside(area)) continue;
      bool free = true;
      for (const Box& t : taken) free = free && !b.overlaps(t);
      if (!free) continue;
      *leader = i >= near;
      taken.push_back(b);
      return b;
    }
    // Nowhere free: right of the point, clamped into the area.
    Box b{px + gap, py - h / 2, px + gap + w, py + h / 2};
    const double dx = std::min(0.0, area.x1 - b.x1), dy = std::clamp(0.0, area.y0 - b.y0, area.y1 - b.y1);
    b = {b.x0 + dx, b.y0 + dy, b.x1 + dx, b.y1 + dy};
    *leader = false;
    taken.push_back(b);
    return b;
  }
};

// Text width estimate for the sans-serif labels (a little wide, so real
// glyphs fit in the reserved box).
double text_width(const std::string& s, double font_size) { return 0.62 * font_size * double(s.size()); }

constexpr double kLabelFont = 10;

// One panel: cost (log x) against precision (linear y), a labelled point per row.
void svg_panel(std::ostringstream& svg, double x0, double y0, const std::vector<TradeRow>& rows, bool ms,
               const std::string& title) {
  constexpr double kW = 540, kH = 400, kLeft = 62, kRight = 24, kTop = 34, kBottom = 50;
  double lo = 1e300, hi = 0;
  for (const TradeRow& r : rows) {
    const double c = ms ? r.ms_per_frame : r.box_tests_per_frame;
    if (c > 0) lo = std::min(lo, c), hi = std::max(hi, c);
  }
  if (hi <= 0) lo = 1, hi = 10;
  const double dlo = std::floor(std::log10(lo)), dhi = std::max(dlo + 1, std::ceil(std::log10(hi)));
  // Precision axis from the data's floor (in steps of 0.1) to 1.
  double pmin = 1;
  for (const TradeRow& r : rows) pmin = std::min(pmin, r.precision());
  const double p0 = std::max(0.0, std::floor(pmin * 10 - 0.5) / 10);
  const Box plot{x0 + kLeft, y0 + kTop, x0 + kW - kRight, y0 + kH - kBottom};
  auto px = [&](double c) {
    const double l = std::log10(std::max(c, std::pow(10.0, dlo)));
    return plot.x0 + (l - dlo) / (dhi - dlo) * (plot.x1 - plot.x0);
  };
  auto py = [&](double p) { return plot.y0 + (1 - (p - p0) / (1 - p0)) * (plot.y1 - plot.y0); };
  svg << "<text x='" << num(x0 + kW / 2) << "' y='" << num(y0 + 20)
      << "' text-anchor='middle' font-size='13'>" << xml_escape(title) << "</text>\n";
  svg << "<rect x='" << num(plot.x0) << "' y='" << num(plot.y0) << "' width='" << num(plot.x1 - plot.x0)
      << "' height='" << num(plot.y1 - plot.y0) << "' fill='none' stroke='#444'/>\n";
  for (double d = dlo; d <= dhi; ++d) {
    const double x = px(std::pow(10.0, d));
    svg << "<line x1='" << num(x) << "' y1='" << num(plot.y0) << "' x2='" << num(x) << "' y2='" << num(plot.y1)
        << "' stroke='#ddd'/><text x='" << num(x) << "' y='" << num(plot.y1 + 16)
        << "' text-anchor='middle' font-size='11'>" << std::pow(10.0, d) << "</text>\n";
  }
  const int steps = static_cast<int>(std::lround((1 - p0) * 10));
  for (int k = 0; k <= steps; ++k) {
    const double p = p0 + k / 10.0, y = py(p);
    char tick[8];
    std::snprintf(tick, sizeof tick, "%.1f", p);
    svg << "<line x1='" << num(plot.x0) << "' y1='" << num(y) << "' x2='" << num(plot.x1) << "' y2='" << num(y)
        << "' stroke='#ddd'/><text x='" << num(plot.x0 - 6) << "' y='" << num(y + 4)
        << "' text-anchor='end' font-size='11'>" << tick << "</text>\n";
  }
  svg << "<text x='" << num((plot.x0 + plot.x1) / 2) << "' y='" << num(y0 + kH - 14)
      << "' text-anchor='middle' font-size='12'>"
      << (ms ? "ms per frame, World::step (log scale)" : "box tests per frame (log scale)") << "</text>\n";
  const double mid = (plot.y0 + plot.y1) / 2;
  svg << "<text x='" << num(x0 + 18) << "' y='" << num(mid) << "' font-size='12' transform='rotate(-90 "
      << num(x0 + 18) << ' ' << num(mid) << ")' text-anchor='middle'>precision</text>\n";

  LabelPlacer placer{{plot.x0 + 2, plot.y0 + 2, plot.x1 - 2, plot.y1 - 2}, {}};
  std::vector<std::pair<double, double>> points;
  for (const TradeRow& r : rows) {
    points.push_back({px(ms ? r.ms_per_frame : r.box_tests_per_frame), py(r.precision())});
    placer.taken.push_back({points.back().first - 5, points.back().second - 5, points.back().first + 5,
                            points.back().second + 5});
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto [x, y] = points[i];
    svg << "<circle cx='" << num(x) << "' cy='" << num(y) << "' r='4' fill='" << policy_color(rows[i].lod.policy)
        << "'/>\n";
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto [x, y] = points[i];
    bool leader = false;
    const double w = text_width(rows[i].label, kLabelFont), h = kLabelFont + 2;
    const Box b = placer.place(x, y, w, h, &leader);
    if (leader) {
      const double lx = b.x0 > x ? b.x0 - 1 : b.x1 + 1;
      svg << "<line x1='" << num(x) << "' y1='" << num(y) << "' x2='" << num(lx) << "' y2='"
          << num((b.y0 + b.y1) / 2) << "' stroke='#999' stroke-width='0.7'/>\n";
    }
    svg << "<text class='label' x='" << num(b.x0) << "' y='" << num(b.y1 - 3) << "' font-size='" << kLabelFont
        << "'>" << xml_escape(rows[i].label) << "</text>\n";
  }
}

}  // namespace

std::string trade_svg(const TradeReport& report, const std::string& scene_name) {
  constexpr double kWidth = 1080, kPanelTop = 58, kLegend = 30, kHeight = kPanelTop + 400 + kLegend;
  double recall_min = 1;
  uint64_t false_negatives = 0;
  for (const TradeRow& r : report.rows) recall_min = std::min(recall_min, r.recall()), false_negatives += r.false_negatives;
  char title[256];
  std::snprintf(title, sizeof title, "%zu LOD settings over %lld frames, %llu exact contacts: %s",
                report.rows.size(), static_cast<long long>(report.frames),
                static_cast<unsigned long long>(report.exact_contacts),
                false_negatives == 0 ? "recall 1 in every setting"
                                     : ("lowest recall " + std::to_string(recall_min)).c_str());
  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << kWidth << "' height='" << kHeight
      << "' font-family='sans-serif'>\n"
      << "<rect width='" << kWidth << "' height='" << kHeight << "' fill='white'/>\n";
  svg << "<text x='" << kWidth / 2 << "' y='22' text-anchor='middle' font-size='16'>"
      << xml_escape(scene_name + ": cost against precision") << "</text>\n";
  svg << "<text x='" << kWidth / 2 << "' y='42' text-anchor='middle' font-size='12' fill='#333'>" << xml_escape(title)
      << "</text>\n";
  svg_panel(svg, 0, kPanelTop, report.rows, /*ms=*/false, "box tests");
  svg_panel(svg, kWidth / 2, kPanelTop, report.rows, /*ms=*/true, "time");
  // Legend: one swatch per policy present.
  const std::pair<LodPolicy, std::string> entries[] = {
      {LodPolicy::fixed, "fixed depth"}, {LodPolicy::thesis, "thesis formula"}, {LodPolicy::screen, "screen tolerance"}};
  double legend_width = 0;
  for (const auto& [p, name] : entries) legend_width += 10 + text_width(name, 12) + 24;
  double x = (kWidth - legend_width) / 2;
  const double y = kPanelTop + 400 + 14;
  for (const auto& [p, name] : entries) {
    svg << "<g class='legend'><circle cx='" << num(x) << "' cy='" << num(y) << "' r='5' fill='" << policy_color(p)
        << "'/><text x='" << num(x + 10) << "' y='" << num(y + 4) << "' font-size='12'>" << name << "</text></g>\n";
    x += 10 + text_width(name, 12) + 24;
  }
  svg << "</svg>\n";
  return svg.str();
}

namespace {

std::string csv_text(const TradeReport& report) {
  std::ostringstream csv;
  csv << "setting,policy,min_depth,max_depth,pixel_tolerance,frames,true_positives,false_positives,"
         "false_negatives,precision,recall,box_tests_per_frame,ms_per_frame,false_positives_by_depth\n";
  for (const TradeRow& r : report.rows) {
    const char* policy = to_string(r.lod.policy);
    csv << r.label << ',' << policy << ',' << r.lod.min_depth << ',' << r.lod.max_depth << ','
        << r.lod.pixel_tolerance << ',' << report.frames << ',' << r.true_positives << ',' << r.false_positives << ','
        << r.false_negatives << ',' << r.precision() << ',' << r.recall() << ',' << r.box_tests_per_frame << ','
        << r.ms_per_frame << ',' << depth_pairs_text(r.false_positives_by_depth) << '\n';
  }
  return csv.str();
}

bool write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();  // the last bytes are written here, and may fail here
  return !out.fail();
}

}  // namespace

int trade_main(int argc, char** argv) {
  CLI::App app{"Score every LOD setting against an exact mesh-mesh answer (--response none)", "octscene trade"};
  std::string scene_path, plot_path, csv_path;
  TradeOptions options;
  app.add_option("scene", scene_path, "scene JSON")->required();
  app.add_option("--meshes", options.meshes, "folder of the source meshes (model x -> DIR/x.obj, .ply, ...)")
      ->check(kNonEmptyPath);
  app.add_option("--frames", options.frames, "frames to run (default: the scene's)")
      ->check(CLI::Range(int64_t{0}, kMaxFrames));
  app.add_option("--max-depth", options.max_depth, "deepest depth tried (default: baked depth, at most 8)")
      ->check(CLI::Range(1, 12));
  options.threads = usable_cores();
  app.add_option("--threads", options.threads, "worker threads (scores do not depend on it; default: all cores the process may run on)")
      ->check(CLI::Range(1, 4096));
  app.add_option("--plot", plot_path, "write an SVG of cost against precision")->check(kNonEmptyPath);
  app.add_option("--csv", csv_path, "write one CSV row per setting")->check(kNonEmptyPath);
  try {
    app.parse(argc, argv);  // argv[0] is the subcommand name, skipped like a program name
  } catch (const CLI::ParseError& e) {
    return parse_error_exit(app, e, "octscene trade");
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);

  auto scene = load_scene(scene_path);
  if (!scene) {
    std::fprintf(stderr, "octscene: error: %s: %s\n", scene_path.c_str(), scene.error().message.c_str());
    return 1;
  }
  auto library = ModelLibrary::open(scene->baked);
  if (!library) {
    std::fprintf(stderr, "octscene: error: %s: %s\n", scene->baked.c_str(), library.error().message.c_str());
    return 1;
  }
  auto report = run_trade(*scene, *library, options);
  if (!report) {
    std::fprintf(stderr, "octscene: error: %s: %s\n", scene_path.c_str(), report.error().message.c_str());
    return 1;
  }
  for (const std::string& w : report->warnings) std::fprintf(stderr, "octscene: warning: %s\n", w.c_str());

  std::printf("%s: %lld frames, %zu objects, %llu exact contacts (%llu pairs tested exactly)\n", scene_path.c_str(),
              static_cast<long long>(report->frames), scene->objects.size(),
              static_cast<unsigned long long>(report->exact_contacts),
              static_cast<unsigned long long>(report->exact_tests));
  std::printf("%-12s %9s %9s %6s %9s %7s %12s %9s  %s\n", "setting", "TP", "FP", "FN", "precision", "recall",
              "boxes/frame", "ms/frame", "FP by depth pair");
  for (const TradeRow& r : report->rows) {
    std::printf("%-12s %9llu %9llu %6llu %9.4f %7.4f %12.1f %9.4f  %s\n", r.label.c_str(),
                static_cast<unsigned long long>(r.true_positives), static_cast<unsigned long long>(r.false_positives),
                static_cast<unsigned long long>(r.false_negatives), r.precision(), r.recall(), r.box_tests_per_frame,
                r.ms_per_frame, depth_pairs_text(r.false_positives_by_depth).c_str());
  }
  for (const Miss& m : report->misses) {
    std::fprintf(stderr,
                 "octscene: BUG: %s missed a contact at frame %lld: %s (depth %d) and %s (depth %d); the exact "
                 "test finds it\n",
                 m.setting.c_str(), static_cast<long long>(m.frame), scene->objects[m.a].name.c_str(), m.depth_a,
                 scene->objects[m.b].name.c_str(), m.depth_b);
  }
  if (!csv_path.empty() && !write_text(csv_path, csv_text(*report))) {
    std::fprintf(stderr, "octscene: error: %s: cannot write\n", csv_path.c_str());
    return 1;
  }
  if (!plot_path.empty() && !write_text(plot_path, trade_svg(*report, std::filesystem::path(scene_path).filename().string()))) {
    std::fprintf(stderr, "octscene: error: %s: cannot write\n", plot_path.c_str());
    return 1;
  }
  if (!stdout_written()) {
    std::fprintf(stderr, "octscene: error: stdout: write failed\n");
    return 1;
  }
  return report->misses.empty() ? 0 : 1;
}

}  // namespace octbake::scene

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
#include <fstream>
#include <sstream>

#include "exact.h"
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

// One panel: cost (log x) against precision (linear y), a labelled point per row.
void svg_panel(std::ostringstream& svg, double x0, const std::vector<TradeRow>& rows, bool ms, const char* title) {
  constexpr double kW = 520, kH = 400, kLeft = 60, kRight = 20, kTop = 40, kBottom = 50;
  double lo = 1e300, hi = 0;
  for (const TradeRow& r : rows) {
    const double c = ms ? r.ms_per_frame : r.box_tests_per_frame;
    if (c > 0) lo = std::min(lo, c), hi = std::max(hi, c);
  }
  if (hi <= 0) lo = 1, hi = 10;
  const double dlo = std::floor(std::log10(lo)), dhi = std::max(dlo + 1, std::ceil(std::log10(hi)));
  auto px = [&](double c) {
    const double l = std::log10(std::max(c, std::pow(10.0, dlo)));
    return x0 + kLeft + (l - dlo) / (dhi - dlo) * (kW - kLeft - kRight);
  };
  auto py = [&](double p) { return kTop + (1 - p) * (kH - kTop - kBottom); };
  svg << "<text x='" << x0 + kW / 2 << "' y='22' text-anchor='middle' font-size='15'>" << title << "</text>\n";
  svg << "<rect x='" << x0 + kLeft << "' y='" << kTop << "' width='" << kW - kLeft - kRight << "' height='"
      << kH - kTop - kBottom << "' fill='none' stroke='#444'/>\n";
  for (double d = dlo; d <= dhi; ++d) {
    const double x = px(std::pow(10.0, d));
    svg << "<line x1='" << x << "' y1='" << kTop << "' x2='" << x << "' y2='" << kH - kBottom
        << "' stroke='#ddd'/><text x='" << x << "' y='" << kH - kBottom + 16
        << "' text-anchor='middle' font-size='11'>1e" << d << "</text>\n";
  }
  for (int k = 0; k <= 4; ++k) {
    const double y = py(k / 4.0);
    svg << "<line x1='" << x0 + kLeft << "' y1='" << y << "' x2='" << x0 + kW - kRight << "' y2='" << y
        << "' stroke='#ddd'/><text x='" << x0 + kLeft - 6 << "' y='" << y + 4
        << "' text-anchor='end' font-size='11'>" << k / 4.0 << "</text>\n";
  }
  svg << "<text x='" << x0 + (kW + kLeft - kRight) / 2 << "' y='" << kH - 12 << "' text-anchor='middle' font-size='12'>"
      << (ms ? "ms per frame (World::step, log)" : "box tests per frame (log)") << "</text>\n";
  svg << "<text x='" << x0 + 16 << "' y='" << (kTop + kH - kBottom) / 2 << "' font-size='12' transform='rotate(-90 "
      << x0 + 16 << ' ' << (kTop + kH - kBottom) / 2 << ")' text-anchor='middle'>precision</text>\n";
  for (const TradeRow& r : rows) {
    const double x = px(ms ? r.ms_per_frame : r.box_tests_per_frame), y = py(r.precision());
    svg << "<circle cx='" << x << "' cy='" << y << "' r='4' fill='" << policy_color(r.lod.policy) << "'/>"
        << "<text x='" << x + 6 << "' y='" << y - 5 << "' font-size='10'>" << xml_escape(r.label) << "</text>\n";
  }
}

std::string svg_plot(const TradeReport& report, const std::string& scene_name) {
  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='1040' height='400' font-family='sans-serif'>\n"
      << "<rect width='1040' height='400' fill='white'/>\n";
  svg_panel(svg, 0, report.rows, /*ms=*/false, ("cost vs precision: " + xml_escape(scene_name)).c_str());
  svg_panel(svg, 520, report.rows, /*ms=*/true, "time vs precision (recall is 1 for all)");
  svg << "</svg>\n";
  return svg.str();
}

std::string csv_text(const TradeReport& report) {
  std::ostringstream csv;
  csv << "setting,policy,min_depth,max_depth,pixel_tolerance,frames,true_positives,false_positives,"
         "false_negatives,precision,recall,box_tests_per_frame,ms_per_frame,false_positives_by_depth\n";
  for (const TradeRow& r : report.rows) {
    const char* policy = r.lod.policy == LodPolicy::fixed ? "fixed" : r.lod.policy == LodPolicy::thesis ? "thesis" : "screen";
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
  return static_cast<bool>(out);
}

}  // namespace

int trade_main(int argc, char** argv) {
  CLI::App app{"Score every LOD setting against an exact mesh-mesh answer (--response none)", "octscene trade"};
  std::string scene_path, plot_path, csv_path;
  TradeOptions options;
  app.add_option("scene", scene_path, "scene JSON")->required();
  app.add_option("--meshes", options.meshes, "folder of the source meshes (model x -> DIR/x.obj, .ply, ...)");
  app.add_option("--frames", options.frames, "frames to run (default: the scene's)");
  app.add_option("--max-depth", options.max_depth, "deepest depth tried (default: baked depth, at most 8)")
      ->check(CLI::Range(1, 12));
  app.add_option("--plot", plot_path, "write an SVG of cost against precision");
  app.add_option("--csv", csv_path, "write one CSV row per setting");
  try {
    app.parse(argc, argv);  // argv[0] is the subcommand name, skipped like a program name
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
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
  if (!plot_path.empty() && !write_text(plot_path, svg_plot(*report, scene_path))) {
    std::fprintf(stderr, "octscene: error: %s: cannot write\n", plot_path.c_str());
    return 1;
  }
  return report->misses.empty() ? 0 : 1;
}

}  // namespace octbake::scene

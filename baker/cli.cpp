#include "cli.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <nlohmann/json.hpp>

#include "octbake/baked_file.h"

namespace octbake {
namespace {

// printf into a std::string.
[[gnu::format(printf, 2, 3)]] void appendf(std::string& s, const char* fmt, ...) {
  char buf[512];
  va_list args;
  va_start(args, fmt);
  const int n = std::vsnprintf(buf, sizeof buf, fmt, args);
  va_end(args);
  if (n > 0) s.append(buf, std::min<size_t>(static_cast<size_t>(n), sizeof buf - 1));
}

const char* compression_name(Compression c) { return c == Compression::zstd ? "zstd" : "none"; }

std::string describe(const BakedFile& file, const std::string& path) {
  std::string s;
  const auto& trees = file.trees();
  appendf(s, "%s: format version %u, baker %s, %zu tree%s\n", path.c_str(), file.format_version(),
          file.baker_version().c_str(), trees.size(), trees.size() == 1 ? "" : "s");
  for (const TreeInfo& t : trees) {
    const Eigen::Vector3d lo = t.bounds.min, hi = t.bounds.max, ext = hi - lo;
    s += "  tree " + t.name + "\n";
    s += "    source hash   " + t.source_hash + " (XXH3-128 of the source file)\n";
    appendf(s, "    bounds        min (%.9g, %.9g, %.9g) max (%.9g, %.9g, %.9g)\n", lo.x(), lo.y(), lo.z(),
            hi.x(), hi.y(), hi.z());
    appendf(s, "    mesh          %llu triangles, %llu vertices\n",
            static_cast<unsigned long long>(t.triangle_count), static_cast<unsigned long long>(t.vertex_count));
    appendf(s, "    options       depth %d, occupancy %s, compression %s", t.options.depth,
            to_string(t.options.occupancy), compression_name(t.options.compression));
    if (t.options.compression == Compression::zstd) appendf(s, ":%d", t.options.compression_level);
    s += "\n";
    appendf(s, "    depth %12s %14s %14s   %s\n", "boxes", "stored bytes", "raw bytes", "leaf box size (model units)");
    uint64_t stored = 0, raw = 0;
    for (int d = 0; d <= t.depth; ++d) {
      const double cells = std::ldexp(1.0, d);
      appendf(s, "    %5d %12llu %14llu %14llu   %.6g x %.6g x %.6g\n", d,
              static_cast<unsigned long long>(t.box_count[d]), static_cast<unsigned long long>(t.stored_bytes[d]),
              static_cast<unsigned long long>(t.raw_bytes[d]), ext.x() / cells, ext.y() / cells, ext.z() / cells);
      stored += t.stored_bytes[d];
      raw += t.raw_bytes[d];
    }
    appendf(s, "    total %12s %14llu %14llu\n", "", static_cast<unsigned long long>(stored),
            static_cast<unsigned long long>(raw));
  }
  return s;
}

// The same facts as describe(), as JSON (documented at print_info).
nlohmann::ordered_json describe_json(const BakedFile& file, const std::string& path) {
  using nlohmann::ordered_json;
  auto vec = [](const Eigen::Vector3d& v) { return ordered_json::array({v.x(), v.y(), v.z()}); };
  ordered_json trees = ordered_json::array();
  for (const TreeInfo& t : file.trees()) {
    const Eigen::Vector3d ext = t.bounds.max - t.bounds.min;
    ordered_json levels = ordered_json::array();
    uint64_t stored = 0, raw = 0;
    for (int d = 0; d <= t.depth; ++d) {
      const double cells = std::ldexp(1.0, d);
      levels.push_back({{"depth", d},
                        {"boxes", t.box_count[d]},
                        {"stored_bytes", t.stored_bytes[d]},
                        {"raw_bytes", t.raw_bytes[d]},
                        {"leaf_size", vec(ext / cells)}});
      stored += t.stored_bytes[d];
      raw += t.raw_bytes[d];
    }
    trees.push_back({{"name", t.name},
                     {"source_hash", t.source_hash},
                     {"depth", t.depth},
                     {"triangles", t.triangle_count},
                     {"vertices", t.vertex_count},
                     {"options",
                      {{"depth", t.options.depth},
                       {"occupancy", to_string(t.options.occupancy)},
                       {"compression", compression_name(t.options.compression)},
                       {"compression_level", t.options.compression_level}}},
                     {"bounds", {{"min", vec(t.bounds.min)}, {"max", vec(t.bounds.max)}}},
                     {"levels", std::move(levels)},
                     {"stored_bytes", stored},
                     {"raw_bytes", raw}});
  }
  return {{"path", path},
          {"format_version", file.format_version()},
          {"baker_version", file.baker_version()},
          {"trees", std::move(trees)}};
}

}  // namespace

std::string error_reason(const Error& e, const std::string& path) {
  const std::string prefix = path + ": ";
  if (e.message.compare(0, prefix.size(), prefix) == 0) return e.message.substr(prefix.size());
  return e.message.empty() ? to_string(e.code) : e.message;
}

std::optional<std::pair<Compression, int>> parse_compression(const std::string& text) {
  if (text == "none") return std::pair{Compression::none, 0};
  if (text == "zstd") return std::pair{Compression::zstd, 19};
  const std::string prefix = "zstd:";
  if (text.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  const std::string digits = text.substr(prefix.size());
  if (digits.empty() || digits.size() > 2 || digits.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  const int level = std::stoi(digits);
  if (level < 1 || level > 22) return std::nullopt;
  return std::pair{Compression::zstd, level};
}

std::optional<Occupancy> parse_occupancy(const std::string& text) {
  for (Occupancy mode : kOccupancies)
    if (text == to_string(mode)) return mode;
  return std::nullopt;
}

int print_info(const std::vector<std::string>& files, std::FILE* out, std::FILE* err, bool json) {
  int status = 0;
  nlohmann::ordered_json described = nlohmann::ordered_json::array();
  for (const std::string& path : files) {
    auto file = BakedFile::open(path);
    // Decode every level too, so a file --info accepts is one the runtime loads.
    std::optional<Error> problem;
    if (!file) problem = file.error();
    for (size_t i = 0; !problem && i < file->trees().size(); ++i)
      if (auto tree = file->load(i, file->trees()[i].depth); !tree) problem = tree.error();
    if (problem) {
      std::fprintf(err, "octbake: error: %s: %s\n", path.c_str(), error_reason(*problem, path).c_str());
      status = 1;
      continue;
    }
    if (json)
      described.push_back(describe_json(*file, path));
    else
      std::fputs(describe(*file, path).c_str(), out);
  }
  if (json) {
    // Replace, not throw, should a name hold bytes that are not UTF-8.
    const std::string text = nlohmann::ordered_json{{"files", std::move(described)}}.dump(
        2, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
    std::fprintf(out, "%s\n", text.c_str());
  }
  std::fflush(out);
  return status;
}

std::string human_count(double n) {
  char buf[32];
  if (n >= 1e6)
    std::snprintf(buf, sizeof buf, "%.1fM", n / 1e6);
  else if (n >= 1e4)
    std::snprintf(buf, sizeof buf, "%.1fK", n / 1e3);
  else
    std::snprintf(buf, sizeof buf, "%.0f", n);
  return buf;
}

std::string human_duration(double seconds) {
  const uint64_t s = seconds > 0 && std::isfinite(seconds) ? static_cast<uint64_t>(std::min(seconds, 1e9)) : 0;
  char buf[48];
  if (s < 60)
    std::snprintf(buf, sizeof buf, "%llu s", static_cast<unsigned long long>(s));
  else if (s < 3600)
    std::snprintf(buf, sizeof buf, "%llu min %02llu s", static_cast<unsigned long long>(s / 60),
                  static_cast<unsigned long long>(s % 60));
  else
    std::snprintf(buf, sizeof buf, "%llu h %02llu min", static_cast<unsigned long long>(s / 3600),
                  static_cast<unsigned long long>(s / 60 % 60));
  return buf;
}

std::string progress_line(const ProgressCounts& c) {
  std::string s;
  appendf(s, "baking %zu/%zu files, %s/%s tri", c.files_done, c.files_total, human_count(c.triangles_done).c_str(),
          human_count(c.triangles_known).c_str());
  if (c.seconds <= 0 || c.triangles_done <= 0) return s;
  const double rate = c.triangles_done / c.seconds;
  appendf(s, ", %s tri/s", human_count(rate).c_str());
  const double left = c.triangles_known - c.triangles_done;
  if (c.files_waiting == 0 && left > 0) s += ", ETA " + human_duration(left / rate);
  if (c.files_writing > 0) appendf(s, ", writing %zu", c.files_writing);
  return s;
}

std::string summary_line(int baked, int up_to_date, int failed, double seconds, uint64_t triangles) {
  std::string s;
  appendf(s, "octbake: %d baked, %d up to date, %d failed in %.2f s (%s tri/s)", baked, up_to_date, failed, seconds,
          human_count(seconds > 0 ? double(triangles) / seconds : 0).c_str());
  return s;
}

}  // namespace octbake

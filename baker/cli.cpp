#include "cli.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>

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
  for (Occupancy mode : {Occupancy::surface, Occupancy::solid, Occupancy::vertices})
    if (text == to_string(mode)) return mode;
  return std::nullopt;
}

int print_info(const std::vector<std::string>& files, std::FILE* out, std::FILE* err) {
  int status = 0;
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
    std::fputs(describe(*file, path).c_str(), out);
  }
  std::fflush(out);
  return status;
}

}  // namespace octbake

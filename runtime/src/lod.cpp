// Depth policies (docs/interface.md section 5).
#include "octbake/lod.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

namespace octbake {

const char* to_string(LodPolicy policy) {
  switch (policy) {
    case LodPolicy::fixed: return "fixed";
    case LodPolicy::thesis: return "thesis";
    case LodPolicy::screen: return "screen";
  }
  return "?";
}

int thesis_depth(double area, double a_min, double a_max, int min_depth, int max_depth) {
  const int lo = std::min(min_depth, max_depth);
  const double sum = a_min + a_max;
  if (!(sum > 0)) return lo;
  const double d = std::floor(area / sum * max_depth) + min_depth;
  if (!(d >= lo)) return lo;  // also NaN
  return d >= max_depth ? max_depth : int(d);
}

namespace {
// 2^d for the depths a tree can have (std::ldexp is a library call, and this
// runs for every object in a pair whenever it or the camera moved).
constexpr std::array<double, 64> kPow2 = [] {
  std::array<double, 64> p{};
  double v = 1;
  for (double& x : p) x = v, v *= 2;
  return p;
}();
}  // namespace

int screen_depth(double area, int min_depth, int max_depth, double tolerance) {
  const double side = std::sqrt(area);
  for (int d = std::min(min_depth, max_depth); d < max_depth; ++d)  // exact: division by 2^d
    if (side / (size_t(d) < kPow2.size() ? kPow2[size_t(d)] : std::ldexp(1.0, d)) <= tolerance) return d;
  return max_depth;
}

std::vector<int> choose_depths(const LodSettings& settings, std::span<const double> areas,
                               std::span<const int> max_depths) {
  assert(areas.size() == max_depths.size());
  double a_min = 0, a_max = 0;
  if (!areas.empty()) {
    const auto [lo, hi] = std::minmax_element(areas.begin(), areas.end());
    a_min = *lo;
    a_max = *hi;
  }
  std::vector<int> depths(areas.size());
  for (size_t i = 0; i < areas.size(); ++i) {
    // The LOD range, clamped to what this object has.
    const int hi = std::max(0, std::min(settings.max_depth, max_depths[i]));
    const int lo = std::clamp(settings.min_depth, 0, hi);
    switch (settings.policy) {
      case LodPolicy::fixed: depths[i] = hi; break;
      case LodPolicy::thesis: depths[i] = thesis_depth(areas[i], a_min, a_max, lo, hi); break;
      case LodPolicy::screen: depths[i] = screen_depth(areas[i], lo, hi, settings.pixel_tolerance); break;
    }
  }
  return depths;
}

}  // namespace octbake

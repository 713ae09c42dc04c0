// LOD policies on hand-made area sets (docs/interface.md section 5).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "octbake/lod.h"

#include "seeded_random.h"

namespace octbake {
namespace {

TEST(ThesisDepth, HandComputed) {
  // A_min = 100, A_max = 600: floor(A / 700 * 6) + 1.
  EXPECT_EQ(thesis_depth(100, 100, 600, 1, 6), 1);  // 0.857 -> 0
  EXPECT_EQ(thesis_depth(300, 100, 600, 1, 6), 3);  // 2.57 -> 2
  EXPECT_EQ(thesis_depth(350, 100, 600, 1, 6), 4);  // 3.0 exactly -> 3
  EXPECT_EQ(thesis_depth(600, 100, 600, 1, 6), 6);  // 5.14 -> 5
  EXPECT_EQ(thesis_depth(600, 100, 600, 2, 6), 6);  // 5 + 2 clamped to 6
  EXPECT_EQ(thesis_depth(0, 100, 600, 2, 6), 2);
}

TEST(ThesisDepth, AllEqualAndAllZero) {
  // All equal: A / 2A * max = max / 2.
  EXPECT_EQ(thesis_depth(50, 50, 50, 1, 6), 4);
  EXPECT_EQ(thesis_depth(50, 50, 50, 0, 5), 2);
  // All zero: no information, the coarsest depth.
  EXPECT_EQ(thesis_depth(0, 0, 0, 1, 6), 1);
  EXPECT_EQ(thesis_depth(0, 0, 0, 3, 6), 3);
}

TEST(ScreenDepth, Boundaries) {
  // sqrt(256) = 16 = 2^4: at tolerance 1 depth 4 is exactly on the boundary.
  EXPECT_EQ(screen_depth(256, 1, 6, 1.0), 4);
  EXPECT_EQ(screen_depth(256 + 1e-9, 1, 6, 1.0), 5);
  EXPECT_EQ(screen_depth(256, 1, 6, 2.0), 3);
  EXPECT_EQ(screen_depth(256, 1, 6, 0.5), 5);
  EXPECT_EQ(screen_depth(256, 1, 3, 1.0), 3);  // would need 4: max
  EXPECT_EQ(screen_depth(256, 5, 6, 1.0), 5);  // already fine at min
  EXPECT_EQ(screen_depth(0, 2, 6, 1.0), 2);
  EXPECT_EQ(screen_depth(1920.0 * 1080, 1, 12, 1.0), 11);  // sqrt = 1440 < 2048
  EXPECT_EQ(screen_depth(1e30, 1, 12, 1.0), 12);
}

// The definition, with the library's ldexp: screen_depth's table of powers
// must give the same depth for every area, tolerance and depth range.
int screen_depth_by_definition(double area, int min_depth, int max_depth, double tolerance) {
  const double side = std::sqrt(area);
  for (int d = std::min(min_depth, max_depth); d < max_depth; ++d)
    if (side / std::ldexp(1.0, d) <= tolerance) return d;
  return max_depth;
}

TEST(ScreenDepth, EqualsTheDefinitionOnRandomAreas) {
  std::mt19937 rng(5);
  const double specials[] = {0.0, std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::min(),
                             std::numeric_limits<double>::max(), std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN(), 1.0, 4.0, 4.0 * (1 + 1e-16)};
  for (int run = 0; run < 20000; ++run) {
    const double area = run % 9 == 0 ? specials[(run / 9) % std::size(specials)]
                                     : std::pow(10.0, -320 + 630 * test::uniform01(rng));
    const double tolerance = run % 5 == 0 ? std::ldexp(1.0, int(rng() % 40) - 20)
                                          : std::pow(10.0, -310 + 620 * test::uniform01(rng));
    const int lo = int(rng() % 80) - 4, hi = int(rng() % 80) - 4;  // beyond the table, and lo > hi
    ASSERT_EQ(screen_depth(area, lo, hi, tolerance), screen_depth_by_definition(area, lo, hi, tolerance))
        << "area " << area << " tolerance " << tolerance << " depths " << lo << ".." << hi;
  }
}

TEST(ChooseDepths, ClampsToEachObject) {
  const std::vector<double> areas{100, 300, 600};
  const std::vector<int> max_depths{6, 2, 12};
  LodSettings s;
  s.min_depth = 1;
  s.max_depth = 8;

  s.policy = LodPolicy::fixed;
  EXPECT_EQ(choose_depths(s, areas, max_depths), (std::vector<int>{6, 2, 8}));

  s.policy = LodPolicy::thesis;  // floor(A / 700 * max_i) + 1 with max_i = 6, 2, 8
  EXPECT_EQ(choose_depths(s, areas, max_depths), (std::vector<int>{1, 1, 7}));

  s.policy = LodPolicy::screen;  // sqrt: 10, 17.3, 24.5 -> 4, 5, 5
  EXPECT_EQ(choose_depths(s, areas, max_depths), (std::vector<int>{4, 2, 5}));

  // A min depth beyond an object's max gives its max.
  s.min_depth = 4;
  s.policy = LodPolicy::thesis;
  EXPECT_EQ(choose_depths(s, areas, max_depths), (std::vector<int>{4, 2, 8}));  // 6 + 4 clamped
}

TEST(ChooseDepths, EmptyAndAllZero) {
  LodSettings s;
  s.policy = LodPolicy::thesis;
  EXPECT_TRUE(choose_depths(s, {}, {}).empty());
  const std::vector<double> zero{0, 0};
  const std::vector<int> max_depths{6, 6};
  EXPECT_EQ(choose_depths(s, zero, max_depths), (std::vector<int>{1, 1}));
  s.policy = LodPolicy::screen;
  EXPECT_EQ(choose_depths(s, zero, max_depths), (std::vector<int>{1, 1}));
}

}  // namespace
}  // namespace octbake

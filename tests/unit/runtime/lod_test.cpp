// LOD policies on hand-made area sets (docs/interface.md section 5).
#include <gtest/gtest.h>

#include <cmath>

#include "octbake/lod.h"

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

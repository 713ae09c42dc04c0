// The trade plot: a legend, a title from the data, and point labels that
// overlap nothing and stay inside their plot, even for clustered points.
#include <gtest/gtest.h>

#include <random>

#include "seeded_random.h"
#include "trade.h"

namespace octbake::scene {
namespace {

struct Rect {
  double x0, y0, x1, y1;
  bool overlaps(const Rect& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
};

// Label boxes as the plot reserves them: font 10, 0.62 em per character,
// baseline 3 above the box bottom.
// Every "<prefix>A' ... B'...>TEXT<" occurrence: the two numbers after the
// prefix and the text up to the next '<' (no std::regex: GCC 12 warns inside it).
struct Hit {
  double a, b;
  std::string text, tag;
};
std::vector<Hit> find_all(const std::string& svg, const std::string& prefix, const std::string& second) {
  std::vector<Hit> hits;
  for (size_t at = svg.find(prefix); at != std::string::npos; at = svg.find(prefix, at + 1)) {
    const size_t a = at + prefix.size(), b = svg.find(second, a) + second.size();
    const size_t close = svg.find('>', b), end = svg.find('<', close);
    hits.push_back({std::stod(svg.substr(a)), std::stod(svg.substr(b)), svg.substr(close + 1, end - close - 1),
                    svg.substr(at, close - at)});
  }
  return hits;
}

// Label boxes as the plot reserves them: font 10, 0.62 em per character,
// baseline 3 above the box bottom.
std::vector<Rect> label_boxes(const std::string& svg) {
  std::vector<Rect> boxes;
  for (const Hit& h : find_all(svg, "<text class='label' x='", "y='")) {
    const double w = 0.62 * 10 * double(h.text.size());
    boxes.push_back({h.a, h.b + 3 - 12, h.a + w, h.b + 3});
  }
  return boxes;
}

std::vector<Rect> point_boxes(const std::string& svg) {
  std::vector<Rect> boxes;
  for (const Hit& h : find_all(svg, "<circle cx='", "cy='")) {
    if (h.tag.find("r='4'") == std::string::npos) continue;  // not a legend swatch
    boxes.push_back({h.a - 4, h.b - 4, h.a + 4, h.b + 4});
  }
  return boxes;
}

TradeRow row(const std::string& label, LodPolicy policy, double boxes, double ms, uint64_t tp, uint64_t fp,
             uint64_t fn = 0) {
  TradeRow r;
  r.label = label;
  r.lod.policy = policy;
  r.box_tests_per_frame = boxes;
  r.ms_per_frame = ms;
  r.true_positives = tp;
  r.false_positives = fp;
  r.false_negatives = fn;
  return r;
}

void expect_clean_layout(const std::string& svg, size_t rows) {
  const std::vector<Rect> labels = label_boxes(svg), points = point_boxes(svg);
  ASSERT_EQ(labels.size(), 2 * rows);  // one per point in each panel
  ASSERT_EQ(points.size(), 2 * rows);
  for (size_t i = 0; i < labels.size(); ++i) {
    const Rect& a = labels[i];
    // Inside one panel's plot frame (x 62..516 or 602..1056, y 92..408).
    const bool left = a.x0 >= 62 && a.x1 <= 516, right = a.x0 >= 602 && a.x1 <= 1056;
    EXPECT_TRUE(left || right) << "label " << i << " clipped: x " << a.x0 << ".." << a.x1;
    EXPECT_GE(a.y0, 92);
    EXPECT_LE(a.y1, 408);
    for (size_t j = i + 1; j < labels.size(); ++j) EXPECT_FALSE(a.overlaps(labels[j])) << i << " and " << j;
    for (size_t j = 0; j < points.size(); ++j) EXPECT_FALSE(a.overlaps(points[j])) << "label " << i << ", point " << j;
  }
}

// The measured test 1 rows (README): several points nearly coincide.
TradeReport thesis_like() {
  TradeReport r;
  r.frames = 7200;
  r.exact_contacts = 13848;
  const double boxes[] = {102, 290, 713, 1290, 2026, 3049};
  const double precision[] = {0.399, 0.459, 0.605, 0.750, 0.850, 0.919};
  for (int d = 0; d < 6; ++d) {
    const uint64_t fp = static_cast<uint64_t>(13848 / precision[d]) - 13848;
    r.rows.push_back(row("fixed " + std::to_string(d + 1), LodPolicy::fixed, boxes[d], 0.01 * (d + 1), 13848, fp));
  }
  r.rows.push_back(row("thesis 1-6", LodPolicy::thesis, 289, 0.012, 13848, 14183));
  const double sboxes[] = {3027, 2791, 2199, 1433, 798}, sprec[] = {0.918, 0.910, 0.870, 0.778, 0.642};
  const char* names[] = {"screen 0.5px", "screen 1px", "screen 2px", "screen 4px", "screen 8px"};
  for (int i = 0; i < 5; ++i)
    r.rows.push_back(row(names[i], LodPolicy::screen, sboxes[i], 0.06 - 0.01 * i, 13848,
                         static_cast<uint64_t>(13848 / sprec[i]) - 13848));
  return r;
}

TEST(TradePlot, HasALegendAndATitleFromTheData) {
  const std::string svg = trade_svg(thesis_like(), "test1.json");
  EXPECT_NE(svg.find("test1.json: cost against precision"), std::string::npos);
  EXPECT_NE(svg.find("12 LOD settings over 7200 frames, 13848 exact contacts: recall 1 in every setting"),
            std::string::npos);
  for (const char* entry : {"fixed depth", "thesis formula", "screen tolerance"})
    EXPECT_NE(svg.find(std::string(">") + entry + "</text>"), std::string::npos) << entry;

  TradeReport missed = thesis_like();
  missed.rows[0].false_negatives = 1;
  EXPECT_NE(trade_svg(missed, "x").find("lowest recall 0.99992"), std::string::npos);
}

TEST(TradePlot, LabelsOfTheMeasuredRowsNeitherOverlapNorClip) {
  expect_clean_layout(trade_svg(thesis_like(), "test1.json"), 12);
}

// Random clusters: points piled within a few pixels of each other.
TEST(TradePlot, LabelsOfClusteredPointsNeitherOverlapNorClip) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 20; ++trial) {
    TradeReport r;
    r.frames = 100;
    const double centre = std::pow(10.0, octbake::test::uniform(random, 1, 4));
    for (int i = 0; i < 12; ++i) {
      const double boxes = centre * octbake::test::uniform(random, 0.9, 1.1);
      const uint64_t tp = 500, fp = static_cast<uint64_t>(octbake::test::uniform(random, 0, 200));
      r.rows.push_back(row("setting " + std::to_string(i), LodPolicy::screen, boxes, boxes * 1e-4, tp, fp));
    }
    SCOPED_TRACE(trial);
    expect_clean_layout(trade_svg(r, "random.json"), 12);
  }
}

}  // namespace
}  // namespace octbake::scene

// The text of octbake's progress and summary lines, from counts and elapsed
// time: rates, ETA, number and duration formatting.
#include <gtest/gtest.h>

#include "cli.h"

namespace octbake {
namespace {

TEST(CliProgressText, HumanCountAndDuration) {
  EXPECT_EQ(human_count(0), "0");
  EXPECT_EQ(human_count(9999), "9999");
  EXPECT_EQ(human_count(12345), "12.3K");
  EXPECT_EQ(human_count(999949), "999.9K");
  EXPECT_EQ(human_count(1.5e6), "1.5M");
  EXPECT_EQ(human_duration(0), "0 s");
  EXPECT_EQ(human_duration(42.9), "42 s");
  EXPECT_EQ(human_duration(125), "2 min 05 s");
  EXPECT_EQ(human_duration(7300), "2 h 01 min");
  EXPECT_EQ(human_duration(-3), "0 s");
  EXPECT_EQ(human_duration(1.0 / 0.0), "0 s");
}

TEST(CliProgressText, RateAndEtaFromCounts) {
  ProgressCounts c;
  c.files_total = 3;
  c.files_done = 1;
  c.triangles_known = 70312;
  c.triangles_done = 35156;  // half
  c.seconds = 2;
  // 17578 tri/s, and the other half takes as long again: 2 s.
  EXPECT_EQ(progress_line(c), "baking 1/3 files, 35.2K/70.3K tri, 17.6K tri/s, ETA 2 s");

  c.triangles_done = 7000;  // 3500 tri/s, 63312 to go: 18.1 s
  EXPECT_EQ(progress_line(c), "baking 1/3 files, 7000/70.3K tri, 3500 tri/s, ETA 18 s");
  c.seconds = 20;  // ten times slower: 180.9 s
  EXPECT_EQ(progress_line(c), "baking 1/3 files, 7000/70.3K tri, 350 tri/s, ETA 3 min 00 s");
}

TEST(CliProgressText, NoEtaWhileFilesAreUnreadAndNoRateBeforeWork) {
  ProgressCounts c;
  c.files_total = 4;
  c.files_done = 1;
  c.files_waiting = 2;  // their triangles are not known yet
  c.triangles_known = 3e6;
  c.triangles_done = 1.5e6;
  c.seconds = 3;
  EXPECT_EQ(progress_line(c), "baking 1/4 files, 1.5M/3.0M tri, 500.0K tri/s");
  c.files_waiting = 0;
  EXPECT_EQ(progress_line(c), "baking 1/4 files, 1.5M/3.0M tri, 500.0K tri/s, ETA 3 s");

  ProgressCounts start;
  start.files_total = 2;
  EXPECT_EQ(progress_line(start), "baking 0/2 files, 0/0 tri");
  start.seconds = 5;  // time passes, nothing done yet: no rate, no ETA
  start.triangles_known = 1000;
  EXPECT_EQ(progress_line(start), "baking 0/2 files, 0/1000 tri");

  // The last build done, its file being compressed: no ETA, "writing".
  ProgressCounts writing;
  writing.files_total = 1;
  writing.triangles_known = writing.triangles_done = 70312;
  writing.files_writing = 1;
  writing.seconds = 4;
  EXPECT_EQ(progress_line(writing), "baking 0/1 files, 70.3K/70.3K tri, 17.6K tri/s, writing 1");

  // Every file finished: no ETA.
  ProgressCounts end;
  end.files_total = end.files_done = 2;
  end.triangles_known = end.triangles_done = 5000;
  end.seconds = 1;
  EXPECT_EQ(progress_line(end), "baking 2/2 files, 5000/5000 tri, 5000 tri/s");
}

TEST(CliProgressText, SummaryLine) {
  EXPECT_EQ(summary_line(5, 0, 1, 0.42, 42000), "octbake: 5 baked, 0 up to date, 1 failed in 0.42 s (100.0K tri/s)");
  EXPECT_EQ(summary_line(0, 3, 0, 0.01, 0), "octbake: 0 baked, 3 up to date, 0 failed in 0.01 s (0 tri/s)");
  EXPECT_EQ(summary_line(1, 0, 0, 0, 100), "octbake: 1 baked, 0 up to date, 0 failed in 0.00 s (0 tri/s)");
}

}  // namespace
}  // namespace octbake

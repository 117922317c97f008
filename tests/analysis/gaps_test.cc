// Gap report on hand-made arrays: exact gaps, longest, fraction, leading/trailing.
#include "analysis/cleaning/gaps.h"

#include <gtest/gtest.h>

#include <limits>

#include "core/error.h"

namespace csw::cleaning {
namespace {

MarkerArray Full(int64_t frames, int64_t markers) {
  MarkerArray a(frames, markers);
  for (float& v : a.data()) v = 1.0f;
  return a;
}

TEST(CleaningGaps, ExactGapsLongestAndFraction) {
  MarkerArray a = Full(20, 3);
  // marker 0: leading 0-1, interior 5-7, trailing 18-19
  for (int64_t f : {0, 1, 5, 6, 7, 18, 19}) a.SetMissing(f, 0);
  // marker 1: one interior frame at 10
  a.SetMissing(10, 1);
  // marker 2: never visible
  for (int64_t f = 0; f < 20; ++f) a.SetMissing(f, 2);
  const std::vector<Gap> g0 = FindGaps(a, 0);
  ASSERT_EQ(g0.size(), 3u);
  EXPECT_EQ(g0[0], (Gap{0, 0, 2, true, false}));
  EXPECT_EQ(g0[1], (Gap{0, 5, 3, false, false}));
  EXPECT_EQ(g0[2], (Gap{0, 18, 2, false, true}));
  EXPECT_TRUE(g0[1].interior());
  EXPECT_EQ(g0[1].end(), 8);
  EXPECT_EQ(FindGaps(a, 1), (std::vector<Gap>{Gap{1, 10, 1, false, false}}));
  EXPECT_EQ(FindGaps(a, 2), (std::vector<Gap>{Gap{2, 0, 20, true, true}}));

  const GapReport r = MakeGapReport(a);
  EXPECT_EQ(r.frames, 20);
  EXPECT_EQ(r.markers, 3);
  ASSERT_EQ(r.per_marker.size(), 3u);
  EXPECT_EQ(r.per_marker[0].missing_frames, 7);
  EXPECT_DOUBLE_EQ(r.per_marker[0].fraction_missing, 7.0 / 20.0);
  EXPECT_EQ(r.per_marker[0].longest, 3);
  EXPECT_FALSE(r.per_marker[0].never_visible);
  EXPECT_EQ(r.per_marker[1].longest, 1);
  EXPECT_DOUBLE_EQ(r.per_marker[1].fraction_missing, 0.05);
  EXPECT_TRUE(r.per_marker[2].never_visible);
  EXPECT_DOUBLE_EQ(r.per_marker[2].fraction_missing, 1.0);
  EXPECT_EQ(r.gap_count, 5);
  EXPECT_EQ(r.missing_samples, 28);
  EXPECT_DOUBLE_EQ(r.fraction_missing, 28.0 / 60.0);
  EXPECT_EQ(r.longest, 20);
  EXPECT_EQ(r.leading_or_trailing, 3);
  EXPECT_EQ(r.AllGaps(), FindAllGaps(a));
  EXPECT_EQ(r.AllGaps().size(), 5u);
  EXPECT_EQ(CountGapsInRange(r.AllGaps(), 1, 2), 3);
  EXPECT_EQ(CountGapsInRange(r.AllGaps(), 3, 5), 1);
  EXPECT_EQ(CountGapsInRange(r.AllGaps(), 6, 0), 1);
}

TEST(CleaningGaps, NoGapsAndEmptyTakes) {
  const GapReport r = MakeGapReport(Full(10, 2));
  EXPECT_EQ(r.gap_count, 0);
  EXPECT_EQ(r.longest, 0);
  EXPECT_DOUBLE_EQ(r.fraction_missing, 0.0);
  const GapReport e = MakeGapReport(MarkerArray());
  EXPECT_EQ(e.gap_count, 0);
  EXPECT_DOUBLE_EQ(e.fraction_missing, 0.0);
  EXPECT_TRUE(e.per_marker.empty());
}

TEST(CleaningGaps, AnyNonFiniteCoordinateIsMissing) {
  MarkerArray a = Full(6, 1);
  a.at(2, 0)[1] = std::numeric_limits<float>::quiet_NaN();  // one coordinate only
  a.at(3, 0)[2] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(FindGaps(a, 0), (std::vector<Gap>{Gap{0, 2, 2, false, false}}));
  EXPECT_THROW(FindGaps(a, 1), InvalidInput);
  EXPECT_THROW(FindGaps(a, -1), InvalidInput);
}

}  // namespace
}  // namespace csw::cleaning

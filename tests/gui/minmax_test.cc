// Display decimation: every bin's extremes equal a brute-force scan of its samples.
#include "workbench/gui/minmax.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace csw::gui {
namespace {

TEST(MinMaxPyramid, BinsMatchBruteForceWithGaps) {
  const double rate = 120.0;
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  std::vector<float> s(100000);
  for (size_t i = 0; i < s.size(); ++i) s[i] = static_cast<float>(std::sin(i * 0.001)) * 10 + noise(rng);
  for (size_t i = 5000; i < 7000; ++i) s[i] = std::numeric_limits<float>::quiet_NaN();  // a gap
  MinMaxPyramid p(s, rate);
  for (auto [t0, t1, columns] : {std::tuple{0.0, 100000 / rate, 800}, std::tuple{33.3, 71.9, 517},
                                 std::tuple{41.0, 59.0, 300}, std::tuple{10.0, 10.5, 1000}}) {
    auto bins = p.Decimate(t0, t1, columns);
    ASSERT_FALSE(bins.empty());
    EXPECT_LE(static_cast<int>(bins.size()), columns);
    int64_t first = static_cast<int64_t>(std::floor(t0 * rate));
    int64_t last = std::min<int64_t>(static_cast<int64_t>(s.size()), static_cast<int64_t>(std::ceil(t1 * rate)) + 1);
    int64_t count = last - first;
    if (count <= columns) {
      ASSERT_EQ(static_cast<int64_t>(bins.size()), count);
      for (int64_t i = 0; i < count; ++i) {
        float v = s[static_cast<size_t>(first + i)];
        if (std::isnan(v)) {
          EXPECT_TRUE(std::isnan(bins[static_cast<size_t>(i)].min));
        } else {
          EXPECT_EQ(bins[static_cast<size_t>(i)].min, v);
        }
      }
      continue;
    }
    ASSERT_EQ(static_cast<int>(bins.size()), columns);
    for (int c = 0; c < columns; ++c) {
      int64_t a = first + count * c / columns, b = first + count * (c + 1) / columns;
      float lo = std::numeric_limits<float>::quiet_NaN(), hi = lo;
      for (int64_t i = a; i < b; ++i) {
        float v = s[static_cast<size_t>(i)];
        if (std::isnan(v)) continue;
        if (std::isnan(lo) || v < lo) lo = v;
        if (std::isnan(hi) || v > hi) hi = v;
      }
      const MinMaxBin& bin = bins[static_cast<size_t>(c)];
      EXPECT_DOUBLE_EQ(bin.time_s, static_cast<double>(a) / rate);
      if (std::isnan(lo)) {
        EXPECT_TRUE(std::isnan(bin.min) && std::isnan(bin.max)) << "column " << c;
      } else {
        EXPECT_EQ(bin.min, lo) << "column " << c;
        EXPECT_EQ(bin.max, hi) << "column " << c;
      }
    }
  }
}

TEST(MinMaxPyramid, ValueAtAndOutOfRange) {
  MinMaxPyramid p({1.0f, 2.0f, 3.0f}, 10.0);
  EXPECT_EQ(p.ValueAt(0.0), 1.0f);
  EXPECT_EQ(p.ValueAt(0.1), 2.0f);
  EXPECT_EQ(p.ValueAt(0.25), 3.0f);
  EXPECT_TRUE(std::isnan(p.ValueAt(0.3)));
  EXPECT_TRUE(std::isnan(p.ValueAt(-0.1)));
  EXPECT_TRUE(p.Decimate(1.0, 2.0, 10).empty());
}

}  // namespace
}  // namespace csw::gui

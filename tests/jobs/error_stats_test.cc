// ErrorStats (models/inversion.h): the one mergeable mean / sd / max used by
// the model jobs, against values computed by hand and two-pass formulas.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "models/inversion.h"

namespace csw {
namespace {

// Two-pass reference: mean, sample sd, max.
void Reference(const std::vector<double>& x, double* mean, double* sd, double* max) {
  double s = 0;
  *max = x[0];
  for (double v : x) {
    s += v;
    *max = std::max(*max, v);
  }
  *mean = s / static_cast<double>(x.size());
  double ss = 0;
  for (double v : x) ss += (v - *mean) * (v - *mean);
  *sd = std::sqrt(ss / static_cast<double>(x.size() - 1));
}

TEST(ErrorStats, KnownValues) {
  ErrorStats s;
  for (double v : {2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0}) s.Add(v);
  EXPECT_EQ(s.count, 8);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_NEAR(s.sd, std::sqrt(32.0 / 7.0), 1e-12);  // sum of squared deviations 32
  EXPECT_DOUBLE_EQ(s.max, 9.0);
  EXPECT_NEAR(s.m2, 32.0, 1e-12);
}

TEST(ErrorStats, IgnoresNonFiniteAndHandlesTinyCounts) {
  ErrorStats s;
  EXPECT_EQ(s.count, 0);
  s.Add(std::nan(""));
  s.Add(INFINITY);
  EXPECT_EQ(s.count, 0);
  s.Add(1.5);
  EXPECT_EQ(s.count, 1);
  EXPECT_DOUBLE_EQ(s.mean, 1.5);
  EXPECT_DOUBLE_EQ(s.sd, 0.0);
  EXPECT_DOUBLE_EQ(s.max, 1.5);
  ErrorStats empty;
  s.Merge(empty);
  EXPECT_EQ(s.count, 1);
  empty.Merge(s);
  EXPECT_EQ(empty.count, 1);
  EXPECT_DOUBLE_EQ(empty.mean, 1.5);
}

TEST(ErrorStats, MergeOfTwoHalvesEqualsTheWhole) {
  std::mt19937_64 rng(3);
  std::lognormal_distribution<double> dist(0.0, 0.8);
  std::vector<double> x(1001);
  for (double& v : x) v = 1000.0 + dist(rng);  // a large offset: catastrophic cancellation if done naively
  ErrorStats whole, a, b;
  for (size_t i = 0; i < x.size(); ++i) {
    whole.Add(x[i]);
    (i < 400 ? a : b).Add(x[i]);
  }
  ErrorStats merged = a;
  merged.Merge(b);
  EXPECT_EQ(merged.count, whole.count);
  EXPECT_NEAR(merged.mean, whole.mean, 1e-12);
  EXPECT_NEAR(merged.sd, whole.sd, 1e-12);
  EXPECT_EQ(merged.max, whole.max);
  double mean, sd, max;
  Reference(x, &mean, &sd, &max);
  EXPECT_NEAR(whole.mean, mean, 1e-10);
  EXPECT_NEAR(whole.sd, sd, 1e-10);
  EXPECT_EQ(whole.max, max);
  // Many small pieces (one per sample) merge to the same.
  ErrorStats pieces;
  for (double v : x) {
    ErrorStats one;
    one.Add(v);
    pieces.Merge(one);
  }
  EXPECT_NEAR(pieces.mean, mean, 1e-10);
  EXPECT_NEAR(pieces.sd, sd, 1e-10);
}

TEST(ErrorStats, SummariseErrorsUsesTheSameStatistics) {
  Eigen::MatrixXd e(2, 3);
  e << 1, std::nan(""), 3,  //
      4, 5, 6;
  ErrorStats direct;
  for (double v : {1.0, 3.0, 4.0, 5.0, 6.0}) direct.Add(v);
  const ErrorStats s = SummariseErrors(e);
  EXPECT_EQ(s.count, direct.count);
  EXPECT_DOUBLE_EQ(s.mean, 19.0 / 5.0);
  EXPECT_DOUBLE_EQ(s.sd, direct.sd);
  EXPECT_DOUBLE_EQ(s.max, 6.0);
}

// Percentiles by linear interpolation between closest ranks (h = (n − 1)·q):
// values worked out by hand.
TEST(ErrorSamples, PercentilesOfKnownValues) {
  ErrorSamples s;
  EXPECT_TRUE(std::isnan(s.Percentile(99)));  // no samples
  // 1 … 100 in a scrambled order: x[k] = k + 1.
  for (int i = 0; i < 100; ++i) s.Add(static_cast<double>((i * 37) % 100 + 1));
  EXPECT_EQ(s.stats.count, 100);
  EXPECT_DOUBLE_EQ(s.stats.mean, 50.5);
  EXPECT_DOUBLE_EQ(s.Percentile(0), 1.0);
  EXPECT_DOUBLE_EQ(s.Percentile(100), 100.0);
  EXPECT_NEAR(s.Percentile(50), 50.5, 1e-12);      // h = 49.5: halfway between 50 and 51
  EXPECT_NEAR(s.Percentile(99), 99.01, 1e-12);     // h = 98.01: 99 + 0.01
  EXPECT_NEAR(s.Percentile(99.9), 99.901, 1e-12);  // h = 98.901: 99 + 0.901
  // Three samples: h = 2 × 0.99 = 1.98 between 2 and 10: 2 + 0.98 × 8 = 9.84.
  ErrorSamples t;
  for (double v : {10.0, 1.0, 2.0}) t.Add(v);
  EXPECT_NEAR(t.Percentile(99), 9.84, 1e-12);
  EXPECT_NEAR(t.Percentile(99.9), 2 + 0.998 * 8, 1e-12);
  EXPECT_DOUBLE_EQ(t.Percentile(50), 2.0);
  // One sample: every percentile is it; non-finite samples are ignored.
  ErrorSamples one;
  one.Add(std::nan(""));
  one.Add(INFINITY);
  one.Add(0.25);
  EXPECT_EQ(one.values.size(), 1u);
  EXPECT_DOUBLE_EQ(one.Percentile(99.9), 0.25);
  EXPECT_DOUBLE_EQ(Percentile({std::nan(""), 4.0, 2.0}, 50), 3.0);
  EXPECT_TRUE(std::isnan(Percentile({1.0}, 101)));
}

TEST(ErrorSamples, MergedPercentilesAreThoseOfAllSamples) {
  std::mt19937_64 rng(5);
  std::lognormal_distribution<double> dist(0.0, 1.0);
  std::vector<double> x(2001);
  for (double& v : x) v = dist(rng);
  ErrorSamples a, b, whole;
  for (size_t i = 0; i < x.size(); ++i) {
    whole.Add(x[i]);
    (i % 3 == 0 ? a : b).Add(x[i]);
  }
  a.Merge(b);
  EXPECT_EQ(a.stats.count, 2001);
  EXPECT_NEAR(a.stats.mean, whole.stats.mean, 1e-12);
  EXPECT_EQ(a.stats.max, whole.stats.max);
  // Reference: a full sort, 2001 samples: h = 2000 × 0.99 = 1980 exactly, and
  // 2000 × 0.999 = 1998 exactly: order statistics, no interpolation.
  std::vector<double> sorted = x;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_NEAR(a.Percentile(99), sorted[1980], 1e-9);
  EXPECT_NEAR(a.Percentile(99.9), sorted[1998], 1e-9);
  EXPECT_DOUBLE_EQ(a.Percentile(100), whole.stats.max);
  // Between ranks: h = 2000 × 0.995 = 1990 and 2000 × 0.9995 = 1999.
  EXPECT_NEAR(a.Percentile(99.95), sorted[1999], 1e-9);
  EXPECT_NEAR(a.Percentile(99.975), 0.5 * (sorted[1999] + sorted[2000]), 1e-9);
}

}  // namespace
}  // namespace csw

// ErrorStats (models/inversion.h): the one mergeable mean / sd / max used by
// the model jobs, against values computed by hand and two-pass formulas.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace csw

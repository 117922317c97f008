#include "analysis/keys/key_timing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.h"

namespace csw::keys {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Values worked by hand: fit 1.000 s with a 5 ms standard error, factor 4
// (20 ms), speech anchor 1.060 s with a 20 ms spread: equal variances, so
// the midpoint 1.030 s.
TEST(CombineWithSpeech, EqualVariancesGiveTheMidpoint) {
  EXPECT_NEAR(CombineWithSpeech(1.000, 0.005, 1.060, 0.020, 4.0), 1.030, 1e-12);
}

// Fit sd 10 ms × 2 = 20 ms (variance 400), spread 40 ms (variance 1600):
// weights 1/400 and 1/1600, i.e. 0.8 and 0.2: 0.8 × 2.000 + 0.2 × 2.100 =
// 2.020 s. A well-determined fit (0.5 ms × 4 = 2 ms against 40 ms: weight
// 1600/1604) moves 100 ms × 4/1604 = 0.249 ms.
TEST(CombineWithSpeech, WeightsAreTheInverseVariances) {
  EXPECT_NEAR(CombineWithSpeech(2.000, 0.010, 2.100, 0.040, 2.0), 2.020, 1e-12);
  EXPECT_NEAR(CombineWithSpeech(2.000, 0.0005, 2.100, 0.040, 4.0), 2.000 + 0.1 * 4.0 / 1604.0, 1e-12);
  // Symmetric: an anchor before the fit pulls it back by as much.
  EXPECT_NEAR(CombineWithSpeech(2.000, 0.010, 1.900, 0.040, 2.0), 1.980, 1e-12);
}

TEST(CombineWithSpeech, NothingToCombineLeavesTheFit) {
  EXPECT_EQ(CombineWithSpeech(1.5, 0.01, 1.7, 0.03, 0.0), 1.5);        // factor 0: off
  EXPECT_EQ(CombineWithSpeech(1.5, kNaN, 1.7, 0.03, 4.0), 1.5);        // no standard error
  EXPECT_EQ(CombineWithSpeech(1.5, 0.01, 1.7, 0.0, 4.0), 1.5);         // no spread
  EXPECT_EQ(CombineWithSpeech(1.5, 0.01, kNaN, 0.03, 4.0), 1.5);       // no anchor
  EXPECT_EQ(CombineWithSpeech(1.5, kInf, 1.7, 0.03, 4.0), 1.7);        // an undetermined fit: the speech alone
  EXPECT_DOUBLE_EQ(CombineWithSpeech(1.5, 0.0, 1.7, 0.03, 4.0), 1.5);  // an exact fit
}

TEST(KeyTimingOptions, ANegativeFitSdFactorIsRefused) {
  KeyTimingOptions o;
  EXPECT_EQ(o.Check(), "");
  o.anchor_fit_sd_factor = -1.0;
  EXPECT_NE(o.Check().find("anchor_fit_sd_factor"), std::string::npos);
  o.anchor_fit_sd_factor = kNaN;
  EXPECT_NE(o.Check(), "");
}

TEST(KeyTimingOptions, ANonPositiveMovementWindowIsRefused) {
  KeyTimingOptions o;
  EXPECT_DOUBLE_EQ(o.max_movement_s, 0.8);
  o.max_movement_s = 0.0;
  EXPECT_NE(o.Check().find("max_movement_s"), std::string::npos);
  o.max_movement_s = kNaN;
  EXPECT_NE(o.Check().find("max_movement_s"), std::string::npos);
}

TEST(KeyTimingOptions, InClassKeepingNeedsAPosteriorInZeroOneAndANonNegativeReach) {
  KeyTimingOptions o;
  EXPECT_EQ(o.Check(), "");
  o.anchor_in_class_posterior = 0.0;
  EXPECT_NE(o.Check().find("anchor_in_class_posterior"), std::string::npos);
  o.anchor_in_class_posterior = 1.5;
  EXPECT_NE(o.Check().find("anchor_in_class_posterior"), std::string::npos);
  o.anchor_in_class_posterior = 1.0;
  EXPECT_EQ(o.Check(), "");
  o.anchor_in_class_max_s = -0.1;
  EXPECT_NE(o.Check().find("anchor_in_class_max_s"), std::string::npos);
  o.anchor_in_class_max_s = kNaN;
  EXPECT_NE(o.Check().find("anchor_in_class_max_s"), std::string::npos);
}

}  // namespace
}  // namespace csw::keys

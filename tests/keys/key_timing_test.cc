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

// A take worked by hand: rest, six keys whose syllables start (A1) every
// 0.3 s from 0.5 s, rest. Both components change at every key; the fitted
// targets lie A1 + 0.10, 0.11, 0.09, 0.105, 0.095 s after their A1, and the
// last key's at 2.28 s, i.e. 0.28 s after its A1 2.0 s. Lags: median
// 0.1025 s, absolute deviations 0.0025 .. 0.1775, MAD 0.0075, spread 0.0111 s,
// so the gate is its 80 ms floor: the last key's target (0.1775 s from A1 +
// lag) is outside it, but within the in-class reach (0.2 s) with the hand in
// its own class (posteriors all 1), so it is kept — unless the final return
// to rest, which has no A1, has its target nearer (2.32 s: 0.04 s away), in
// which case the fit found that return and the target becomes A1 + lag =
// 2.1025 s.
std::vector<TimedKey> AnchorTestKeys(double last_fit_s, double rest_target_s, std::vector<ExpectedKey>* expected) {
  const std::vector<double> fits = {0.60, 0.91, 1.19, 1.505, 1.795, last_fit_s};
  std::vector<TimedKey> keys(8);
  expected->assign(8, ExpectedKey{});
  auto set = [&](size_t k, double target) {
    for (ComponentTiming* c : {&keys[k].shape, &keys[k].placement}) {
      c->changes = true;
      c->kinematic = true;
      c->target_s = target;
    }
    keys[k].target_s = target;
  };
  set(0, 0.40);
  for (size_t k = 1; k <= 6; ++k) {
    set(k, fits[k - 1]);
    (*expected)[k].anchor_s = 0.5 + 0.3 * static_cast<double>(k - 1);
    (*expected)[k].shape = static_cast<int>(k % 2 + 1);
    (*expected)[k].placement = static_cast<int>(k % 2 + 1);
  }
  set(7, rest_target_s);
  return keys;
}

TEST(AnchorToSpeech, AFitOnTheFinalReturnToRestIsReplacedByTheSpeech) {
  const Eigen::MatrixXd shape_post = Eigen::MatrixXd::Ones(300, 9), place_post = Eigen::MatrixXd::Ones(300, 6);
  std::vector<ExpectedKey> expected;
  std::vector<TimedKey> keys = AnchorTestKeys(2.28, 2.32, &expected);
  AnchorToSpeech(keys, expected, KeyTimingOptions{}, shape_post, place_post, 100.0);
  EXPECT_NEAR(keys[6].shape.target_s, 2.1025, 1e-9);
  EXPECT_NEAR(keys[6].placement.target_s, 2.1025, 1e-9);
  EXPECT_TRUE(keys[6].shape.from_speech);
  // The other keys are within the gate and have no standard error to be
  // combined with: unchanged.
  EXPECT_DOUBLE_EQ(keys[3].shape.target_s, 1.19);
  EXPECT_FALSE(keys[3].shape.from_speech);
  EXPECT_DOUBLE_EQ(keys[7].shape.target_s, 2.32);  // the rest itself has no A1

  // The return to rest further than A1 + lag: the in-class fit is kept.
  keys = AnchorTestKeys(2.28, 2.60, &expected);
  AnchorToSpeech(keys, expected, KeyTimingOptions{}, shape_post, place_post, 100.0);
  EXPECT_DOUBLE_EQ(keys[6].shape.target_s, 2.28);
  EXPECT_FALSE(keys[6].shape.from_speech);

  // Out of class (posteriors 0): replaced by the gate alone, wherever the rest.
  keys = AnchorTestKeys(2.28, 2.60, &expected);
  AnchorToSpeech(keys, expected, KeyTimingOptions{}, Eigen::MatrixXd::Zero(300, 9), Eigen::MatrixXd::Zero(300, 6),
                 100.0);
  EXPECT_NEAR(keys[6].shape.target_s, 2.1025, 1e-9);
}

}  // namespace
}  // namespace csw::keys

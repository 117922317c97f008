// Suggested target frames on trajectories built from known minimum-jerk
// movements: the suggestion lands on the true target (where the movement ends
// and the next begins), whatever the expected time's error within the window,
// and says why when there is nothing to suggest.
#include "analysis/target_suggestion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/error.h"

namespace csw::analysis {
namespace {

// Minimum-jerk position fraction at s in [0, 1].
double MinJerk(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10 - 15 * s + 6 * s * s);
}

struct Trajectory {
  Eigen::MatrixXd series;       // frames × 3 (mm)
  std::vector<double> targets;  // true target times (s)
};

// Targets every `period` seconds, each reached by a movement of `duration`
// seconds that starts `period - duration` after the previous target (a hold
// in between), to random points 20-80 mm away; Gaussian noise per coordinate.
Trajectory MakeTrajectory(double rate_hz, int keys, double period, double duration, double noise_mm, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1, 1), amplitude(20, 80);
  std::normal_distribution<double> noise(0, noise_mm);
  std::vector<Eigen::Vector3d> points{Eigen::Vector3d::Zero()};
  Trajectory t;
  for (int k = 0; k < keys; ++k) {
    Eigen::Vector3d dir(unit(rng), unit(rng), unit(rng));
    points.push_back(points.back() + dir.normalized() * amplitude(rng));
    t.targets.push_back(0.3 + period * (k + 1));
  }
  const auto frames = static_cast<Eigen::Index>((t.targets.back() + 0.4) * rate_hz);
  t.series.resize(frames, 3);
  for (Eigen::Index f = 0; f < frames; ++f) {
    const double time = static_cast<double>(f) / rate_hz;
    Eigen::Vector3d p = points[0];
    for (int k = 0; k < keys; ++k) {
      const double start = t.targets[static_cast<size_t>(k)] - duration;
      p += (points[static_cast<size_t>(k) + 1] - points[static_cast<size_t>(k)]) * MinJerk((time - start) / duration);
    }
    for (int d = 0; d < 3; ++d) t.series(f, d) = p(d) + noise(rng);
  }
  return t;
}

TEST(TargetSuggestion, FindsTheTrueTargetsOfMinimumJerkMovementsDespiteExpectedTimeErrors) {
  // 120 Hz, 40 keys, 350 ms per key with 250 ms movements (100 ms holds),
  // 0.2 mm noise. Expected times off by up to ±60 ms (uniform), as the phasing
  // laws' spread would put them.
  for (uint64_t seed : {1u, 2u, 3u}) {
    const Trajectory t = MakeTrajectory(120, 40, 0.35, 0.25, 0.2, seed);
    std::mt19937_64 rng(seed + 100);
    std::uniform_real_distribution<double> error(-0.06, 0.06);
    std::vector<double> expected;
    for (double target : t.targets) expected.push_back(target + error(rng));
    const auto suggestions = SuggestTargets(t.series, 120, expected);
    ASSERT_EQ(suggestions.size(), t.targets.size());
    double sum = 0, worst = 0;
    for (size_t k = 0; k < suggestions.size(); ++k) {
      ASSERT_GE(suggestions[k].frame, 0) << "key " << k << ": " << suggestions[k].why;
      // The hold spans [target, target + 100 ms]: the speed is lowest within
      // it, so a suggestion inside the hold is right.
      const double e = suggestions[k].time_s - t.targets[k];
      EXPECT_GE(e, -0.017) << "seed " << seed << " key " << k;
      EXPECT_LE(e, 0.100 + 0.017) << "seed " << seed << " key " << k;
      EXPECT_NEAR(suggestions[k].offset_s, suggestions[k].time_s - expected[k], 1e-12);
      sum += std::abs(e);
      worst = std::max(worst, std::abs(e));
    }
    EXPECT_LT(sum / static_cast<double>(suggestions.size()), 0.06) << "seed " << seed;
  }
}

TEST(TargetSuggestion, BackToBackMovementsRestAtTheTarget) {
  // No hold: each movement starts at the previous target, so the speed is zero
  // only at the targets; the suggestion must be within 2 frames (17 ms).
  const Trajectory t = MakeTrajectory(120, 30, 0.3, 0.3, 0.2, 7);
  std::vector<double> expected;
  for (double target : t.targets) expected.push_back(target + 0.05);
  const auto suggestions = SuggestTargets(t.series, 120, expected);
  for (size_t k = 0; k < suggestions.size(); ++k) {
    ASSERT_GE(suggestions[k].frame, 0) << suggestions[k].why;
    if (k + 1 < suggestions.size()) {
      EXPECT_NEAR(suggestions[k].time_s, t.targets[k], 2.0 / 120) << "key " << k;
    } else {
      // The last target is followed by stillness: any frame after it is at rest.
      EXPECT_GE(suggestions[k].time_s, t.targets[k] - 2.0 / 120);
    }
  }
}

// Two keys whose windows hold the same speed minimum do not both get it: the
// key expected nearer to it keeps it, the other takes its next minimum in
// time order, or none (with the reason) when its neighbours hold them all.
// The result does not depend on the order of the expected times.
TEST(TargetSuggestion, SuccessiveKeysNeverShareATargetAndKeepTheirOrder) {
  const Trajectory t = MakeTrajectory(120, 6, 0.3, 0.3, 0.2, 11);  // back to back: minima at the targets only
  const double t1 = t.targets[2], t2 = t.targets[3];
  TargetSuggestionOptions wide;
  wide.search_s = 0.2;  // the second key's window holds t1 (0.12 s away) and t2 (0.18 s away)
  {
    const auto s = SuggestTargets(t.series, 120, {t1 - 0.01, t1 + 0.12}, wide);
    ASSERT_GE(s[0].frame, 0) << s[0].why;
    ASSERT_GE(s[1].frame, 0) << s[1].why;
    EXPECT_NEAR(s[0].time_s, t1, 2.0 / 120);
    EXPECT_NEAR(s[1].time_s, t2, 2.0 / 120);  // nearest alone would be t1 again
    // Each alone, the second key takes t1: the rule above is what moved it.
    EXPECT_NEAR(SuggestTargets(t.series, 120, {t1 + 0.12}, wide)[0].time_s, t1, 2.0 / 120);
  }
  for (bool reversed : {false, true}) {
    std::vector<double> expected{t1 - 0.01, t1 + 0.12, t2 + 0.005};
    if (reversed) std::reverse(expected.begin(), expected.end());
    const auto s = SuggestTargets(t.series, 120, expected, wide);
    ASSERT_EQ(s.size(), 3u);
    const SuggestedTarget& a = s[reversed ? 2 : 0];
    const SuggestedTarget& b = s[1];
    const SuggestedTarget& c = s[reversed ? 0 : 2];
    EXPECT_DOUBLE_EQ(a.expected_s, t1 - 0.01);
    EXPECT_NEAR(a.time_s, t1, 2.0 / 120) << reversed;
    EXPECT_NEAR(c.time_s, t2, 2.0 / 120) << reversed;
    EXPECT_EQ(b.frame, -1) << reversed;  // squeezed between its neighbours' targets
    EXPECT_NE(b.why.find("neighbouring keys"), std::string::npos) << b.why;
  }
}

TEST(TargetSuggestion, SaysWhyWhenNothingCanBeSuggested) {
  // A straight line at constant speed never slows down.
  Eigen::MatrixXd line(240, 3);
  for (int f = 0; f < 240; ++f) line.row(f) << f * 1.0, 0, 0;
  auto s = SuggestTargets(line, 120, {1.0});
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].frame, -1);
  EXPECT_NE(s[0].why.find("does not slow down"), std::string::npos) << s[0].why;
  // Missing samples over the window.
  Trajectory t = MakeTrajectory(120, 4, 0.35, 0.25, 0.2, 3);
  for (Eigen::Index f = 0; f < t.series.rows(); ++f)
    if (std::abs(static_cast<double>(f) / 120 - t.targets[1]) < 0.3) t.series(f, 1) = std::nan("");
  s = SuggestTargets(t.series, 120, {t.targets[1], 50.0});
  EXPECT_EQ(s[0].frame, -1);
  EXPECT_NE(s[0].why.find("no valid samples"), std::string::npos) << s[0].why;
  EXPECT_EQ(s[1].frame, -1);
  EXPECT_NE(s[1].why.find("outside the take"), std::string::npos) << s[1].why;
}

TEST(TargetSuggestion, RefusesBadOptionsAndTimes) {
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(100, 2);
  TargetSuggestionOptions o;
  o.search_s = 0;
  EXPECT_THROW(SuggestTargets(x, 100, {0.5}, o), InvalidInput);
  EXPECT_THROW(SuggestTargets(x, 0, {0.5}), InvalidInput);
  EXPECT_THROW(SuggestTargets(x, 100, {std::nan("")}), InvalidInput);
  o = {};
  o.cutoff_hz = 60;  // above Nyquist at 100 Hz
  EXPECT_THROW(SuggestTargets(x, 100, {0.5}, o), InvalidInput);
}

}  // namespace
}  // namespace csw::analysis

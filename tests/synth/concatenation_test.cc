// Selection and concatenation of dictionary units (issue 15 item 4): hand-built
// dictionaries whose units are linear ramps between per-key class values (and,
// for diphones, piecewise linear through a known value at the phone boundary),
// so that every expected value, cost and level is computed here, not read back
// from the code under test.
#include "synth/concatenation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"

namespace csw::dict {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr double kRate = 100;
constexpr double kTol = 1e-9;

KeyCode K(const char* ps) { return KeyCode{ps[0] - '0', ps[1] - '0'}; }

// Per-key class values: hand parameters per shape; forearm-in-head (rx ry rz
// rad, tx ty tz mm) and head pose per placement.
Eigen::RowVectorXd ShapeValue(int s) {
  Eigen::RowVectorXd v(3);
  v << s, 0.5 * s * s, 3.0 - s;
  return v;
}
Eigen::Vector3d PlacementTranslation(int p) {
  static const double t[6][3] = {{0, -150, 100}, {40, 0, 0}, {0, 30, 0}, {0, 60, 0}, {30, -40, 0}, {0, 0, 50}};
  return Eigen::Vector3d(t[p][0], t[p][1], t[p][2]);
}
Eigen::RowVectorXd ForearmValue(int p) {
  Eigen::RowVectorXd v(6);
  const Eigen::Vector3d t = PlacementTranslation(p);
  v << 0.01 * p, -0.02 * p, 0.03 * p, t(0), t(1), t(2);
  return v;
}
Eigen::RowVectorXd HeadValue(int p) {
  Eigen::RowVectorXd v(6);
  v << 0.01 * p, 0.02 * (p % 2), -0.01 * p, 1.0 + p, 2.0 - p, 0.5 * p * p;
  return v;
}

// A dikey of `duration_s` (rows = round(duration · rate) + 1), every stream a
// linear ramp from the leaving key's class value to the arriving key's; the
// first hand parameter starts `offset` above its class value (decaying
// linearly to 0 at the end), for units that do not join their neighbours.
DikeyUnit Dikey(const char* from, const char* to, double duration_s, double offset = 0) {
  DikeyUnit u;
  u.take = std::string("t") + from + to;
  u.from = K(from);
  u.to = K(to);
  u.start_s = 0;
  u.end_s = duration_s;
  u.rate_hz = kRate;
  const auto n = static_cast<Eigen::Index>(std::llround(duration_s * kRate)) + 1;
  u.hand_params.resize(n, 3);
  u.forearm_in_head.resize(n, 6);
  u.head_pose.resize(n, 6);
  for (Eigen::Index r = 0; r < n; ++r) {
    const double a = n > 1 ? static_cast<double>(r) / static_cast<double>(n - 1) : 1.0;
    u.hand_params.row(r) = (1 - a) * ShapeValue(u.from.shape) + a * ShapeValue(u.to.shape);
    u.hand_params(r, 0) += (1 - a) * offset;
    u.forearm_in_head.row(r) = (1 - a) * ForearmValue(u.from.placement) + a * ForearmValue(u.to.placement);
    u.head_pose.row(r) = (1 - a) * HeadValue(u.from.placement) + a * HeadValue(u.to.placement);
  }
  return u;
}

Dictionary DikeyDictionary(std::vector<DikeyUnit> units) {
  Dictionary d;
  d.hand_parameter_names = {"h1", "h2", "h3"};
  d.dikeys = std::move(units);
  return d;
}

std::vector<KeyTarget> Keys(const std::vector<std::pair<const char*, double>>& list) {
  std::vector<KeyTarget> keys;
  for (const auto& [code, t] : list) keys.push_back(KeyTarget{K(code), t});
  return keys;
}

Eigen::Index Frame(double t) { return static_cast<Eigen::Index>(std::llround(t * kRate)); }

double MaxAbsDiff(const Eigen::RowVectorXd& a, const Eigen::RowVectorXd& b) { return (a - b).cwiseAbs().maxCoeff(); }

// Column standard deviations (n − 1) of stacked rows.
Eigen::RowVectorXd ColumnSigma(const Eigen::MatrixXd& rows) {
  const Eigen::RowVectorXd mean = rows.colwise().mean();
  return ((rows.rowwise() - mean).array().square().colwise().sum() / static_cast<double>(rows.rows() - 1))
      .sqrt()
      .matrix();
}

// Every frame of every dikey as [hand | forearm-in-head | head].
Eigen::MatrixXd AllDikeyRows(const Dictionary& d) {
  Eigen::Index n = 0;
  for (const DikeyUnit& u : d.dikeys) n += u.frames();
  Eigen::MatrixXd all(n, 15);
  Eigen::Index r = 0;
  for (const DikeyUnit& u : d.dikeys) {
    all.block(r, 0, u.frames(), 3) = u.hand_params;
    all.block(r, 3, u.frames(), 6) = u.forearm_in_head;
    all.block(r, 9, u.frames(), 6) = u.head_pose;
    r += u.frames();
  }
  return all;
}

TEST(ConcatenateDikeys, AllWholeKeyFramesAreTheUnitsEndRows) {
  // Unit durations 0.25, 0.36, 0.40 s for slots of 0.30, 0.30, 0.40 s.
  const Dictionary d = DikeyDictionary({Dikey("00", "12", 0.25), Dikey("12", "35", 0.36), Dikey("35", "00", 0.40)});
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"35", 0.8}, {"00", 1.2}});
  const HandTrack t = ConcatenateDikeys(d, keys, 1.5);
  ASSERT_EQ(t.frames(), 151);
  EXPECT_EQ(t.rate_hz, kRate);
  ASSERT_EQ(t.hand_params.cols(), 3);
  ASSERT_EQ(t.forearm_in_head.cols(), 6);
  ASSERT_EQ(t.head_pose.cols(), 6);
  ASSERT_EQ(t.keys.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE("slot " + std::to_string(i));
    const KeyReport& r = t.keys[i];
    EXPECT_EQ(r.level, FallbackLevel::kWhole);
    EXPECT_EQ(r.code, keys[i + 1].code);
    EXPECT_EQ(r.used_to, keys[i + 1].code);
    EXPECT_DOUBLE_EQ(r.target_s, keys[i + 1].target_s);
    ASSERT_EQ(r.units, std::vector<int>{static_cast<int>(i)});
    const DikeyUnit& u = d.dikeys[i];
    const Eigen::Index f = Frame(keys[i + 1].target_s);
    EXPECT_LT(MaxAbsDiff(t.hand_params.row(f), u.hand_params.row(u.frames() - 1)), kTol);
    EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(f), u.forearm_in_head.row(u.frames() - 1)), kTol);
    EXPECT_LT(MaxAbsDiff(t.head_pose.row(f), u.head_pose.row(u.frames() - 1)), kTol);
  }
  // The first key frame is the first unit's first row; the ends are held.
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(20), d.dikeys[0].hand_params.row(0)), kTol);
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(0), t.hand_params.row(20)), kTol);
  EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(150), ForearmValue(0)), kTol);
  // Linear warping: frame 65 is halfway through slot 1 (frames 50-80), so
  // halfway along the 12 → 35 ramp whatever the unit's own 37 rows.
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(65), 0.5 * (ShapeValue(2) + ShapeValue(5))), kTol);
  EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(65), 0.5 * (ForearmValue(1) + ForearmValue(3))), kTol);
  // Selection 1 × (|0.25 − 0.30| + |0.36 − 0.30| + |0.40 − 0.40|); every join continuous.
  EXPECT_NEAR(t.total_cost, 0.05 + 0.06 + 0.0, 1e-9);
}

TEST(ConcatenateDikeys, AUnitMuchLongerThanItsSlotIsTrimmedNotCompressed) {
  // A 1.0 s 12 → 35 unit in a 0.4 s slot (frames 50-90): with
  // max_compression 1.25 the slot shows the unit's last 0.5 s, i.e. the ramp
  // from halfway (a = 0.5) to its end; the first slot (00 → 12, 0.5 s) ends at
  // the ramp's start, so smoothing spreads the half-ramp jump over it. Without
  // trimming the whole unit is squeezed (2.5 x) and frame 70 is halfway.
  const Dictionary d = DikeyDictionary({Dikey("00", "12", 0.5), Dikey("12", "35", 1.0), Dikey("35", "00", 0.4)});
  const auto keys = Keys({{"00", 0.0}, {"12", 0.5}, {"35", 0.9}, {"00", 1.3}});
  ConcatOptions o;
  o.max_compression = 1.25;
  const HandTrack t = ConcatenateDikeys(d, keys, 1.3, o);
  const Eigen::RowVectorXd mid = 0.5 * (ShapeValue(2) + ShapeValue(5));
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(50), mid), kTol);  // the trimmed unit's first row
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(70), 0.75 * ShapeValue(5) + 0.25 * ShapeValue(2)), kTol);
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(90), ShapeValue(5)), kTol);
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(25), 0.5 * (ShapeValue(0) + ShapeValue(2)) + 0.5 * (mid - ShapeValue(2))),
            kTol);  // halfway through slot 0: its ramp plus half the jump
  o.max_compression = 0;
  const HandTrack squeezed = ConcatenateDikeys(d, keys, 1.3, o);
  EXPECT_LT(MaxAbsDiff(squeezed.hand_params.row(50), ShapeValue(2)), kTol);
  EXPECT_LT(MaxAbsDiff(squeezed.hand_params.row(70), mid), kTol);
  // The largest step of the first hand parameter in slot 1: 3/40 per frame
  // squeezed, 1.5/40 trimmed (the unit's own ramp is 3 over 100 frames).
  auto max_step = [](const HandTrack& h) {
    double m = 0;
    for (Eigen::Index f = 51; f <= 90; ++f) m = std::max(m, std::abs(h.hand_params(f, 0) - h.hand_params(f - 1, 0)));
    return m;
  };
  EXPECT_NEAR(max_step(squeezed), 3.0 / 40.0, 1e-9);
  EXPECT_NEAR(max_step(t), 1.5 / 40.0, 1e-9);
  // Keeping the key posture: the trimmed half-ramp starts at key 12 again,
  // its offset (shape 2 minus the ramp's middle) fading linearly: frame 50
  // is shape 2, frame 70 the trimmed row (3/4 of the way) plus half the
  // offset, i.e. halfway, frame 90 shape 5; slot 0 has no jump to spread.
  o.max_compression = 1.25;
  o.trim_keeps_key_posture = true;
  const HandTrack kept = ConcatenateDikeys(d, keys, 1.3, o);
  EXPECT_LT(MaxAbsDiff(kept.hand_params.row(50), ShapeValue(2)), kTol);
  EXPECT_LT(MaxAbsDiff(kept.hand_params.row(70), mid), kTol);
  EXPECT_LT(MaxAbsDiff(kept.hand_params.row(90), ShapeValue(5)), kTol);
  EXPECT_LT(MaxAbsDiff(kept.hand_params.row(25), 0.5 * (ShapeValue(0) + ShapeValue(2))), kTol);
  o.trim_keeps_key_posture = false;
  o.max_compression = 0.5;
  EXPECT_THAT([&] { ConcatenateDikeys(d, keys, 1.3, o); },
              ::testing::ThrowsMessage<InvalidInput>(HasSubstr("max_compression must be 0 or >= 1")));
}

// A 12 → 35 dikey of 0.6 s (61 rows) that holds, then moves at constant
// speed: the hand parameters hold shape 2 for rows 0-30 and ramp to shape 5
// over rows 30-60; the forearm and head hold placement 1 for rows 0-40 and
// ramp to placement 3 over rows 40-60.
DikeyUnit HoldThenMove() {
  DikeyUnit u = Dikey("12", "35", 0.6);
  for (Eigen::Index r = 0; r < u.frames(); ++r) {
    const double s = std::clamp((static_cast<double>(r) - 30.0) / 30.0, 0.0, 1.0);
    const double p = std::clamp((static_cast<double>(r) - 40.0) / 20.0, 0.0, 1.0);
    u.hand_params.row(r) = (1 - s) * ShapeValue(2) + s * ShapeValue(5);
    u.forearm_in_head.row(r) = (1 - p) * ForearmValue(1) + p * ForearmValue(3);
    u.head_pose.row(r) = (1 - p) * HeadValue(1) + p * HeadValue(3);
  }
  return u;
}

TEST(ConcatenateDikeys, KeptMovementDurationsFitTheSlotWithTheHoldBeforeThem) {
  // The hold-then-move unit on a 0.4 s slot (frames 50-90). Its movements'
  // onsets by the documented rule (the last frame whose 5-frame mean speed
  // is at most a tenth of the peak): shape row 27 (rows 25-29 still), pose
  // row 37. Kept durations: the shape's last 0.33 s end at frame 90 at their
  // own speed, so the ramp starts at frame 60 (unit row 30) and moves 1/30
  // of the way per frame; the pose ramp starts at frame 70 (unit row 40).
  // The linear warp instead trims the unit's first 0.1 s and compresses the
  // rest 1.25 times: the shape ramp starts at frame 66, 1.25 times faster.
  const Dictionary d = DikeyDictionary({Dikey("00", "12", 0.5), HoldThenMove(), Dikey("35", "00", 0.4)});
  const auto keys = Keys({{"00", 0.0}, {"12", 0.5}, {"35", 0.9}, {"00", 1.3}});
  ConcatOptions o;
  o.max_compression = 1.25;
  o.keep_movement_duration = true;
  const HandTrack kept = ConcatenateDikeys(d, keys, 1.3, o);
  auto shape_at = [](double a) { return ((1 - a) * ShapeValue(2) + a * ShapeValue(5)).eval(); };
  auto pose_at = [](double a) { return ((1 - a) * ForearmValue(1) + a * ForearmValue(3)).eval(); };
  for (Eigen::Index f = 50; f <= 60; ++f) EXPECT_LT(MaxAbsDiff(kept.hand_params.row(f), ShapeValue(2)), kTol) << f;
  for (Eigen::Index f = 60; f <= 90; ++f)
    EXPECT_LT(MaxAbsDiff(kept.hand_params.row(f), shape_at(static_cast<double>(f - 60) / 30.0)), kTol) << f;
  for (Eigen::Index f = 50; f <= 70; ++f) EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(f), ForearmValue(1)), kTol);
  EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(80), pose_at(0.5)), kTol);
  EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(90), ForearmValue(3)), kTol);
  o.keep_movement_duration = false;
  const HandTrack linear = ConcatenateDikeys(d, keys, 1.3, o);
  EXPECT_LT(MaxAbsDiff(linear.hand_params.row(66), ShapeValue(2)), kTol);
  EXPECT_LT(MaxAbsDiff(linear.hand_params.row(78), shape_at(0.5)), kTol);
  EXPECT_LT(MaxAbsDiff(linear.hand_params.row(62), ShapeValue(2)), kTol);

  // A 1.0 s slot (frames 50-150): the hold is stretched, the movements keep
  // their speed and end at frame 150 (shape ramp from frame 120, pose from
  // 130); the linear warp would start the shape ramp at frame 100.
  const auto slow = Keys({{"00", 0.0}, {"12", 0.5}, {"35", 1.5}, {"00", 1.9}});
  o.keep_movement_duration = true;
  const HandTrack stretched = ConcatenateDikeys(d, slow, 1.9, o);
  EXPECT_LT(MaxAbsDiff(stretched.hand_params.row(120), ShapeValue(2)), kTol);
  EXPECT_LT(MaxAbsDiff(stretched.hand_params.row(135), shape_at(0.5)), kTol);
  EXPECT_LT(MaxAbsDiff(stretched.forearm_in_head.row(130), ForearmValue(1)), kTol);
  EXPECT_LT(MaxAbsDiff(stretched.forearm_in_head.row(140), pose_at(0.5)), kTol);

  // A 0.2 s slot (frames 50-70), shorter than the shape's 0.33 s movement:
  // the hold is dropped and the movement compressed at most 1.25 times, so
  // the slot shows the unit's last 0.25 s (from row 35, 1/6 of the ramp):
  // the smoothing carries that step back over the previous slot, and the
  // ramp then runs 1.25 times its own speed.
  const auto fast = Keys({{"00", 0.0}, {"12", 0.5}, {"35", 0.7}, {"00", 1.1}});
  const HandTrack squeezed = ConcatenateDikeys(d, fast, 1.1, o);
  EXPECT_LT(MaxAbsDiff(squeezed.hand_params.row(50), shape_at(1.0 / 6.0)), kTol);
  EXPECT_LT(MaxAbsDiff(squeezed.hand_params.row(62), shape_at(1.0 / 6.0 + 12.0 * 1.25 / 30.0)), kTol);
  EXPECT_LT(MaxAbsDiff(squeezed.hand_params.row(70), ShapeValue(5)), kTol);
}

TEST(ConcatenateDikeys, KeptMovementDurationsKeepThePlacementsArrivalToo) {
  // The hold-then-move unit whose pose stream is still arriving at
  // placement 1 for its first 0.1 s (from_placement_lag_s; rows 0-10 ramp
  // from 5 mm beside it). On the 0.4 s slot the arrival keeps its speed
  // (frames 50-60), so does the movement (from frame 70); the hold between
  // is cut. The linear warp trims the unit's first 0.1 s, the arrival with
  // them: the slot starts on placement 1.
  DikeyUnit u = HoldThenMove();
  Eigen::RowVectorXd beside = Eigen::RowVectorXd::Zero(6);
  beside(3) = 5.0;
  for (Eigen::Index r = 0; r <= 10; ++r)
    u.forearm_in_head.row(r) = ForearmValue(1) + (1.0 - static_cast<double>(r) / 10.0) * beside;
  u.from_placement_lag_s = 0.1;
  const Dictionary d = DikeyDictionary({Dikey("00", "12", 0.5), u, Dikey("35", "00", 0.4)});
  const auto keys = Keys({{"00", 0.0}, {"12", 0.5}, {"35", 0.9}, {"00", 1.3}});
  ConcatOptions o;
  o.max_compression = 1.25;
  o.keep_movement_duration = true;
  const HandTrack kept = ConcatenateDikeys(d, keys, 1.3, o);
  EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(50), ForearmValue(1) + beside), kTol);
  EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(55), ForearmValue(1) + 0.5 * beside), kTol);
  for (Eigen::Index f = 60; f <= 70; ++f)
    EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(f), ForearmValue(1)), kTol) << f;
  EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(80), 0.5 * (ForearmValue(1) + ForearmValue(3))), kTol);
  EXPECT_LT(MaxAbsDiff(kept.forearm_in_head.row(90), ForearmValue(3)), kTol);
  // The reported lag: the arrival ends 0.1 s into the slot.
  ASSERT_EQ(kept.keys.size(), 3u);
  EXPECT_NEAR(kept.keys[1].leaving_placement_lag_s, 0.1, 1e-12);
  o.keep_movement_duration = false;
  const HandTrack linear = ConcatenateDikeys(d, keys, 1.3, o);
  EXPECT_LT(MaxAbsDiff(linear.forearm_in_head.row(50), ForearmValue(1)), kTol);
  EXPECT_NEAR(linear.keys[1].leaving_placement_lag_s, 0.0, 1e-12);
}

// The hold-then-move unit as a CV key's dikey whose target came 50 ms after
// its syllable's A1 in the corpus, between 00 → 12 (0.5 s, a linear ramp) and
// 35 → 00; the keys 12 at 0.5 s, 35 at 0.9 s (A1 given), 00 at 1.3 s.
Dictionary OnsetDictionary(std::optional<KeyType> unit_type) {
  DikeyUnit u = HoldThenMove();
  u.phasing_s = 0.05;
  u.to_type = unit_type;
  return DikeyDictionary({Dikey("00", "12", 0.5), u, Dikey("35", "00", 0.4)});
}
std::vector<KeyTarget> OnsetKeys(double a1_of_35) {
  auto keys = Keys({{"00", 0.0}, {"12", 0.5}, {"35", 0.9}, {"00", 1.3}});
  keys[2].a1_s = a1_of_35;
  keys[2].type = KeyType::kCV;
  return keys;
}

TEST(ConcatenateDikeys, MovementOnsetsStartEachMovementAtItsSyllablesPhasing) {
  // Movement onsets by the documented rule: shape row 27, pose row 37 (see
  // KeptMovementDurations...), so the unit's shape movement lasts 0.33 s and
  // started 0.05 − 0.33 = −0.28 s from A1, the pose movement 0.23 s from
  // −0.18 s. With A1 at 0.80 s the shape movement is laid on 0.52-0.90 s
  // (unit time 0.27 + (t − 0.52) · 0.33 / 0.38; its ramp, rows 30-60, starts
  // at 0.5545 s) and the pose movement on 0.62-0.90 s (unit time 0.37 +
  // (t − 0.62) · 0.23 / 0.28). The linear warp instead trims the unit's
  // first 0.1 s: the shape ramp starts at frame 66.
  const Dictionary d = OnsetDictionary(KeyType::kCV);
  ConcatOptions o;
  o.max_compression = 1.25;
  o.movement_onsets = true;
  const HandTrack t = ConcatenateDikeys(d, OnsetKeys(0.80), 1.3, o);
  auto shape_at = [](double a) { return ((1 - a) * ShapeValue(2) + a * ShapeValue(5)).eval(); };
  auto pose_at = [](double a) { return ((1 - a) * ForearmValue(1) + a * ForearmValue(3)).eval(); };
  auto head_at = [](double a) { return ((1 - a) * HeadValue(1) + a * HeadValue(3)).eval(); };
  auto shape_row = [](double time) { return 100.0 * (0.27 + (time - 0.52) * 0.33 / 0.38); };
  auto pose_row = [](double time) { return 100.0 * (0.37 + (time - 0.62) * 0.23 / 0.28); };
  for (Eigen::Index f = 50; f <= 55; ++f) EXPECT_LT(MaxAbsDiff(t.hand_params.row(f), ShapeValue(2)), kTol) << f;
  for (Eigen::Index f = 56; f <= 90; ++f) {
    const double a = std::clamp((shape_row(f / kRate) - 30.0) / 30.0, 0.0, 1.0);
    EXPECT_LT(MaxAbsDiff(t.hand_params.row(f), shape_at(a)), 1e-9) << f;
  }
  EXPECT_NEAR((shape_row(0.70) - 30.0) / 30.0, 0.421053, 1e-6);  // the check above at frame 70, by hand
  for (Eigen::Index f = 50; f <= 65; ++f) EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(f), ForearmValue(1)), kTol) << f;
  EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(80), pose_at((pose_row(0.80) - 40.0) / 20.0)), 1e-9);
  EXPECT_LT(MaxAbsDiff(t.head_pose.row(80), head_at((pose_row(0.80) - 40.0) / 20.0)), 1e-9);
  EXPECT_NEAR((pose_row(0.80) - 40.0) / 20.0, 0.589286, 1e-6);
  EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(90), ForearmValue(3)), kTol);
  // The previous slot is untouched: the 00 → 12 ramp.
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(45), 0.1 * ShapeValue(0) + 0.9 * ShapeValue(2)), kTol);

  o.movement_onsets = false;
  const HandTrack linear = ConcatenateDikeys(d, OnsetKeys(0.80), 1.3, o);
  EXPECT_LT(MaxAbsDiff(linear.hand_params.row(66), ShapeValue(2)), kTol);
  EXPECT_GT(MaxAbsDiff(linear.hand_params.row(60), t.hand_params.row(60)), 0.1);
}

TEST(ConcatenateDikeys, AnEarlyMovementOverlapsThePreviousSlot) {
  // A1 at 0.70 s: the shape movement starts at 0.70 + 0.05 − 0.33 = 0.42 s,
  // 0.08 s before its slot (allowed: up to 0.3 of the previous 0.5 s slot).
  // It is laid on 0.42-0.90 s (unit time 0.27 + (t − 0.42) · 0.33 / 0.48),
  // and before 0.5 s its displacement from the held shape 2 is added to the
  // 00 → 12 ramp. The pose movement starts at 0.52 s, inside its slot.
  const Dictionary d = OnsetDictionary(KeyType::kCV);
  ConcatOptions o;
  o.max_compression = 1.25;
  o.movement_onsets = true;
  const HandTrack t = ConcatenateDikeys(d, OnsetKeys(0.70), 1.3, o);
  auto shape_at = [](double a) { return ((1 - a) * ShapeValue(2) + a * ShapeValue(5)).eval(); };
  auto pose_at = [](double a) { return ((1 - a) * ForearmValue(1) + a * ForearmValue(3)).eval(); };
  auto ramp = [](double a) { return ((1 - a) * ShapeValue(0) + a * ShapeValue(2)).eval(); };
  // Frame 48: unit time 0.31125 (row 31.125, 0.0375 of the ramp), on the
  // 00 → 12 ramp at 0.96.
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(48), ramp(0.96) + shape_at(0.0375) - ShapeValue(2)), 1e-9);
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(40), ramp(0.8)), kTol);             // before 0.42 s: untouched
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(50), shape_at(2.5 / 30.0)), 1e-9);  // row 32.5
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(60), shape_at(0.3125)), 1e-9);      // row 39.375
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(90), ShapeValue(5)), kTol);
  // Pose: unit time 0.37 + (0.80 − 0.52) · 0.23 / 0.38 at frame 80 (row 53.95).
  EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(80), pose_at((100.0 * (0.37 + 0.28 * 0.23 / 0.38) - 40.0) / 20.0)), 1e-9);
  // No step anywhere: frame-to-frame changes stay below the fastest ramp's.
  for (Eigen::Index f = 1; f < t.frames(); ++f)
    EXPECT_LT(MaxAbsDiff(t.hand_params.row(f), t.hand_params.row(f - 1)), 0.5) << f;

  // The overlap capped at a tenth of the previous slot: the movement starts
  // at 0.45 s (unit time 0.27 + (t − 0.45) · 0.33 / 0.45; row 38 at 0.6 s).
  o.max_onset_overlap = 0.1;
  const HandTrack capped = ConcatenateDikeys(d, OnsetKeys(0.70), 1.3, o);
  EXPECT_LT(MaxAbsDiff(capped.hand_params.row(60), shape_at(8.0 / 30.0)), 1e-9);
  EXPECT_LT(MaxAbsDiff(capped.hand_params.row(45), ramp(0.9)), kTol);
  // None: it starts with its slot (unit time 0.27 + (t − 0.5) · 0.33 / 0.4;
  // row 35.25 at 0.6 s) and the previous slot is the plain ramp.
  o.max_onset_overlap = 0;
  const HandTrack none = ConcatenateDikeys(d, OnsetKeys(0.70), 1.3, o);
  EXPECT_LT(MaxAbsDiff(none.hand_params.row(60), shape_at(5.25 / 30.0)), 1e-9);
  EXPECT_LT(MaxAbsDiff(none.hand_params.row(48), ramp(0.96)), kTol);
}

TEST(ConcatenateDikeys, MovementOnsetsNeedTheKeysA1AndAUnitOfItsType) {
  // A unit measured on a lone vowel (another A1), or a key without A1: the
  // slot is warped as without the option. Both warp options at once, or an
  // overlap outside [0, 1], are refused.
  ConcatOptions o;
  o.max_compression = 1.25;
  const HandTrack plain = ConcatenateDikeys(OnsetDictionary(KeyType::kCV), OnsetKeys(0.80), 1.3, o);
  o.movement_onsets = true;
  const HandTrack other_type = ConcatenateDikeys(OnsetDictionary(KeyType::kVowelAlone), OnsetKeys(0.80), 1.3, o);
  EXPECT_LT((other_type.hand_params - plain.hand_params).cwiseAbs().maxCoeff(), kTol);
  EXPECT_LT((other_type.forearm_in_head - plain.forearm_in_head).cwiseAbs().maxCoeff(), kTol);
  const HandTrack no_a1 =
      ConcatenateDikeys(OnsetDictionary(KeyType::kCV), OnsetKeys(std::numeric_limits<double>::quiet_NaN()), 1.3, o);
  EXPECT_LT((no_a1.hand_params - plain.hand_params).cwiseAbs().maxCoeff(), kTol);
  o.keep_movement_duration = true;
  try {
    ConcatenateDikeys(OnsetDictionary(KeyType::kCV), OnsetKeys(0.80), 1.3, o);
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("keep_movement_duration and movement_onsets exclude each other"));
  }
  o.keep_movement_duration = false;
  o.max_onset_overlap = 1.5;
  EXPECT_THROW(ConcatenateDikeys(OnsetDictionary(KeyType::kCV), OnsetKeys(0.80), 1.3, o), InvalidInput);
}

TEST(ConcatenateDikeys, LeavingPlacementLagFollowsTheSlotsWarpAndTrim) {
  // Units leaving 12 and 35 whose placements arrived 0.1 s and -0.03 s after
  // their first rows. 12 → 35 (0.5 s) on a 0.25 s slot: with no trimming the
  // lag is warped to 0.05 s; with max_compression 1.25 the unit's first 0.375
  // s are trimmed (the 0.1 s arrival with them): 0. A negative lag (the
  // placement arrived before the shape target) is kept as it is; the rest's
  // unknown lag stays NaN.
  std::vector<DikeyUnit> units = {Dikey("00", "12", 0.3), Dikey("12", "35", 0.5), Dikey("35", "00", 0.4)};
  units[1].from_placement_lag_s = 0.1;
  units[2].from_placement_lag_s = -0.03;
  const Dictionary d = DikeyDictionary(units);
  const auto keys = Keys({{"00", 0.0}, {"12", 0.3}, {"35", 0.55}, {"00", 0.95}});
  ConcatOptions o;
  o.max_compression = 0;
  HandTrack t = ConcatenateDikeys(d, keys, 1.0, o);
  ASSERT_EQ(t.keys.size(), 3u);
  EXPECT_TRUE(std::isnan(t.keys[0].leaving_placement_lag_s));
  EXPECT_NEAR(t.keys[1].leaving_placement_lag_s, 0.05, 1e-12);
  EXPECT_NEAR(t.keys[2].leaving_placement_lag_s, -0.03, 1e-12);
  o.max_compression = 1.25;
  t = ConcatenateDikeys(d, keys, 1.0, o);
  EXPECT_NEAR(t.keys[1].leaving_placement_lag_s, 0.0, 1e-12);
}

TEST(ConcatenateDikeys, ChoosesTheCloserDurationWhenJoinsTie) {
  // Two continuous 12 → 35 candidates for a 0.30 s slot: 0.20 s (listed
  // first) and 0.32 s.
  const Dictionary d = DikeyDictionary(
      {Dikey("00", "12", 0.30), Dikey("12", "35", 0.20), Dikey("12", "35", 0.32), Dikey("35", "00", 0.40)});
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"35", 0.8}, {"00", 1.2}});
  const HandTrack t = ConcatenateDikeys(d, keys, 1.5);
  ASSERT_EQ(t.keys.size(), 3u);
  EXPECT_EQ(t.keys[0].units, std::vector<int>{0});
  EXPECT_EQ(t.keys[1].units, std::vector<int>{2});
  EXPECT_EQ(t.keys[2].units, std::vector<int>{3});
  EXPECT_NEAR(t.total_cost, 0.02, 1e-9);
  // With selection weight 3 the cost triples.
  ConcatOptions o;
  o.selection_weight = 3;
  EXPECT_NEAR(ConcatenateDikeys(d, keys, 1.5, o).total_cost, 0.06, 1e-9);
}

TEST(ConcatenateDikeys, ChoosesTheContinuousCandidateWhenDurationsTie) {
  // Two 0.30 s candidates for 12 → 35: the first starts 0.8 above the end of
  // 00 → 12 in the first hand parameter, the second joins it exactly.
  const Dictionary d = DikeyDictionary(
      {Dikey("00", "12", 0.30), Dikey("12", "35", 0.30, 0.8), Dikey("12", "35", 0.30), Dikey("35", "00", 0.40)});
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"35", 0.8}, {"00", 1.2}});
  const HandTrack t = ConcatenateDikeys(d, keys, 1.5);
  EXPECT_EQ(t.keys[1].units, std::vector<int>{2});
  EXPECT_NEAR(t.total_cost, 0.0, 1e-9);
}

TEST(ConcatenateDikeys, TargetCostLeavesOutUnitsCutAtAnApproachedKey) {
  // One take where key 12 was only approached: its 00 -> 12 unit (A) ends,
  // and its 12 -> 35 unit (B) starts, 0.8 above shape 2's value in hand
  // parameter 1; both last exactly their slots. Typical units C, D (0.05 s
  // off their slots), G, and E, F (not needed here) reach every class value.
  DikeyUnit a = Dikey("00", "12", 0.30);
  for (Eigen::Index r = 0; r < a.frames(); ++r)
    a.hand_params(r, 0) += 0.8 * static_cast<double>(r) / static_cast<double>(a.frames() - 1);
  const Dictionary d =
      DikeyDictionary({a, Dikey("12", "35", 0.30, 0.8), Dikey("00", "12", 0.25), Dikey("12", "35", 0.25),
                       Dikey("35", "00", 0.40), Dikey("35", "12", 0.3), Dikey("12", "00", 0.3)});
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"35", 0.8}, {"00", 1.2}});
  // Without the target cost the seed's costs pick A, B: no mismatch, no jump.
  const HandTrack seed = ConcatenateDikeys(d, keys, 1.5);
  EXPECT_EQ(seed.keys[0].units, std::vector<int>{0});
  EXPECT_EQ(seed.keys[1].units, std::vector<int>{1});
  EXPECT_NEAR(seed.total_cost, 0.0, kTol);
  // Shape 2's mean over the six instants of key 12 (A's end, B's start, C's
  // end, D's start, E's end, F's start) is 0.8 x 2 / 6 above its value: B
  // starts 0.8 - 0.267 from it, D 0.267. The cost is the RMS over the three
  // hand parameters of that distance / the column's sd, times the weight;
  // placements, rests and shape 5 are exact everywhere.
  ConcatOptions o;
  o.target_weight = 10;
  const HandTrack t = ConcatenateDikeys(d, keys, 1.5, o);
  EXPECT_EQ(t.keys[0].units, std::vector<int>{2});
  EXPECT_EQ(t.keys[1].units, std::vector<int>{3});
  EXPECT_EQ(t.keys[2].units, std::vector<int>{4});
  const double sigma0 = ColumnSigma(AllDikeyRows(d))(0);
  const double mean_offset = 0.8 * 2.0 / 6.0;
  EXPECT_NEAR(t.total_cost, 0.05 + 0.05 + 10 * std::sqrt(1.0 / 3.0) * mean_offset / sigma0, 1e-9);
  // The key 12 is held at its class value (D's first row), not 0.8 above.
  EXPECT_NEAR(t.hand_params(Frame(0.5), 0), ShapeValue(2)(0), kTol);
  EXPECT_NEAR(seed.hand_params(Frame(0.5), 0), ShapeValue(2)(0) + 0.8, kTol);
  o.target_weight = -1;
  EXPECT_THAT([&] { ConcatenateDikeys(d, keys, 1.5, o); },
              ::testing::ThrowsMessage<InvalidInput>(HasSubstr("target_weight must be >= 0")));
}

TEST(ConcatenateDikeys, PosturePullMovesAnApproachedKeyTowardItsCodesExemplar) {
  // Key 12 was only approached in one take: its 00 -> 12 unit A ends, and
  // its 12 -> 35 unit B starts, 0.8 above shape 2's value in hand parameter
  // 1 and 20 mm beyond placement 1's in forearm tx; they are the only units
  // of their successions, so they are chosen. Four more instances of code
  // 12 (the ends of two 35 -> 12 units, the starts of two 12 -> 00 units)
  // are exact: code 12's mean is a third of the way (0.267, 6.67 mm), its sd
  // 0.377 and 9.43 mm (population), 1.414 sd from the approached posture
  // in both; its exemplar (the instance nearest the mean) is exact. Codes
  // 00 and 35 have four instances each.
  DikeyUnit a = Dikey("00", "12", 0.30), b = Dikey("12", "35", 0.30, 0.8);
  for (Eigen::Index r = 0; r < a.frames(); ++r) {
    const double u = static_cast<double>(r) / static_cast<double>(a.frames() - 1);
    a.hand_params(r, 0) += 0.8 * u;
    a.forearm_in_head(r, 3) += 20.0 * u;
    b.forearm_in_head(r, 3) += 20.0 * (1.0 - u);
  }
  const Dictionary d = DikeyDictionary({a, b, Dikey("35", "12", 0.3), Dikey("12", "00", 0.3), Dikey("35", "12", 0.3),
                                        Dikey("12", "00", 0.3), Dikey("35", "00", 0.4)});
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"35", 0.8}, {"00", 1.2}});
  const HandTrack plain = ConcatenateDikeys(d, keys, 1.5);
  ASSERT_EQ(plain.keys[0].units, std::vector<int>{0});
  ASSERT_EQ(plain.keys[1].units, std::vector<int>{1});
  EXPECT_TRUE(plain.postures.empty());
  EXPECT_NEAR(plain.hand_params(Frame(0.5), 0), ShapeValue(2)(0) + 0.8, kTol);

  // RMS over the 3 + 6 values: from the mean sqrt(2 x 1.414^2 / 9) = 2/3;
  // from the exemplar (2.121 sd in both) 1.0, so radius 0.5 moves it half
  // way: 0.4 above and 10 mm beyond.
  ConcatOptions o;
  o.posture_radius = 0.5;
  const HandTrack t = ConcatenateDikeys(d, keys, 1.5, o);
  ASSERT_EQ(t.postures.size(), 4u);
  EXPECT_NEAR(t.postures[1].distance, 2.0 / 3.0, 1e-9);
  EXPECT_TRUE(t.postures[1].pulled);
  for (size_t i : {0u, 2u, 3u}) {
    EXPECT_TRUE(std::isnan(t.postures[i].distance)) << i;  // 4 instances < posture_min_instances 5
    EXPECT_FALSE(t.postures[i].pulled) << i;
  }
  EXPECT_NEAR(t.hand_params(Frame(0.5), 0), ShapeValue(2)(0) + 0.4, 1e-9);
  EXPECT_NEAR(t.forearm_in_head(Frame(0.5), 3), ForearmValue(1)(3) + 10.0, 1e-9);
  // Only those two values move; the other keys' frames keep their postures,
  // and halfway through each neighbouring slot the minimum-jerk ramp has
  // made half the correction.
  Eigen::RowVectorXd expected = plain.hand_params.row(Frame(0.5));
  expected(0) -= 0.4;
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(Frame(0.5)), expected), 1e-9);
  for (double time : {0.2, 0.8, 1.2, 1.4}) {
    EXPECT_LT(MaxAbsDiff(t.hand_params.row(Frame(time)), plain.hand_params.row(Frame(time))), 1e-12) << time;
    EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(Frame(time)), plain.forearm_in_head.row(Frame(time))), 1e-12) << time;
  }
  EXPECT_NEAR(t.hand_params(Frame(0.35), 0) - plain.hand_params(Frame(0.35), 0), -0.2, 1e-9);
  EXPECT_NEAR(t.forearm_in_head(Frame(0.65), 3) - plain.forearm_in_head(Frame(0.65), 3), -5.0, 1e-9);

  // Radius 2/3 or more leaves it; a code needing more instances is left.
  o.posture_radius = 0.7;
  EXPECT_NEAR(ConcatenateDikeys(d, keys, 1.5, o).hand_params(Frame(0.5), 0), ShapeValue(2)(0) + 0.8, kTol);
  o.posture_radius = 0.5;
  o.posture_min_instances = 7;
  const HandTrack few = ConcatenateDikeys(d, keys, 1.5, o);
  EXPECT_NEAR(few.hand_params(Frame(0.5), 0), ShapeValue(2)(0) + 0.8, kTol);
  EXPECT_TRUE(std::isnan(few.postures[1].distance));
  o.posture_min_instances = 0;
  EXPECT_THAT([&] { ConcatenateDikeys(d, keys, 1.5, o); },
              ::testing::ThrowsMessage<InvalidInput>(HasSubstr("posture_min_instances must be >= 1")));
  o.posture_min_instances = 5;
  o.posture_radius = -1;
  EXPECT_THAT([&] { ConcatenateDikeys(d, keys, 1.5, o); },
              ::testing::ThrowsMessage<InvalidInput>(HasSubstr("posture_radius must be >= 0")));
  o.posture_radius = std::numeric_limits<double>::infinity();
  EXPECT_THAT([&] { ConcatenateDikeys(d, keys, 1.5, o); },
              ::testing::ThrowsMessage<InvalidInput>(HasSubstr("posture_radius must be >= 0")));
}

TEST(ConcatenateDikeys, ConcatenationCostIsTheWeightedRmsOfTheNormalisedJump) {
  // Only the discontinuous candidate: the path's cost is its one jump, 0.8 in
  // hand parameter 1, divided by that column's standard deviation over every
  // frame of the dictionary, times sqrt(w_1 / Σw).
  const Dictionary d =
      DikeyDictionary({Dikey("00", "12", 0.30), Dikey("12", "35", 0.30, 0.8), Dikey("35", "00", 0.40)});
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"35", 0.8}, {"00", 1.2}});
  const double sigma0 = ColumnSigma(AllDikeyRows(d))(0);
  EXPECT_NEAR(ConcatenateDikeys(d, keys, 1.5).total_cost, std::sqrt(1.0 / 15.0) * 0.8 / sigma0, 1e-9);
  ConcatOptions o;
  o.hand_weights = Eigen::Vector3d(3, 1, 1);  // Σw = 3 + 1 + 1 + 12 pose columns
  o.concatenation_weight = 2;
  EXPECT_NEAR(ConcatenateDikeys(d, keys, 1.5, o).total_cost, 2 * std::sqrt(3.0 / 17.0) * 0.8 / sigma0, 1e-9);
}

double MaxJump(const Eigen::MatrixXd& m, Eigen::Index col) {
  double worst = 0;
  for (Eigen::Index f = 1; f < m.rows(); ++f) worst = std::max(worst, std::abs(m(f, col) - m(f - 1, col)));
  return worst;
}

TEST(ConcatenateDikeys, SmoothingSpreadsTheBoundaryJumpOverThePreviousUnit) {
  // 12 → 35 starts 3.0 above where 00 → 12 ends (hand parameter 1).
  const Dictionary d =
      DikeyDictionary({Dikey("00", "12", 0.30), Dikey("12", "35", 0.30, 3.0), Dikey("35", "00", 0.40)});
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"35", 0.8}, {"00", 1.2}});
  ConcatOptions raw;
  raw.smoothing = false;
  const HandTrack without = ConcatenateDikeys(d, keys, 1.5, raw);
  const HandTrack with = ConcatenateDikeys(d, keys, 1.5);
  const double jump_without = MaxJump(without.hand_params, 0), jump_with = MaxJump(with.hand_params, 0);
  std::printf("largest frame-to-frame jump of hand parameter 1: %.4f without smoothing, %.4f with\n", jump_without,
              jump_with);
  // Without: frame 50 is the end of 00 → 12 (2.0), and 12 → 35 holds 5.0
  // (its ramp 2 → 5 plus the offset 3 decaying to 0): a jump of 3.0. With:
  // the 3.0 is spread over the 30 frames of slot 0 (0.1 a frame) on top of
  // its ramp of 2/30 a frame.
  EXPECT_NEAR(jump_without, 3.0, 1e-9);
  EXPECT_NEAR(jump_with, 2.0 / 30 + 0.1, 1e-9);
  EXPECT_LT(jump_with, 0.1 * jump_without);
  // The next unit's onset is the target: key frame 50 is its first row.
  EXPECT_LT(MaxAbsDiff(with.hand_params.row(50), d.dikeys[1].hand_params.row(0)), kTol);
  // Smoothing moves only slot 0: slot 1 and 2 frames are the same.
  EXPECT_LT((with.hand_params.bottomRows(100) - without.hand_params.bottomRows(100)).cwiseAbs().maxCoeff(), kTol);
}

// Index of the class (key of `means`) whose mean is nearest (Euclidean) to v.
int Nearest(const std::map<int, Eigen::RowVectorXd>& means, const Eigen::RowVectorXd& v) {
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (const auto& [c, m] : means) {
    const double dist = (m - v).norm();
    if (dist < best_d) {
      best_d = dist;
      best = c;
    }
  }
  return best;
}

// Class means computed here from the units' end rows: hand parameters per
// shape, forearm-in-head translation per placement.
void ClassMeans(const Dictionary& d, std::map<int, Eigen::RowVectorXd>* shapes,
                std::map<int, Eigen::RowVectorXd>* placements) {
  std::map<int, std::pair<Eigen::RowVectorXd, int>> s, p;
  auto add = [](std::map<int, std::pair<Eigen::RowVectorXd, int>>& m, int c, const Eigen::RowVectorXd& v) {
    auto it = m.find(c);
    if (it == m.end()) {
      m[c] = {v, 1};
    } else {
      it->second.first += v;
      ++it->second.second;
    }
  };
  for (const DikeyUnit& u : d.dikeys) {
    const Eigen::Index last = u.frames() - 1;
    add(s, u.from.shape, u.hand_params.row(0));
    add(s, u.to.shape, u.hand_params.row(last));
    add(p, u.from.placement, u.forearm_in_head.row(0).tail(3));
    add(p, u.to.placement, u.forearm_in_head.row(last).tail(3));
  }
  for (const auto& [c, sum] : s) (*shapes)[c] = sum.first / sum.second;
  for (const auto& [c, sum] : p) (*placements)[c] = sum.first / sum.second;
}

// Slots 12 → 33 (level 1: 12 → 23 exists, placement 2 is 30 mm from 3 and 5
// is 78 mm away), 33 → 25 (level 2: shape 3 → 5 from 13 → 45, placement 3 → 2
// from 31 → 27), 25 → 48 (level 3: no unit leaves 25, no shape succession
// 5 → 8, no placement succession 2 → 4), the others whole.
Dictionary FallbackDictionary() {
  return DikeyDictionary({Dikey("00", "12", 0.3), Dikey("12", "23", 0.3), Dikey("12", "53", 0.3),
                          Dikey("13", "45", 0.3), Dikey("31", "27", 0.3), Dikey("48", "00", 0.4)});
}
std::vector<KeyTarget> FallbackKeys() {
  return Keys({{"00", 0.2}, {"12", 0.5}, {"33", 0.8}, {"25", 1.1}, {"48", 1.4}, {"00", 1.8}});
}

TEST(ConcatenateDikeys, FallbackChainStillProducesEveryIntendedKey) {
  const Dictionary d = FallbackDictionary();
  const auto keys = FallbackKeys();
  const HandTrack t = ConcatenateDikeys(d, keys, 2.0);
  ASSERT_EQ(t.keys.size(), 5u);
  const std::vector<FallbackLevel> levels = {FallbackLevel::kWhole, FallbackLevel::kClosestPlacement,
                                             FallbackLevel::kTwoStreams, FallbackLevel::kInterpolated,
                                             FallbackLevel::kWhole};
  const std::vector<std::vector<int>> units = {{0}, {1}, {3, 4}, {}, {5}};
  for (size_t i = 0; i < 5; ++i) {
    SCOPED_TRACE("slot " + std::to_string(i) + " → " + keys[i + 1].code.Text());
    EXPECT_EQ(t.keys[i].level, levels[i]) << FallbackLevelName(t.keys[i].level);
    EXPECT_EQ(t.keys[i].units, units[i]);
    EXPECT_EQ(t.keys[i].code, keys[i + 1].code);
  }
  EXPECT_EQ(t.keys[1].used_to, K("23"));
  EXPECT_EQ(t.keys[2].used_to, K("25"));
  EXPECT_STREQ(FallbackLevelName(FallbackLevel::kClosestPlacement), "closest placement");
  EXPECT_STREQ(FallbackLevelName(FallbackLevel::kTwoStreams), "two streams");

  std::map<int, Eigen::RowVectorXd> shapes, placements;
  ClassMeans(d, &shapes, &placements);
  ASSERT_EQ(shapes.size(), 7u);  // 0 1 2 3 5 7 8
  ASSERT_EQ(placements.size(), 6u);
  for (const KeyTarget& k : keys) {
    SCOPED_TRACE("key " + k.code.Text() + " at " + std::to_string(k.target_s));
    const Eigen::Index f = Frame(k.target_s);
    EXPECT_EQ(Nearest(shapes, t.hand_params.row(f)), k.code.shape);
    EXPECT_EQ(Nearest(placements, t.forearm_in_head.row(f).tail(3)), k.code.placement);
    // With smoothing each key lands exactly on its class value.
    EXPECT_LT(MaxAbsDiff(t.hand_params.row(f), ShapeValue(k.code.shape)), kTol);
    EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(f), ForearmValue(k.code.placement)), kTol);
  }
  // Level 3 is a minimum-jerk blend of the class values: frame 125, halfway
  // through 25 → 48 (frames 110-140), is their midpoint.
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(125), 0.5 * (ShapeValue(5) + ShapeValue(8))), kTol);
  EXPECT_LT(MaxAbsDiff(t.head_pose.row(125), 0.5 * (HeadValue(2) + HeadValue(4))), kTol);
}

// Largest frame-to-frame Euclidean step of the forearm-in-head translation (mm).
double MaxTranslationStep(const Eigen::MatrixXd& forearm_in_head) {
  double worst = 0;
  for (Eigen::Index f = 1; f < forearm_in_head.rows(); ++f)
    worst = std::max(worst, (forearm_in_head.row(f).tail(3) - forearm_in_head.row(f - 1).tail(3)).norm());
  return worst;
}

TEST(ConcatenateDikeys, FallbackChainWithNoisyUnitsStillProducesEveryIntendedKey) {
  // The fallback dictionary with every unit three times (0.25, 0.30, 0.35 s),
  // each end moved by deterministic noise: hand parameters ±0.2, rotations
  // ±0.005 rad, translations ±3 mm (placements are ≥ 30 mm apart), so no unit
  // joins its neighbour exactly.
  uint32_t state = 12345;
  auto noise = [&state](double scale) {
    state = state * 1664525u + 1013904223u;  // LCG: the same numbers everywhere
    return scale * (static_cast<double>(state >> 8) / static_cast<double>(1u << 24) * 2.0 - 1.0);
  };
  std::vector<DikeyUnit> units;
  for (const DikeyUnit& base : FallbackDictionary().dikeys) {
    for (double duration : {0.25, 0.30, 0.35}) {
      DikeyUnit u = Dikey(base.from.Text().c_str(), base.to.Text().c_str(), duration);
      Eigen::RowVectorXd n0(15), n1(15);
      for (Eigen::Index c = 0; c < 15; ++c) {
        const double scale = c < 3 ? 0.2 : (c < 6 || (c >= 9 && c < 12)) ? 0.005 : 3.0;
        n0(c) = noise(scale);
        n1(c) = noise(scale);
      }
      for (Eigen::Index r = 0; r < u.frames(); ++r) {
        const double a = static_cast<double>(r) / static_cast<double>(u.frames() - 1);
        const Eigen::RowVectorXd n = (1 - a) * n0 + a * n1;
        u.hand_params.row(r) += n.head(3);
        u.forearm_in_head.row(r) += n.segment(3, 6);
        u.head_pose.row(r) += n.tail(6);
      }
      units.push_back(std::move(u));
    }
  }
  const Dictionary d = DikeyDictionary(std::move(units));
  const auto keys = FallbackKeys();
  const HandTrack t = ConcatenateDikeys(d, keys, 2.0);
  ConcatOptions raw;
  raw.smoothing = false;
  const HandTrack r = ConcatenateDikeys(d, keys, 2.0, raw);
  const std::vector<FallbackLevel> levels = {FallbackLevel::kWhole, FallbackLevel::kClosestPlacement,
                                             FallbackLevel::kTwoStreams, FallbackLevel::kInterpolated,
                                             FallbackLevel::kWhole};
  ASSERT_EQ(t.keys.size(), 5u);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(t.keys[i].level, levels[i]) << "slot " << i;
  EXPECT_EQ(t.keys[1].used_to, K("23"));
  std::map<int, Eigen::RowVectorXd> shapes, placements;
  ClassMeans(d, &shapes, &placements);
  for (const KeyTarget& k : keys) {
    SCOPED_TRACE("key " + k.code.Text() + " at " + std::to_string(k.target_s));
    const Eigen::Index f = Frame(k.target_s);
    EXPECT_EQ(Nearest(shapes, t.hand_params.row(f)), k.code.shape);
    EXPECT_EQ(Nearest(placements, t.forearm_in_head.row(f).tail(3)), k.code.placement);
  }
  // Without smoothing key 33 (level 1) stays at placement 2.
  EXPECT_EQ(Nearest(placements, r.forearm_in_head.row(Frame(0.8)).tail(3)), 2);
  const double step_with = MaxTranslationStep(t.forearm_in_head), step_without = MaxTranslationStep(r.forearm_in_head);
  std::printf("noisy fallback: largest forearm-in-head translation step %.2f mm with smoothing, %.2f mm without\n",
              step_with, step_without);
  // Without smoothing the level-1 unit's end (placement 2) jumps 30 mm to the
  // next unit's start (placement 3).
  EXPECT_GT(step_without, 25.0);
  EXPECT_LT(step_with, 0.25 * step_without);
}

TEST(ConcatenateDikeys, ClosestPlacementAtTheLastKeyStillReachesItsPlacement) {
  // 12 → 33 is the last slot: no next onset, so the smoothing aims at the
  // placement's class mean.
  const Dictionary d = FallbackDictionary();
  const auto keys = Keys({{"00", 0.2}, {"12", 0.5}, {"33", 0.8}});
  const HandTrack t = ConcatenateDikeys(d, keys, 1.0);
  ASSERT_EQ(t.keys.size(), 2u);
  EXPECT_EQ(t.keys[1].level, FallbackLevel::kClosestPlacement);
  EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(80), ForearmValue(3)), kTol);
  EXPECT_LT(MaxAbsDiff(t.hand_params.row(80), ShapeValue(3)), kTol);
  EXPECT_LT(MaxAbsDiff(t.forearm_in_head.row(100), ForearmValue(3)), kTol);  // held
  // Without smoothing the unit used arrives at placement 2.
  ConcatOptions raw;
  raw.smoothing = false;
  EXPECT_LT(MaxAbsDiff(ConcatenateDikeys(d, keys, 1.0, raw).forearm_in_head.row(80), ForearmValue(2)), kTol);
}

TEST(ConcatenateDikeys, LevelAboveTheAllowedOneThrows) {
  const Dictionary d = FallbackDictionary();
  ConcatOptions o;
  o.max_fallback_level = 0;
  try {
    ConcatenateDikeys(d, FallbackKeys(), 2.0, o);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("key 3"), HasSubstr("12-33"), HasSubstr("fallback level 0")));
  }
  o.max_fallback_level = 2;
  try {
    ConcatenateDikeys(d, FallbackKeys(), 2.0, o);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("key 5"), HasSubstr("25-48"), HasSubstr("fallback level 2")));
  }
  o.max_fallback_level = 4;
  try {
    ConcatenateDikeys(d, FallbackKeys(), 2.0, o);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("max_fallback_level must be in 0-3"));
  }
}

TEST(ConcatenateDikeys, KeyTheDictionaryNeverHoldsThrows) {
  try {
    ConcatenateDikeys(FallbackDictionary(), Keys({{"00", 0.2}, {"16", 0.5}, {"00", 0.8}}), 1.0);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("16"), HasSubstr("holds no key with shape 6")));
  }
}

template <typename Fn>
std::string ErrorOf(Fn fn) {
  try {
    fn();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no InvalidInput)";
}

TEST(ConcatenateDikeys, BadInputsThrowNamingTheProblem) {
  const Dictionary d = FallbackDictionary();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(ErrorOf([&] { ConcatenateDikeys(Dictionary{}, FallbackKeys(), 2.0); }),
              HasSubstr("the dictionary has no dikey units"));
  EXPECT_THAT(ErrorOf([&] { ConcatenateDikeys(d, Keys({{"00", 0.2}}), 2.0); }), HasSubstr("need at least two keys"));
  EXPECT_THAT(ErrorOf([&] {
                ConcatenateDikeys(d, Keys({{"00", 0.2}, {"12", 0.5}, {"23", 0.5}}), 2.0);
              }),
              AllOf(HasSubstr("key 3"), HasSubstr("is not after the previous")));
  EXPECT_THAT(ErrorOf([&] {
                ConcatenateDikeys(d, Keys({{"00", 0.2}, {"12", 0.1}}), 2.0);
              }),
              AllOf(HasSubstr("key 2"), HasSubstr("is not after the previous")));
  EXPECT_THAT(ErrorOf([&] {
                ConcatenateDikeys(d, Keys({{"00", 0.2}, {"12", nan}}), 2.0);
              }),
              HasSubstr("key 2: time is not finite"));
  EXPECT_THAT(ErrorOf([&] { ConcatenateDikeys(d, Keys({{"00", 0.2}, {"12", 0.5}}), nan); }), HasSubstr("duration"));
  EXPECT_THAT(ErrorOf([&] {
                ConcatenateDikeys(d, Keys({{"00", 0.2}, {"12", 2.5}}), 2.0);
              }),
              AllOf(HasSubstr("key 2"), HasSubstr("outside [0, 2.000] s")));
  ConcatOptions o;
  o.hand_weights = Eigen::Vector2d(1, 1);
  EXPECT_THAT(ErrorOf([&] { ConcatenateDikeys(d, FallbackKeys(), 2.0, o); }),
              HasSubstr("hand_weights has 2 values, the dictionary 3 parameters"));
  o = {};
  o.hand_weights = Eigen::Vector3d(1, nan, 1);
  EXPECT_THAT(ErrorOf([&] { ConcatenateDikeys(d, FallbackKeys(), 2.0, o); }), HasSubstr("hand_weights must be finite"));
  o = {};
  o.rate_hz = 0;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDikeys(d, FallbackKeys(), 2.0, o); }), HasSubstr("rate_hz must be positive"));
  Dictionary bad = d;
  bad.dikeys[2].hand_params(1, 1) = nan;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDikeys(bad, FallbackKeys(), 2.0); }),
              AllOf(HasSubstr("dikey unit 2"), HasSubstr("12-53"), HasSubstr("not finite")));
}

// ---------------------------------------------------------------------------
// Diphones: face parameters (2) per phone, each unit piecewise linear from its
// first phone's value to a known value at the phone boundary to its second's.

Eigen::RowVectorXd PhoneValue(const std::string& p) {
  static const std::map<std::string, std::pair<double, double>> v = {{"_", {0, 0}},  {"a", {1, 2}}, {"b", {3, -1}},
                                                                     {"c", {-2, 4}}, {"d", {5, 5}}, {"e", {-4, -3}}};
  Eigen::RowVectorXd r(2);
  r << v.at(p).first, v.at(p).second;
  return r;
}
Eigen::RowVectorXd BoundaryValue(const std::string& p1, const std::string& p2) {
  Eigen::RowVectorXd off(2);
  off << 1, -1;
  return 0.5 * (PhoneValue(p1) + PhoneValue(p2)) + off;
}

// Phone 1 on [s1, b], phone 2 on [b, e2].
DiphoneUnit Diphone(const std::string& p1, const std::string& p2, double s1, double b, double e2) {
  DiphoneUnit u;
  u.take = "d" + p1 + p2;
  u.phone1 = p1;
  u.phone2 = p2;
  u.phone1_start_s = s1;
  u.phone1_end_s = b;
  u.phone2_start_s = b;
  u.phone2_end_s = e2;
  u.start_s = 0.5 * (s1 + b);
  u.end_s = 0.5 * (b + e2);
  u.rate_hz = kRate;
  u.first_frame = std::llround(u.start_s * kRate);
  const auto n = static_cast<Eigen::Index>(std::llround(u.end_s * kRate)) + 1 - u.first_frame;
  const double rb = (b - u.start_s) / (u.end_s - u.start_s) * static_cast<double>(n - 1);
  u.face_params.resize(n, 2);
  const Eigen::RowVectorXd v1 = PhoneValue(p1), m = BoundaryValue(p1, p2), v2 = PhoneValue(p2);
  for (Eigen::Index r = 0; r < n; ++r) {
    const double x = static_cast<double>(r);
    u.face_params.row(r) =
        x <= rb ? v1 + (x / rb) * (m - v1) : m + ((x - rb) / (static_cast<double>(n - 1) - rb)) * (v2 - m);
  }
  return u;
}

Dictionary DiphoneDictionary() {
  Dictionary d;
  d.face_parameter_names = {"f1", "f2"};
  d.diphones = {Diphone("_", "a", 0.0, 0.2, 0.4), Diphone("a", "b", 1.0, 1.3, 1.4), Diphone("b", "_", 2.0, 2.1, 2.5),
                Diphone("d", "c", 3.0, 3.2, 3.4), Diphone("c", "_", 4.0, 4.2, 4.6), Diphone("c", "e", 5.0, 5.2, 5.4)};
  return d;
}

std::vector<PhoneTarget> Phones(const std::vector<std::pair<std::string, double>>& ends) {
  std::vector<PhoneTarget> phones;
  double start = 0;
  for (const auto& [p, end] : ends) {
    phones.push_back(PhoneTarget{p, start, end});
    start = end;
  }
  return phones;
}

TEST(ConcatenateDiphones, WholeUnitsPhoneBoundariesLandOnTheTargetBoundaries) {
  const Dictionary d = DiphoneDictionary();
  const auto phones = Phones({{"_", 0.2}, {"a", 0.4}, {"b", 0.5}, {"_", 0.9}});
  const FaceTrack t = ConcatenateDiphones(d, phones, 0.9);
  ASSERT_EQ(t.frames(), 91);
  ASSERT_EQ(t.diphones.size(), 3u);
  EXPECT_EQ(t.fallback_per_diphone, (std::vector<int>{0, 0, 0}));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(t.diphones[static_cast<size_t>(i)].level, DiphoneLevel::kWhole);
    EXPECT_EQ(t.diphones[static_cast<size_t>(i)].units, std::vector<int>{i});
  }
  EXPECT_EQ(t.diphones[1].phone1, "a");
  EXPECT_EQ(t.diphones[1].phone2, "b");
  EXPECT_NEAR(t.diphones[1].start_s, 0.30, 1e-12);
  EXPECT_NEAR(t.diphones[1].end_s, 0.45, 1e-12);
  // Middles (frames 10, 30, 45, 70) are the phones' values, boundaries (20,
  // 40, 50) the units' boundary values, although the unit a+b puts its
  // boundary at 75 % and the target at 67 %.
  EXPECT_LT(MaxAbsDiff(t.face_params.row(30), PhoneValue("a")), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(45), PhoneValue("b")), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(70), PhoneValue("_")), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(20), BoundaryValue("_", "a")), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(40), BoundaryValue("a", "b")), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(50), BoundaryValue("b", "_")), kTol);
  // Frame 35: half of a's 10 frames in the slot → half of the unit's 15 rows.
  EXPECT_LT(MaxAbsDiff(t.face_params.row(35), 0.5 * (PhoneValue("a") + BoundaryValue("a", "b"))), kTol);
  // Selection: only slot a+b mismatches (half-phone targets 0.10 and 0.05 s,
  // unit 0.15 and 0.05 s); every join is continuous.
  EXPECT_NEAR(t.total_cost, std::sqrt(0.5 * 0.05 * 0.05), 1e-9);
}

TEST(ConcatenateDiphones, HalfUnitsJoinAtThePhoneBoundary) {
  // a+c is missing: a's second half from a+b, c's first half from d+c.
  const Dictionary d = DiphoneDictionary();
  const auto phones = Phones({{"_", 0.2}, {"a", 0.4}, {"c", 0.6}, {"_", 1.0}});
  const FaceTrack t = ConcatenateDiphones(d, phones, 1.0);
  EXPECT_EQ(t.fallback_per_diphone, (std::vector<int>{0, 1, 0}));
  EXPECT_EQ(t.diphones[1].level, DiphoneLevel::kHalfUnits);
  EXPECT_EQ(t.diphones[1].units, (std::vector<int>{1, 3}));
  EXPECT_EQ(t.diphones[2].units, std::vector<int>{4});
  const Eigen::RowVectorXd ab = BoundaryValue("a", "b"), dc = BoundaryValue("d", "c");
  EXPECT_LT(MaxAbsDiff(t.face_params.row(30), PhoneValue("a")), kTol);
  // The boundary (frame 40) is the right half's boundary value; frame 35,
  // halfway through a's half, is the left unit at half its boundary row plus
  // half the boundary jump.
  EXPECT_LT(MaxAbsDiff(t.face_params.row(40), dc), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(35), PhoneValue("a") + 0.5 * (ab - PhoneValue("a")) + 0.5 * (dc - ab)), kTol);
  // Frame 45, halfway through c's half: halfway from d+c's boundary value to c.
  EXPECT_LT(MaxAbsDiff(t.face_params.row(45), 0.5 * (dc + PhoneValue("c"))), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(50), PhoneValue("c")), kTol);
  // Cost: selection sqrt((0.05² + 0²) / 2) (a's half is 0.15 s in a+b, 0.10
  // s here) + the normalised jump between the two boundary values.
  Eigen::Index rows = 0;
  for (const DiphoneUnit& u : d.diphones) rows += u.frames();
  Eigen::MatrixXd all(rows, 2);
  rows = 0;
  for (const DiphoneUnit& u : d.diphones) {
    all.middleRows(rows, u.frames()) = u.face_params;
    rows += u.frames();
  }
  const Eigen::RowVectorXd sigma = ColumnSigma(all);
  const double join = std::sqrt(0.5 * ((dc - ab).array() / sigma.array()).square().sum());
  EXPECT_NEAR(t.total_cost, std::sqrt(0.5 * 0.05 * 0.05) + join, 1e-9);
  // Without smoothing the left half is the left unit's own: frame 39 is 9/10
  // of the way to a+b's boundary value.
  ConcatOptions raw;
  raw.smoothing = false;
  const FaceTrack r = ConcatenateDiphones(d, phones, 1.0, raw);
  EXPECT_LT(MaxAbsDiff(r.face_params.row(39), PhoneValue("a") + 0.9 * (ab - PhoneValue("a"))), kTol);
}

double MinimumJerkHere(double u) { return 10 * std::pow(u, 3) - 15 * std::pow(u, 4) + 6 * std::pow(u, 5); }

TEST(ConcatenateDiphones, InterpolatesBetweenPhoneMeansWhenNoHalfExists) {
  // e+d: e is never a first phone, so no half unit: minimum-jerk from e's
  // value (end of c+e) to d's (start of d+c).
  const Dictionary d = DiphoneDictionary();
  const auto phones = Phones({{"c", 0.2}, {"e", 0.4}, {"d", 0.6}, {"c", 0.8}});
  const FaceTrack t = ConcatenateDiphones(d, phones, 0.8);
  EXPECT_EQ(t.fallback_per_diphone, (std::vector<int>{0, 2, 0}));
  EXPECT_EQ(t.diphones[1].level, DiphoneLevel::kInterpolated);
  EXPECT_TRUE(t.diphones[1].units.empty());
  const Eigen::RowVectorXd e = PhoneValue("e"), dv = PhoneValue("d");
  EXPECT_LT(MaxAbsDiff(t.face_params.row(30), e), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(35), e + MinimumJerkHere(0.25) * (dv - e)), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(40), 0.5 * (e + dv)), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(50), dv), kTol);
  ConcatOptions o;
  o.max_fallback_level = 1;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, phones, 0.8, o); }),
              AllOf(HasSubstr("phones 2-3"), HasSubstr("e+d"), HasSubstr("fallback level 1")));
}

TEST(ConcatenateDiphones, UnknownPhoneIsTheMeanOfAllPhoneMiddles) {
  const Dictionary d = DiphoneDictionary();
  const auto phones = Phones({{"c", 0.2}, {"z", 0.4}, {"c", 0.6}});
  const FaceTrack t = ConcatenateDiphones(d, phones, 0.6);
  EXPECT_EQ(t.fallback_per_diphone, (std::vector<int>{3, 3}));
  EXPECT_EQ(t.diphones[0].level, DiphoneLevel::kUnknownPhone);
  Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(2);
  for (const DiphoneUnit& u : d.diphones) mean += u.face_params.row(0) + u.face_params.row(u.frames() - 1);
  mean /= 2.0 * static_cast<double>(d.diphones.size());
  EXPECT_LT(MaxAbsDiff(t.face_params.row(30), mean), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(10), PhoneValue("c")), kTol);
  EXPECT_LT(MaxAbsDiff(t.face_params.row(50), PhoneValue("c")), kTol);
  ConcatOptions o;
  o.max_fallback_level = 2;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, phones, 0.6, o); }),
              AllOf(HasSubstr("phone 2 ('z')"), HasSubstr("holds no diphone with it")));
}

TEST(ConcatenateDiphones, BadInputsThrowNamingTheProblem) {
  const Dictionary d = DiphoneDictionary();
  const auto phones = Phones({{"_", 0.2}, {"a", 0.4}, {"b", 0.5}, {"_", 0.8}});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(Dictionary{}, phones, 0.8); }),
              HasSubstr("the dictionary has no diphone units"));
  EXPECT_THAT(ErrorOf([&] {
                ConcatenateDiphones(d, Phones({{"a", 0.2}}), 0.8);
              }),
              HasSubstr("need at least two phones"));
  auto gap = phones;
  gap[2].start_s = 0.42;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, gap, 0.8); }),
              AllOf(HasSubstr("phone 3 ('b')"), HasSubstr("not where the previous ends")));
  auto backwards = phones;
  backwards[1].end_s = 0.1;
  backwards[2].start_s = 0.1;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, backwards, 0.8); }),
              AllOf(HasSubstr("phone 2 ('a')"), HasSubstr("before it starts")));
  auto not_finite = phones;
  not_finite[3].end_s = nan;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, not_finite, 0.8); }),
              AllOf(HasSubstr("phone 4"), HasSubstr("not finite")));
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, phones, 0.5); }), HasSubstr("outside [0, 0.500] s"));
  ConcatOptions o;
  o.face_weights = Eigen::VectorXd::Ones(5);
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, phones, 0.8, o); }),
              HasSubstr("face_weights has 5 values, the dictionary 2 parameters"));
  o = {};
  o.max_fallback_level = -1;
  EXPECT_THAT(ErrorOf([&] { ConcatenateDiphones(d, phones, 0.8, o); }), HasSubstr("max_fallback_level must be in 0-3"));
}

TEST(MinimumJerk, KnownValues) {
  EXPECT_DOUBLE_EQ(MinimumJerk(0), 0);
  EXPECT_DOUBLE_EQ(MinimumJerk(1), 1);
  EXPECT_DOUBLE_EQ(MinimumJerk(0.5), 0.5);
  EXPECT_NEAR(MinimumJerk(0.25), 0.103515625, 1e-15);
  EXPECT_DOUBLE_EQ(MinimumJerk(-1), 0);
  EXPECT_DOUBLE_EQ(MinimumJerk(2), 1);
}

}  // namespace
}  // namespace csw::dict

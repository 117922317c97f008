// synth/dictionary.h on hand-built series: which units are cut and where, the
// forearm pose relative to the head (invariant to head motion), the unsolved-
// frame rule, phasing, coverage and the models' fingerprint.
#include "synth/dictionary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "models/rigid_motion.h"

namespace csw::dict {
namespace {

using Pose = Eigen::Matrix<double, 6, 1>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

KeyMark Mark(double t, int p, int s) { return {t, KeyCode{p, s}}; }

// 100 frames at 100 Hz; hand parameter 0 = the frame number, 1 = −frame.
TakeSeries Series() {
  TakeSeries s;
  s.take = "t";
  s.rate_hz = 100;
  const int n = 100;
  s.hand_params.resize(n, 2);
  s.forearm_pose.resize(n, 6);
  s.head_pose.resize(n, 6);
  for (int f = 0; f < n; ++f) {
    s.hand_params.row(f) << f, -f;
    // The head turns and moves; the forearm keeps one pose in the head frame.
    Pose head;
    head << 0.01 * f, -0.005 * f, 0.002 * f, 1.0 * f, 2.0, -0.5 * f;
    Pose rel;
    rel << 0.3, -0.2, 0.1, 50, -80, 120;
    const RigidTransform h = RigidTransform::FromParameters(head), r = RigidTransform::FromParameters(rel);
    RigidTransform fa;
    fa.rotation = h.rotation * r.rotation;
    fa.translation = h.rotation * r.translation + h.translation;
    s.head_pose.row(f) = head.transpose();
    s.forearm_pose.row(f) = fa.Parameters().transpose();
  }
  s.keys = {Mark(0.10, 2, 5), Mark(0.30, 3, 1), Mark(0.55, 2, 5)};
  return s;
}

TEST(Dikeys, CutsEverySuccessionWithRestsAtTheEnds) {
  ExtractionStats stats;
  const std::vector<DikeyUnit> u = ExtractDikeys(Series(), {}, &stats);
  // 00 (added, t = 0) → 25 → 31 → 25 → 00 (added, last frame 0.99 s).
  ASSERT_EQ(u.size(), 4u);
  EXPECT_EQ(stats.successions, 4);
  EXPECT_EQ(stats.kept, 4);
  const std::vector<std::string> codes = {"00-25", "25-31", "31-25", "25-00"};
  const std::vector<int64_t> first = {0, 10, 30, 55}, frames = {11, 21, 26, 45};
  for (size_t i = 0; i < u.size(); ++i) {
    EXPECT_EQ(SuccessionCode(u[i].from, u[i].to), codes[i]);
    EXPECT_EQ(u[i].index, static_cast<int>(i));
    EXPECT_EQ(u[i].first_frame, first[i]);
    EXPECT_EQ(u[i].frames(), frames[i]);
    // Hand parameters are the take's rows.
    EXPECT_DOUBLE_EQ(u[i].hand_params(0, 0), static_cast<double>(first[i]));
    EXPECT_DOUBLE_EQ(u[i].hand_params(u[i].frames() - 1, 1), -static_cast<double>(first[i] + frames[i] - 1));
    EXPECT_TRUE(std::isnan(u[i].phasing_s));  // no syllable onsets given
  }
  EXPECT_DOUBLE_EQ(u[1].start_s, 0.10);
  EXPECT_DOUBLE_EQ(u[1].end_s, 0.30);
  EXPECT_NEAR(u[1].duration_s(), 0.20, 1e-12);
  EXPECT_DOUBLE_EQ(u[3].end_s, 0.99);
}

TEST(Dikeys, ForearmRelativeToTheHeadIgnoresHeadMotion) {
  const std::vector<DikeyUnit> u = ExtractDikeys(Series());
  Pose rel;
  rel << 0.3, -0.2, 0.1, 50, -80, 120;
  for (const DikeyUnit& d : u) {
    for (int64_t r = 0; r < d.frames(); ++r) {
      for (int k = 0; k < 6; ++k) EXPECT_NEAR(d.forearm_in_head(r, k), rel[k], 1e-9) << r << " " << k;
    }
  }
}

TEST(Dikeys, RelativePoseOfIdentityAndNaN) {
  Pose zero = Pose::Zero(), b;
  b << 0.1, 0.2, -0.3, 4, 5, 6;
  const Pose r = RelativePose(zero, b);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(r[k], b[k], 1e-12);
  // A pure translation of the head: the relative translation is the difference.
  Pose a = Pose::Zero();
  a << 0, 0, 0, 10, 20, 30;
  const Pose r2 = RelativePose(a, b);
  EXPECT_NEAR(r2[3], -6, 1e-12);
  EXPECT_NEAR(r2[4], -15, 1e-12);
  EXPECT_NEAR(r2[5], -24, 1e-12);
  a[0] = kNaN;
  EXPECT_TRUE(std::isnan(RelativePose(a, b)[0]));
}

TEST(Dikeys, UnitsWithUnsolvedFramesAreLeftOut) {
  TakeSeries s = Series();
  s.hand_params(20, 0) = kNaN;  // inside 25 → 31 (frames 10-30)
  ExtractionStats stats;
  std::vector<DikeyUnit> u = ExtractDikeys(s, {}, &stats);
  ASSERT_EQ(u.size(), 3u);
  EXPECT_EQ(stats.rejected_unsolved, 1);
  EXPECT_EQ(SuccessionCode(u[1].from, u[1].to), "31-25");
  // 1 unsolved frame of 21 is within a 10 % allowance.
  DikeyOptions o;
  o.max_unsolved_fraction = 0.1;
  EXPECT_EQ(ExtractDikeys(s, o).size(), 4u);
  // A head pose unsolved at a unit's boundary frame (30, shared by two units).
  s = Series();
  s.head_pose(30, 3) = kNaN;
  EXPECT_EQ(ExtractDikeys(s, {}, &stats).size(), 2u);
}

TEST(Dikeys, NoRestsAddedWhenTheTierHasThemOrWhenAsked) {
  TakeSeries s = Series();
  s.keys = {Mark(0.05, 0, 0), Mark(0.30, 3, 1), Mark(0.90, 0, 0)};
  const std::vector<DikeyUnit> u = ExtractDikeys(s);
  ASSERT_EQ(u.size(), 2u);
  EXPECT_EQ(SuccessionCode(u[0].from, u[0].to), "00-31");
  EXPECT_EQ(u[0].first_frame, 5);
  DikeyOptions o;
  o.add_rests = false;
  s = Series();
  EXPECT_EQ(ExtractDikeys(s, o).size(), 2u);
}

TEST(Dikeys, PhasingIsTheTargetMinusTheSyllableOnset) {
  TakeSeries s = Series();
  s.syllable_onset_s = {0.15, 0.28, 0.60};
  const std::vector<DikeyUnit> u = ExtractDikeys(s);
  ASSERT_EQ(u.size(), 4u);
  EXPECT_NEAR(u[0].phasing_s, 0.10 - 0.15, 1e-12);
  EXPECT_NEAR(u[1].phasing_s, 0.30 - 0.28, 1e-12);
  EXPECT_NEAR(u[2].phasing_s, 0.55 - 0.60, 1e-12);
  EXPECT_TRUE(std::isnan(u[3].phasing_s));  // to rest
}

TEST(Dikeys, EachUnitKeepsTheTypeOfTheKeyItReaches) {
  // Three marks (rests added at 0 and at the end): CV, lone V, lone C.
  TakeSeries s = Series();
  s.syllable_onset_s = {0.15, 0.28, 0.60};
  s.key_type = {KeyType::kCV, KeyType::kVowelAlone, KeyType::kConsonantAlone};
  const std::vector<DikeyUnit> u = ExtractDikeys(s);
  ASSERT_EQ(u.size(), 4u);
  ASSERT_TRUE(u[0].to_type && u[1].to_type && u[2].to_type && u[3].to_type);
  EXPECT_EQ(*u[0].to_type, KeyType::kCV);
  EXPECT_EQ(*u[1].to_type, KeyType::kVowelAlone);
  EXPECT_EQ(*u[2].to_type, KeyType::kConsonantAlone);
  EXPECT_EQ(*u[3].to_type, KeyType::kRest);  // the added rest
  // Unknown types: none but the rests'.
  s.key_type.clear();
  const std::vector<DikeyUnit> v = ExtractDikeys(s);
  ASSERT_EQ(v.size(), 4u);
  EXPECT_FALSE(v[0].to_type.has_value());
  EXPECT_FALSE(v[2].to_type.has_value());
  ASSERT_TRUE(v[3].to_type.has_value());
  EXPECT_EQ(*v[3].to_type, KeyType::kRest);
  s.key_type = {KeyType::kCV};  // one type for three marks
  EXPECT_THROW(ExtractDikeys(s), InvalidInput);
}

TEST(Dikeys, PlacementLagsAreThePlacementTargetsMinusTheShapeTargets) {
  // Marks at 0.10, 0.30, 0.55 (rests added at 0 and at the end): the
  // placements arrive 30 ms after, 20 ms before, unknown.
  TakeSeries s = Series();
  s.placement_target_s = {0.13, 0.28, std::numeric_limits<double>::quiet_NaN()};
  const std::vector<DikeyUnit> u = ExtractDikeys(s);
  ASSERT_EQ(u.size(), 4u);
  EXPECT_TRUE(std::isnan(u[0].from_placement_lag_s));  // the added rest
  EXPECT_NEAR(u[0].to_placement_lag_s, 0.03, 1e-12);
  EXPECT_NEAR(u[1].from_placement_lag_s, 0.03, 1e-12);
  EXPECT_NEAR(u[1].to_placement_lag_s, -0.02, 1e-12);
  EXPECT_NEAR(u[2].from_placement_lag_s, -0.02, 1e-12);
  EXPECT_TRUE(std::isnan(u[2].to_placement_lag_s));
  EXPECT_TRUE(std::isnan(u[3].from_placement_lag_s));
  EXPECT_TRUE(std::isnan(u[3].to_placement_lag_s));
  s.placement_target_s = {0.13};
  EXPECT_THROW(ExtractDikeys(s), InvalidInput);
}

TEST(Dikeys, BadSeriesGiveOneClearError) {
  TakeSeries s = Series();
  s.head_pose.conservativeResize(50, 6);
  try {
    ExtractDikeys(s);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()),
              "take 't': per-frame series disagree (hand parameters 100 frames, forearm pose 100×6, head pose 50×6; "
              "poses need 6 columns)");
  }
  s = Series();
  s.syllable_onset_s = {0.1};
  EXPECT_THROW(ExtractDikeys(s), InvalidInput);
  s = Series();
  s.rate_hz = 0;
  EXPECT_THROW(ExtractDikeys(s), InvalidInput);
}

TEST(Diphones, MiddleToMiddleWithFaceParameters) {
  TakeSeries s = Series();
  s.face_params.resize(100, 1);
  for (int f = 0; f < 100; ++f) s.face_params(f, 0) = 2.0 * f;
  s.phones = {{0.0, 0.2, "_"}, {0.2, 0.3, "p"}, {0.3, 0.5, "a"}, {0.5, 0.99, "_"}};
  s.audio_path = "t.wav";
  ExtractionStats stats;
  const std::vector<DiphoneUnit> u = ExtractDiphones(s, {}, &stats);
  ASSERT_EQ(u.size(), 3u);
  EXPECT_EQ(stats.kept, 3);
  // _+p: 0.10 → 0.25 s, frames 10..25 (llround(25.0) = 25).
  EXPECT_EQ(u[0].phone1, "_");
  EXPECT_EQ(u[0].phone2, "p");
  EXPECT_DOUBLE_EQ(u[0].start_s, 0.10);
  EXPECT_DOUBLE_EQ(u[0].end_s, 0.25);
  EXPECT_EQ(u[0].first_frame, 10);
  EXPECT_EQ(u[0].frames(), 16);
  EXPECT_DOUBLE_EQ(u[0].face_params(0, 0), 20.0);
  EXPECT_EQ(u[1].phone1 + "+" + u[1].phone2, "p+a");
  EXPECT_DOUBLE_EQ(u[1].phone1_start_s, 0.2);
  EXPECT_DOUBLE_EQ(u[1].phone2_end_s, 0.5);
  EXPECT_EQ(u[1].first_frame, 25);
  EXPECT_EQ(u[1].frames(), 16);  // 0.25 → 0.40
  EXPECT_EQ(u[2].audio_path, "t.wav");
  const std::vector<std::pair<std::string, int>> want = {{"_+p", 1}, {"a+_", 1}, {"p+a", 1}};
  EXPECT_EQ(DiphoneCoverage(u), want);
  // An unsolved face frame inside p+a leaves it out.
  s.face_params(30, 0) = kNaN;
  EXPECT_EQ(ExtractDiphones(s, {}, &stats).size(), 2u);
  // Overlapping phones are an error naming the take and the phone.
  s.phones[2].start_s = 0.25;
  try {
    ExtractDiphones(s);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()),
              "take 't': phone 3 ('a') overlaps the previous one, is out of order or has a bad time");
  }
}

TEST(Coverage, CountsSuccessionsOfPlacementsShapesAndKeys) {
  const std::vector<DikeyUnit> u = ExtractDikeys(Series());
  const Coverage c = CoverageOfUnits(u);
  EXPECT_EQ(c.units, 4);
  // Placements 0→2, 2→3, 3→2, 2→0; shapes 0→5, 5→1, 1→5, 5→0.
  EXPECT_EQ(c.placement.sum(), 4);
  EXPECT_EQ(c.placement(0, 2), 1);
  EXPECT_EQ(c.placement(2, 3), 1);
  EXPECT_EQ(c.placement(3, 2), 1);
  EXPECT_EQ(c.placement(2, 0), 1);
  EXPECT_EQ(c.shape(5, 1), 1);
  EXPECT_EQ(c.shape(1, 5), 1);
  // 35 possible placement successions (6 × 6 but 0 → 0), 4 present.
  EXPECT_EQ(c.MissingPlacements().size(), 31u);
  EXPECT_EQ(c.MissingShapes().size(), 80u - 4u);
  const std::vector<std::pair<std::string, int>> want = {{"00-25", 1}, {"25-00", 1}, {"25-31", 1}, {"31-25", 1}};
  EXPECT_EQ(c.dikeys, want);
  // The key lists give the same coverage.
  const Coverage k = CoverageOfKeys({Series().keys, Series().keys}, {0.99, 0.99});
  EXPECT_EQ(k.units, 8);
  EXPECT_EQ(k.placement(2, 3), 2);
  EXPECT_EQ(k.dikeys[0], (std::pair<std::string, int>{"00-25", 2}));
}

TEST(Fingerprint, FollowsTheParametersNotTheObject) {
  FaceModel face;
  face.head.reference = Eigen::Matrix3Xd::Random(3, 4);
  face.shape.mean = Eigen::VectorXd::Random(9);
  face.shape.loadings = Eigen::MatrixXd::Random(9, 2);
  HandModel hand;
  hand.forearm.reference = Eigen::Matrix3Xd::Random(3, 3);
  hand.param_scale = Eigen::VectorXd::Ones(2);
  const std::string a = ModelsFingerprint(&face, &hand);
  EXPECT_EQ(a.size(), 64u);
  FaceModel copy = face;
  copy.info.corpus = "elsewhere.h5";  // provenance does not count
  EXPECT_EQ(ModelsFingerprint(&copy, &hand), a);
  copy.shape.loadings(3, 1) += 1e-9;
  EXPECT_NE(ModelsFingerprint(&copy, &hand), a);
  EXPECT_NE(ModelsFingerprint(&face, nullptr), a);
  // SHA-256 of nothing (no model): the well-known empty digest.
  EXPECT_EQ(ModelsFingerprint(nullptr, nullptr), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");

  Dictionary d;
  d.models_fingerprint = a;
  EXPECT_NO_THROW(CheckModelsMatch(d, a, "d.h5"));
  try {
    CheckModelsMatch(d, ModelsFingerprint(&copy, &hand), "d.h5");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("d.h5: the dictionary was built with models " + a.substr(0, 16)),
              std::string::npos)
        << e.what();
  }
}

TEST(Continuity, MarkerJumpsAndQuantilesByHand) {
  // Two markers over three frames: marker 0 moves 3-4-5 (5 mm) then 1 mm;
  // marker 1 is hidden in frame 1, so it contributes no jump.
  MarkerArray m(3, 2);
  auto set = [&](int64_t f, int64_t k, float x, float y, float z) {
    float* p = m.at(f, k);
    p[0] = x;
    p[1] = y;
    p[2] = z;
  };
  set(0, 0, 0, 0, 0);
  set(1, 0, 3, 4, 0);
  set(2, 0, 3, 4, 1);
  set(0, 1, 9, 9, 9);
  set(2, 1, 0, 0, 0);
  std::vector<double> jumps;
  dict::AppendMarkerJumps(m, &jumps);
  ASSERT_EQ(jumps.size(), 2u);
  EXPECT_NEAR(jumps[0], 5.0, 1e-6);
  EXPECT_NEAR(jumps[1], 1.0, 1e-6);
  std::vector<double> v = {4, 1, 3, 2, 5};  // sorted 1..5: q 0.5 = 3, q 0.99 = 4 + 0.96 = 4.96
  EXPECT_DOUBLE_EQ(dict::Quantile(v, 0.5), 3.0);
  EXPECT_NEAR(dict::Quantile(v, 0.99), 4.96, 1e-12);
  EXPECT_DOUBLE_EQ(dict::Quantile(v, 1.0), 5.0);
  std::vector<double> none;
  EXPECT_TRUE(std::isnan(dict::Quantile(none, 0.5)));
}

}  // namespace
}  // namespace csw::dict

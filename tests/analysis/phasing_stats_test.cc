// Posterior landmarks and phasing statistics (analysis/phasing/) on constructed
// posteriors and hand-computed values.
#include "analysis/phasing/phasing_stats.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "analysis/phasing/posterior_landmarks.h"
#include "core/error.h"

namespace csw::phasing {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Three classes over 21 frames at 100 Hz from t = 1 s: class 0 falls linearly
// from 1 (frame 0) to 0 (frame 10); class 1 rises from 0 (frame 0) to 1 (frame
// 10), stays 1 until frame 14, falls to 0.5 at frame 20; class 2 takes the rest.
Eigen::MatrixXd Constructed() {
  Eigen::MatrixXd p(21, 3);
  for (int f = 0; f < 21; ++f) {
    const double c0 = std::max(0.0, 1.0 - f / 10.0);
    const double c1 = f <= 10 ? f / 10.0 : (f <= 14 ? 1.0 : 1.0 - (f - 14) / 12.0);
    p(f, 0) = c0;
    p(f, 1) = c1;
    p(f, 2) = std::max(0.0, 1.0 - c0 - c1);
  }
  return p;
}

TEST(PhasingPosterior, OnsetWhenDominantTargetAtPlateauCentre) {
  const Eigen::MatrixXd p = Constructed();
  // Class 1 exceeds class 0 when f/10 > 1 - f/10: f > 5 exactly at 5 (tie) -> crossing at frame 5.
  const PosteriorLandmarks l = FindPosteriorLandmarks(p, 100.0, 1.0, 1, 1.0, 1.2);
  ASSERT_TRUE(l.found) << l.reason;
  EXPECT_NEAR(l.onset_s, 1.0 + 5.0 / 100.0, 1e-12);
  // Plateau of 1.0 over frames 10-14: centre frame 12.
  EXPECT_NEAR(l.target_s, 1.0 + 12.0 / 100.0, 1e-12);
  EXPECT_DOUBLE_EQ(l.peak, 1.0);
  EXPECT_FALSE(l.onset_at_window_start);
  // Frame 13 at 0.995: still on the plateau within 0.01; with tolerance 0 the
  // plateau is frames 10-12 (exactly 1), centre 11.
  Eigen::MatrixXd q = p;
  q(13, 1) = 0.995;
  q(13, 2) = 0.005;
  EXPECT_NEAR(FindPosteriorLandmarks(q, 100.0, 1.0, 1, 1.0, 1.2).target_s, 1.12, 1e-12);
  PosteriorLandmarkOptions o;
  o.plateau_tolerance = 0.0;
  EXPECT_NEAR(FindPosteriorLandmarks(q, 100.0, 1.0, 1, 1.0, 1.2, o).target_s, 1.11, 1e-12);
}

TEST(PhasingPosterior, SubFrameCrossing) {
  // Two classes: margin -0.3 at frame 4, +0.1 at frame 5 -> crossing at 4.75.
  Eigen::MatrixXd p(8, 2);
  const double c1[8] = {0.1, 0.1, 0.2, 0.3, 0.35, 0.55, 0.9, 0.8};
  for (int f = 0; f < 8; ++f) {
    p(f, 0) = 1.0 - c1[f];
    p(f, 1) = c1[f];
  }
  const PosteriorLandmarks l = FindPosteriorLandmarks(p, 120.0, 0.0, 1, 0.0, 1.0);
  ASSERT_TRUE(l.found);
  EXPECT_NEAR(l.onset_s, 4.75 / 120.0, 1e-12);
  EXPECT_NEAR(l.target_s, 6.0 / 120.0, 1e-12);
}

TEST(PhasingPosterior, NeverDominantAndWindowEdgeAndBadInput) {
  const Eigen::MatrixXd p = Constructed();
  // Class 2 peaks at 0.5 at frame 20 (a tie with class 1): it never dominates.
  const PosteriorLandmarks l2 = FindPosteriorLandmarks(p, 100.0, 1.0, 2, 1.0, 1.2);
  EXPECT_FALSE(l2.found);
  EXPECT_EQ(l2.reason, "the class never dominates in the window");
  // Window starting at frame 8: class 1 dominates from the first frame.
  const PosteriorLandmarks l1 = FindPosteriorLandmarks(p, 100.0, 1.0, 1, 1.08, 1.2);
  EXPECT_TRUE(l1.found);
  EXPECT_TRUE(l1.onset_at_window_start);
  EXPECT_NEAR(l1.onset_s, 1.08, 1e-12);
  // Unscored rows (NaN) are skipped; a window of NaN rows finds nothing.
  Eigen::MatrixXd q = p;
  q.middleRows(0, 21).setConstant(kNaN);
  EXPECT_EQ(FindPosteriorLandmarks(q, 100.0, 1.0, 1, 1.0, 1.2).reason, "no scored frame in the window");
  EXPECT_THROW(FindPosteriorLandmarks(p, 100.0, 1.0, 3, 1.0, 1.2), InvalidInput);
  EXPECT_THROW(FindPosteriorLandmarks(p, 100.0, 1.0, 1, 1.2, 1.0), InvalidInput);
}

TEST(PhasingStats, StudentTQuantilesMatchTables) {
  // Two-sided 95 %: t(0.975) for 1, 2, 5, 10, 30 degrees of freedom (standard tables).
  EXPECT_NEAR(StudentTTwoSided(0.95, 1), 12.7062, 1e-4);
  EXPECT_NEAR(StudentTTwoSided(0.95, 2), 4.3027, 1e-4);
  EXPECT_NEAR(StudentTTwoSided(0.95, 5), 2.5706, 1e-4);
  EXPECT_NEAR(StudentTTwoSided(0.95, 10), 2.2281, 1e-4);
  EXPECT_NEAR(StudentTTwoSided(0.95, 30), 2.0423, 1e-4);
  EXPECT_NEAR(StudentTTwoSided(0.99, 3), 5.8409, 1e-4);
  EXPECT_THROW(StudentTTwoSided(0.95, 0), InvalidInput);
}

TEST(PhasingStats, SummaryAndHistogram) {
  // 10, 20, 30, 40 (+ NaN left out): mean 25, sd sqrt(500/3), CI t(3) sd / 2.
  const TimeSummary s = SummariseTimes({10, 20, kNaN, 30, 40});
  EXPECT_EQ(s.count, 4);
  EXPECT_DOUBLE_EQ(s.mean_ms, 25.0);
  EXPECT_NEAR(s.sd_ms, std::sqrt(500.0 / 3.0), 1e-12);
  EXPECT_NEAR(s.ci95_ms, 3.1824 * std::sqrt(500.0 / 3.0) / 2.0, 1e-3);
  EXPECT_EQ(SummariseTimes({}).count, 0);
  EXPECT_EQ(SummariseTimes({5}).ci95_ms, 0.0);
  const Histogram h = MakeHistogram({-250, -100, -99.9, -80, 0, 19.9, 400, kNaN}, -200, 20, 12);
  EXPECT_EQ(h.below, 1);
  EXPECT_EQ(h.above, 1);
  EXPECT_EQ(h.counts[5], 2);   // [-100, -80)
  EXPECT_EQ(h.counts[6], 1);   // [-80, -60)
  EXPECT_EQ(h.counts[10], 2);  // [0, 20)
}

TEST(PhasingStats, RowsSummaryJsonAndCsv) {
  std::vector<Phone> phones(4);
  phones[0].start_s = 1.0;  // consonant
  phones[1].start_s = 1.1;  // vowel
  phones[2].start_s = 1.4;  // lone vowel
  Key cv;
  cv.type = KeyType::kCV;
  cv.consonant_phone = 0;
  cv.vowel_phone = 1;
  cv.a1_s = 1.0;
  Key v;
  v.type = KeyType::kVowelAlone;
  v.vowel_phone = 2;
  v.a1_s = 1.4;
  Key c;
  c.type = KeyType::kConsonantAlone;
  c.consonant_phone = 3;
  EXPECT_DOUBLE_EQ(VowelOnset(cv, phones), 1.1);
  EXPECT_DOUBLE_EQ(VowelOnset(v, phones), 1.4);
  EXPECT_TRUE(std::isnan(VowelOnset(c, phones)));

  std::vector<PhasingKeyRow> rows(3);
  rows[0].take = "t1";
  rows[0].code = "25";
  rows[0].type = KeyType::kCV;
  rows[0].a1_s = 1.0;
  rows[0].vowel_onset_s = 1.1;
  rows[0].kinematic = {0.75, 1.04, 0.83, kNaN};  // shape target left out
  rows[1] = rows[0];
  rows[1].key_index = 1;
  rows[1].kinematic = {0.77, 1.02, 0.81, 0.99};
  rows[2].take = "t1";
  rows[2].key_index = 2;
  rows[2].code = "35";
  rows[2].type = KeyType::kVowelAlone;
  rows[2].a1_s = 1.4;
  rows[2].vowel_onset_s = 1.4;
  rows[2].kinematic = {1.2, 1.5, 1.2, 1.5};
  const PhasingSummary a1 = SummarisePhasing(rows, PhasingMethod::kKinematic, PhasingReference::kA1);
  EXPECT_EQ(a1.cv.placement_onset.count, 2);
  EXPECT_NEAR(a1.cv.placement_onset.mean_ms, -240.0, 1e-9);
  EXPECT_NEAR(a1.cv.placement_onset.sd_ms, std::sqrt(200.0), 1e-9);
  EXPECT_NEAR(a1.cv.placement_onset.ci95_ms, 12.7062 * std::sqrt(200.0) / std::sqrt(2.0), 1e-3);
  EXPECT_EQ(a1.cv.shape_target.count, 1);
  EXPECT_NEAR(a1.cv.shape_target.mean_ms, -10.0, 1e-9);
  EXPECT_EQ(a1.v.placement_target.count, 1);
  EXPECT_NEAR(a1.v.placement_target.mean_ms, 100.0, 1e-9);
  EXPECT_EQ(a1.c.placement_onset.count, 0);
  const PhasingSummary vo = SummarisePhasing(rows, PhasingMethod::kKinematic, PhasingReference::kVowelOnset);
  EXPECT_NEAR(vo.cv.placement_onset.mean_ms, -340.0, 1e-9);
  EXPECT_NEAR(vo.v.placement_onset.mean_ms, -200.0, 1e-9);
  EXPECT_EQ(SummarisePhasing(rows, PhasingMethod::kPosterior, PhasingReference::kA1).cv.placement_onset.count, 0);

  const nlohmann::json j = PhasingSummaryToJson(a1);
  EXPECT_EQ(j["CV"]["placement"]["onset"]["count"], 2);
  EXPECT_NEAR(j["CV"]["placement"]["onset"]["mean_ms"].get<double>(), -240.0, 1e-9);
  EXPECT_TRUE(j["V"]["shape"]["target"].contains("ci95_ms"));
  EXPECT_EQ(j["C"]["shape"]["onset"]["count"], 0);

  const std::string header = PhasingCsvHeader();
  EXPECT_EQ(header.rfind("take,key,code,type,a1_s,vowel_onset_s,kinematic_placement_onset_s,", 0), 0u);
  const std::string row = PhasingCsvRow(rows[0]);
  EXPECT_EQ(row.rfind("t1,0,25,CV,1.0000,1.1000,0.7500,1.0400,0.8300,,", 0), 0u) << row;
  // Same number of fields as the header.
  EXPECT_EQ(std::count(row.begin(), row.end(), ','), std::count(header.begin(), header.end(), ','));
  EXPECT_NE(row.find(",-250.0,40.0,-170.0,"), std::string::npos) << row;
}

}  // namespace
}  // namespace csw::phasing

#include "analysis/cleaning/rigid_fill.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>

#include "core/error.h"
#include "core/markerset.h"
#include "tests/analysis/structfill_eval.h"

namespace csw::cleaning {
namespace {

// A rigid body: marker positions in its own frame (mm), kept near the origin so float32 storage
// rounds below 2e-5 mm.
Eigen::Matrix3Xd Body() {
  Eigen::Matrix3Xd b(3, 6);
  b << 0, 60, -40, 10, 30, -20,  //
      0, 10, 25, -50, 45, -30,   //
      0, 5, -10, 20, 35, 40;
  return b;
}

// The body's pose at frame f: rotations up to ~1 rad about a turning axis, translations of
// ±150 mm.
Eigen::Isometry3d Pose(int64_t f) {
  const double t = static_cast<double>(f) / 100.0;
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d axis = Eigen::Vector3d(std::sin(t), std::cos(0.7 * t), 0.5).normalized();
  x.linear() = Eigen::AngleAxisd(1.0 * std::sin(1.3 * t), axis).toRotationMatrix();
  x.translation() = Eigen::Vector3d(150 * std::sin(0.9 * t), 100 * std::cos(1.1 * t), 50 * std::sin(2.1 * t));
  return x;
}

MarkerArray RigidTake(const Eigen::Matrix3Xd& body, int64_t frames, MarkerArray* truth) {
  MarkerArray m(frames, body.cols());
  for (int64_t f = 0; f < frames; ++f)
    for (Eigen::Index j = 0; j < body.cols(); ++j) {
      const Eigen::Vector3d p = Pose(f) * Eigen::Vector3d(body.col(j));
      for (int c = 0; c < 3; ++c) m.at(f, j)[c] = static_cast<float>(p[c]);
    }
  *truth = m;
  return m;
}

double Distance(const MarkerArray& a, const MarkerArray& b, int64_t f, int j) {
  double s = 0;
  for (int c = 0; c < 3; ++c) s += std::pow(double(a.at(f, j)[c]) - double(b.at(f, j)[c]), 2);
  return std::sqrt(s);
}

const std::vector<int> kAll = {0, 1, 2, 3, 4, 5};

TEST(RigidFill, ReproducesHiddenMarkerOfNoiseFreeRigidBody) {
  MarkerArray truth;
  MarkerArray in = RigidTake(Body(), 400, &truth);
  // Marker 0 hidden over frames 100-159; neighbours 1 and 2 also hidden over parts of the gap
  // (4 then 3 neighbours left), and scattered dropouts of the others outside the gap.
  for (int64_t f = 100; f < 160; ++f) in.SetMissing(f, 0);
  for (int64_t f = 110; f < 130; ++f) in.SetMissing(f, 1);
  for (int64_t f = 120; f < 150; ++f) in.SetMissing(f, 2);
  for (int64_t f = 0; f < 400; f += 7)
    if (f < 100 || f >= 160) in.SetMissing(f, 3 + static_cast<int>(f % 3));
  ClusterReference ref = EstimateClusterReference(in, kAll);
  ASSERT_EQ(ref.problem, "");
  EXPECT_EQ(ref.min_visible_used, 6);
  EXPECT_LT(ref.median_residual_mm, 1e-4);
  EXPECT_LT(ref.iterations, RigidFillOptions().max_iterations);  // converged (to 1e-4 mm)
  // The reference is the body up to a rigid motion: same inter-marker distances.
  for (int i = 0; i < 6; ++i)
    for (int j = i + 1; j < 6; ++j)
      EXPECT_NEAR((ref.shape.col(i) - ref.shape.col(j)).norm(), (Body().col(i) - Body().col(j)).norm(), 1e-4);

  MarkerArray out = in;
  RigidGapFit fit;
  ASSERT_EQ(RigidFillGap(in, ref, {0, 100, 60}, &out, {}, &fit), "");
  EXPECT_EQ(fit.min_visible, 3);
  EXPECT_LT(fit.max_residual_mm, 1e-4);
  double worst = 0;
  for (int64_t f = 100; f < 160; ++f) worst = std::max(worst, Distance(out, truth, f, 0));
  EXPECT_LT(worst, 1e-4);
  // Only the gap frames of the gap's marker are written.
  EXPECT_FALSE(out.Visible(99, 1) != in.Visible(99, 1));
  EXPECT_FALSE(out.Visible(115, 1));
}

TEST(RigidFill, RefusesWithTwoVisibleNeighbours) {
  MarkerArray truth;
  MarkerArray in = RigidTake(Body(), 200, &truth);
  for (int64_t f = 50; f < 70; ++f) in.SetMissing(f, 0);
  for (int j = 3; j < 6; ++j) in.SetMissing(60, j);  // frame 60: only markers 1 and 2 left
  RigidClusterFiller filler = RigidClusterFiller::FromMarkers(in, {kAll});
  std::string why;
  EXPECT_FALSE(filler.CanFill(in, {0, 50, 20}, &why));
  EXPECT_NE(why.find("frame 60: 2 visible cluster neighbours, 3 needed"), std::string::npos) << why;
  MarkerArray out = in;
  FillRecord rec{};
  EXPECT_FALSE(filler.Fill(in, {0, 50, 20}, &out, &rec));
  EXPECT_FALSE(out.Visible(55, 0));  // untouched
  // The same gap without frame 60 fills.
  EXPECT_TRUE(filler.CanFill(in, {0, 50, 10}, &why)) << why;
}

TEST(RigidFill, RefusesCollinearNeighbours) {
  // Markers 1-3 on one line, marker 0 and 4 off it.
  Eigen::Matrix3Xd body(3, 5);
  body << 20, -50, 0, 50, 10,  //
      40, 0, 0, 0, -30,        //
      10, 0, 0, 0, 25;
  MarkerArray truth, in;
  {
    MarkerArray m(120, 5);
    for (int64_t f = 0; f < 120; ++f)
      for (int j = 0; j < 5; ++j) {
        const Eigen::Vector3d p = Pose(f) * Eigen::Vector3d(body.col(j));
        for (int c = 0; c < 3; ++c) m.at(f, j)[c] = static_cast<float>(p[c]);
      }
    in = m;
  }
  for (int64_t f = 40; f < 60; ++f) in.SetMissing(f, 0);
  for (int64_t f = 45; f < 50; ++f) in.SetMissing(f, 4);
  ClusterReference ref = EstimateClusterReference(in, {0, 1, 2, 3, 4});
  ASSERT_EQ(ref.problem, "");
  RigidGapFit fit = FitRigidGap(in, ref, {0, 40, 20});
  EXPECT_NE(fit.why_not.find("frame 45: the 3 visible cluster neighbours are collinear"), std::string::npos)
      << fit.why_not;
  EXPECT_TRUE(fit.positions.empty());
  // With marker 4 seen, the gap fills exactly (4 neighbours, not collinear).
  MarkerArray in2 = in;
  for (int64_t f = 45; f < 50; ++f)
    for (int c = 0; c < 3; ++c) in2.at(f, 4)[c] = static_cast<float>((Pose(f) * Eigen::Vector3d(body.col(4)))[c]);
  MarkerArray out = in2;
  ASSERT_EQ(RigidFillGap(in2, ref, {0, 40, 20}, &out), "");
  for (int64_t f = 40; f < 60; ++f) {
    const Eigen::Vector3d p = Pose(f) * Eigen::Vector3d(body.col(0));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.at(f, 0)[c], p[c], 1e-4);
  }
}

TEST(RigidFill, RefusesNonRigidFrameAndReportsResiduals) {
  MarkerArray truth;
  MarkerArray in = RigidTake(Body(), 200, &truth);
  for (int64_t f = 80; f < 100; ++f) in.SetMissing(f, 0);
  in.at(90, 3)[0] += 10.0f;  // marker 3 off by 10 mm at frame 90
  ClusterReference ref = EstimateClusterReference(in, kAll);
  std::vector<double> res = ClusterResiduals(in, ref);
  ASSERT_EQ(res.size(), 200u);
  for (int64_t f = 0; f < 200; ++f)
    if (f != 90 && f != 150) {
      EXPECT_LT(res[static_cast<size_t>(f)], 1e-4) << f;
    }
  // Known answer for a small displacement δ of one marker (frame 150, 0.2 mm): to first order the
  // least-squares rigid fit leaves the residual (I − H) δ, H the hat matrix of the linearised
  // rigid motion (rows [−[p]x I] per marker); RMS = |(I − H) δ| / sqrt(k).
  in.at(150, 4)[1] += 0.2f;
  res = ClusterResiduals(in, ref);
  {
    const int k = 6;
    Eigen::MatrixXd a(3 * k, 6);
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(3 * k);
    for (int j = 0; j < k; ++j) {
      const Eigen::Vector3d p = Pose(150) * Eigen::Vector3d(Body().col(j));
      Eigen::Matrix3d px;
      px << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
      a.block<3, 3>(3 * j, 0) = -px;
      a.block<3, 3>(3 * j, 3) = Eigen::Matrix3d::Identity();
    }
    delta[3 * 4 + 1] = double(in.at(150, 4)[1]) - double(truth.at(150, 4)[1]);
    const Eigen::VectorXd r = delta - a * (a.transpose() * a).ldlt().solve(a.transpose() * delta);
    EXPECT_NEAR(res[150], r.norm() / std::sqrt(double(k)), 0.02 * r.norm() / std::sqrt(double(k)));
  }
  // The 10 mm displacement at frame 90 (k = 5, marker 0 missing): the fit cannot take up more
  // than translation alone leaves, d·sqrt(k − 1)/k.
  EXPECT_LE(res[90], 10.0 * std::sqrt(4.0) / 5.0 + 1e-6);
  EXPECT_GT(res[90], 2.0);
  RigidFillOptions o;
  o.max_residual_mm = 2.0;
  RigidGapFit fit = FitRigidGap(in, ref, {0, 80, 20}, o);
  EXPECT_NE(fit.why_not.find("frame 90: the cluster is not rigid"), std::string::npos) << fit.why_not;
  o.max_residual_mm = 5.0;
  EXPECT_EQ(FitRigidGap(in, ref, {0, 80, 20}, o).why_not, "");
  // The reference ignores the one bad frame (coordinate-wise median).
  for (int i = 0; i < 6; ++i)
    for (int j = i + 1; j < 6; ++j)
      EXPECT_NEAR((ref.shape.col(i) - ref.shape.col(j)).norm(), (Body().col(i) - Body().col(j)).norm(), 1e-4);
}

TEST(RigidFill, ReferenceIsRobustToSpikes) {
  MarkerArray truth;
  MarkerArray in = RigidTake(Body(), 300, &truth);
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int> marker(0, 5);
  for (int64_t f = 3; f < 300; f += 10) in.at(f, marker(rng))[1] += 40.0f;  // 10 % of frames spiked
  ClusterReference ref = EstimateClusterReference(in, kAll);
  ASSERT_EQ(ref.problem, "");
  for (int i = 0; i < 6; ++i)
    for (int j = i + 1; j < 6; ++j)
      EXPECT_NEAR((ref.shape.col(i) - ref.shape.col(j)).norm(), (Body().col(i) - Body().col(j)).norm(), 0.05);
}

TEST(RigidFill, ErrorGainPredictsTheFillNoise) {
  // Square of 4 neighbours of half-side a in the xy plane, filled marker at the centroid: the
  // gain is exactly sqrt(1/k) = 0.5 (rotation does not move the centre); 80 mm above it,
  // sqrt((3/4 + h²/a²)/3). Both checked against the formula and by Monte Carlo.
  Eigen::Matrix3Xd body(3, 6);
  const double a = 30;
  body << a, -a, 0, 0, 0, 0,  //
      0, 0, a, -a, 0, 0,      //
      0, 0, 0, 0, 0, 80;
  const int64_t frames = 4000;
  const double sigma = 0.5;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, sigma);
  MarkerArray in(frames, 6), truth(frames, 6);
  for (int64_t f = 0; f < frames; ++f)
    for (int j = 0; j < 6; ++j) {
      const Eigen::Vector3d p = Pose(f) * Eigen::Vector3d(body.col(j));
      for (int c = 0; c < 3; ++c) {
        truth.at(f, j)[c] = static_cast<float>(p[c]);
        in.at(f, j)[c] = static_cast<float>(p[c] + (j < 4 ? noise(rng) : 0.0));
      }
    }
  // Reference from the exact shape (the test is of the per-frame fit).
  ClusterReference ref;
  ref.columns = {0, 1, 2, 3, 4, 5};
  ref.shape = body;
  for (int target : {4, 5}) {
    MarkerArray hid = in;
    for (int64_t f = 0; f < frames; ++f) hid.SetMissing(f, 4), hid.SetMissing(f, 5);
    RigidFrameFit fit0 = FitClusterFrame(hid, ref, 0, target);
    ASSERT_TRUE(fit0.ok) << fit0.why_not;
    // Analytic gain: centroid = 0; J = tr(S) I − S with S = diag(2a², 2a², 0).
    const Eigen::Vector3d q = body.col(target);
    // J = diag(2a², 2a², 4a²); for q = (0, 0, h), [q]x J⁻¹ [q]xᵀ = diag(h²/2a², h²/2a², 0).
    const double h = q.z();
    const double gain = std::sqrt((3.0 / 4.0 + h * h / (a * a)) / 3.0);
    EXPECT_NEAR(fit0.error_gain, gain, 1e-9);
    RigidFillOptions o;
    o.max_error_gain = 100;
    MarkerArray out = hid;
    ASSERT_EQ(RigidFillGap(hid, ref, {target, 0, frames}, &out, o), "");
    double ss = 0;
    for (int64_t f = 0; f < frames; ++f) ss += std::pow(Distance(out, truth, f, target), 2);
    const double rms_per_coord = std::sqrt(ss / (3.0 * frames));
    // Monte Carlo over 4000 frames: within 5 % of the prediction (1σ of the estimate ~1.3 %).
    EXPECT_NEAR(rms_per_coord / sigma, gain, 0.05 * gain) << "target " << target;
  }
}

TEST(RigidFill, RecordsTheFillAndRejectsBadInput) {
  MarkerArray truth;
  MarkerArray in = RigidTake(Body(), 100, &truth);
  for (int64_t f = 20; f < 30; ++f) in.SetMissing(f, 2);
  RigidClusterFiller filler = RigidClusterFiller::FromMarkers(in, {{0, 1, 3}, kAll});
  EXPECT_EQ(filler.name(), "rigid");
  MarkerArray out = in;
  FillRecord rec{};
  ASSERT_TRUE(filler.Fill(in, {2, 20, 10}, &out, &rec));
  EXPECT_EQ(rec.marker, 2);
  EXPECT_EQ(rec.start, 20);
  EXPECT_EQ(rec.length, 10);
  EXPECT_EQ(rec.method, "rigid");
  nlohmann::json p = nlohmann::json::parse(rec.parameters);
  EXPECT_EQ(p["cluster"].get<std::vector<int>>(), kAll);  // the first cluster lacks column 2
  EXPECT_EQ(p["min_visible"].get<int>(), 5);
  for (int64_t f = 20; f < 30; ++f) EXPECT_LT(Distance(out, truth, f, 2), 1e-4);
  std::string why;
  MarkerArray wide(100, 7);
  EXPECT_FALSE(RigidClusterFiller::FromMarkers(wide, {kAll}).CanFill(wide, {6, 0, 5}, &why));
  EXPECT_EQ(why, "column 6 is in no rigid cluster");
  EXPECT_THROW(EstimateClusterReference(in, {0, 1}), InvalidInput);
  EXPECT_THROW(EstimateClusterReference(in, {0, 1, 1}), InvalidInput);
  EXPECT_THROW(EstimateClusterReference(in, {0, 1, 9}), InvalidInput);
  EXPECT_THROW(filler.CanFill(in, {2, 95, 10}, &why), InvalidInput);
  MarkerArray small(10, 6);
  EXPECT_THROW(filler.Fill(in, {2, 20, 10}, &small, &rec), InvalidInput);
  ClusterReference hollow;
  hollow.columns = kAll;  // no shape
  EXPECT_THROW(FitRigidGap(in, hollow, {2, 20, 10}), InvalidInput);
  EXPECT_THROW(FitClusterFrame(in, filler.clusters()[1], 100, 2), InvalidInput);
  // A cluster never seen with 3 markers: the reference says why.
  ClusterReference none = EstimateClusterReference(wide, kAll);
  EXPECT_NE(none.problem.find("fewer than 10 frames"), std::string::npos) << none.problem;
}

}  // namespace
}  // namespace csw::cleaning

namespace csw::cleaning {
namespace {

// Issue 12's acceptance: on virtual-cuer takes (0.2 mm noise, camera occlusions, dropouts),
// artificial gaps of 1-5, 6-20 and 21-60 frames punched into head- and forearm-cluster markers
// where they were captured are filled by the rigid fill within 0.5 mm of the clean capture on
// average. The reference shape is estimated from the punched take itself. Beside it, the error of
// the captured (noisy) marker at the same frames: the fill is below it (it averages the noise of
// 3-9 neighbours).
TEST(RigidFillCuer, ClusterMarkersWithinHalfMillimetre) {
  using namespace csw::cleaning::testing;
  const MarkerSet set = CuerMarkerSet();  // the test may use the cuer's names; the fill only sees columns
  struct Cluster {
    const char* name;
    std::vector<std::string> markers;
    std::vector<BinScore> bins = std::vector<BinScore>(GapBins().size());
    std::vector<BinScore> captured = std::vector<BinScore>(GapBins().size());
  };
  std::vector<Cluster> clusters = {{"head", set.head_cluster}, {"forearm", set.forearm_cluster}};
  std::mt19937_64 rng(2024);
  for (const SimulationResult& r : CuerTakes()) {
    const MarkerBinding b = BindMarkerSet(set, r.take.marker_names, true, r.take.name);
    for (Cluster& c : clusters) {
      const std::vector<int> cols = b.Columns(c.markers);
      for (int round = 0; round < 4; ++round) {
        MarkerArray punched;
        std::vector<int> bin;
        const std::vector<Gap> gaps = PunchGaps(r.take.markers, cols, rng, 1, 3, 10, &punched, &bin);
        const RigidClusterFiller filler = RigidClusterFiller::FromMarkers(punched, {cols});
        ASSERT_EQ(filler.clusters()[0].problem, "");
        EXPECT_LT(filler.clusters()[0].iterations, RigidFillOptions().max_iterations);  // converged
        MarkerArray out = punched;
        for (size_t i = 0; i < gaps.size(); ++i) {
          BinScore& s = c.bins[static_cast<size_t>(bin[i])];
          ++s.gaps;
          FillRecord rec{};
          if (!filler.Fill(punched, gaps[i], &out, &rec)) continue;
          ++s.filled;
          ScoreGap(r.clean, out, gaps[i], &s);
          ScoreGap(r.clean, r.take.markers, gaps[i], &c.captured[static_cast<size_t>(bin[i])]);
        }
      }
    }
  }
  std::printf(
      "| cluster | gap frames | gaps filled | frames | mean (mm) | p99 (mm) | max (mm) | captured marker mean (mm) "
      "|\n");
  for (const Cluster& c : clusters) {
    BinScore all;
    for (size_t b = 0; b < GapBins().size(); ++b) {
      const BinScore& s = c.bins[b];
      std::printf("| %s | %s | %d/%d | %zu | %.3f | %.3f | %.3f | %.3f |\n", c.name, GapBins()[b].label, s.filled,
                  s.gaps, s.errors.size(), s.Mean(), s.Percentile(0.99), s.Max(), c.captured[b].Mean());
      all.errors.insert(all.errors.end(), s.errors.begin(), s.errors.end());
      // Nearly every gap fills (measured: 447 of 448; the other has a frame with noise gain 3.06)
      // and the acceptance holds in every bin.
      EXPECT_GE(s.filled, s.gaps * 90 / 100) << c.name << " " << GapBins()[b].label;
      EXPECT_LE(s.Mean(), 0.5) << c.name << " " << GapBins()[b].label;
      // Regression bounds, measured 0.175-0.244 mm mean, p99 <= 0.77 mm, max 1.79 mm (forearm).
      EXPECT_LE(s.Mean(), 0.30) << c.name << " " << GapBins()[b].label;
      EXPECT_LE(s.Percentile(0.99), 1.0) << c.name << " " << GapBins()[b].label;
      EXPECT_LE(s.Max(), 2.5) << c.name << " " << GapBins()[b].label;
      // Below the noise of the captured marker itself (3-D mean 0.32 mm for 0.2 mm per axis).
      EXPECT_LT(s.Mean(), c.captured[b].Mean()) << c.name << " " << GapBins()[b].label;
    }
    EXPECT_LE(all.Mean(), 0.5) << c.name;
  }
}

}  // namespace
}  // namespace csw::cleaning

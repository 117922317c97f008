#include "models/rigid_motion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/error.h"
#include "models/pca.h"

namespace csw {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Six head-like markers (mm) around the origin, not coplanar.
Eigen::Matrix3Xd HeadShape() {
  Eigen::Matrix3Xd s(3, 6);
  s << 60, -60, 0, 0, 45, -45,  //
      0, 0, 80, -20, 50, 50,    //
      10, 10, 30, 90, -40, -40;
  return s.colwise() - s.rowwise().mean();
}

RigidTransform MakeTransform(double rx, double ry, double rz, double tx, double ty, double tz) {
  Eigen::Matrix<double, 6, 1> p;
  p << rx, ry, rz, tx, ty, tz;
  return RigidTransform::FromParameters(p);
}

// Angle (degrees) of the rotation taking a to b.
double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / kPi;
}

Eigen::Matrix3Xd Apply(const RigidTransform& t, const Eigen::Matrix3Xd& ref) {
  return (t.rotation * ref).colwise() + t.translation;
}

TEST(RigidMotion, ParametersRoundTrip) {
  const RigidTransform t = MakeTransform(0.3, -0.2, 0.5, 10, -20, 30);
  const Eigen::Matrix<double, 6, 1> p = t.Parameters();
  EXPECT_NEAR(p(0), 0.3, 1e-12);
  EXPECT_NEAR(p(1), -0.2, 1e-12);
  EXPECT_NEAR(p(2), 0.5, 1e-12);
  EXPECT_NEAR(p(5), 30.0, 1e-12);
  // Rotation of 0.5 rad about z maps x to (cos, sin, 0).
  const RigidTransform rz = MakeTransform(0, 0, 0.5, 0, 0, 0);
  EXPECT_NEAR((rz.rotation * Eigen::Vector3d::UnitX() - Eigen::Vector3d(std::cos(0.5), std::sin(0.5), 0)).norm(), 0.0,
              1e-15);
  const RigidTransform id = RigidTransform{}.Inverse();
  const Eigen::Vector3d v(1, 2, 3);
  EXPECT_NEAR((t.Inverse().Apply(t.Apply(v)) - v).norm(), 0.0, 1e-12);
  EXPECT_NEAR((id.Apply(v) - v).norm(), 0.0, 0.0);
}

TEST(RigidMotion, ExactRecovery) {
  const Eigen::Matrix3Xd ref = HeadShape();
  for (RobustLoss loss : {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy}) {
    const RigidTransform truth = MakeTransform(0.4, -0.7, 1.1, 120.5, -33.0, 1500.25);
    RigidOptions opt;
    opt.loss = loss;
    const RigidFit fit = EstimateRigid(ref, Apply(truth, ref), opt);
    ASSERT_TRUE(fit.valid);
    EXPECT_LE((fit.transform.rotation - truth.rotation).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LE((fit.transform.translation - truth.translation).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LE(fit.rms_mm, 1e-9);
    EXPECT_EQ(fit.used_markers.size(), 6u);
  }
}

TEST(RigidMotion, NoisyManyFrames) {
  // 0.2 mm Gaussian noise per coordinate on 6 markers (about 60 mm from the
  // centroid). One frame cannot be better than the noise allows (about 0.08 deg
  // and 0.08 mm per axis for least squares); over many frames the estimate must
  // be unbiased: the mean signed error of every parameter is within 0.05 deg /
  // 0.05 mm, and the per-frame RMS error stays near the least-squares limit.
  const Eigen::Matrix3Xd ref = HeadShape();
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.2);
  std::uniform_real_distribution<double> angle(-0.6, 0.6), shift(-200, 200);
  Eigen::Vector3d sum_rot = Eigen::Vector3d::Zero(), sum_t = Eigen::Vector3d::Zero();
  double sum2_deg = 0.0, sum2_mm = 0.0;
  const int frames = 2000;
  for (int f = 0; f < frames; ++f) {
    const RigidTransform truth = MakeTransform(angle(rng), angle(rng), angle(rng), shift(rng), shift(rng), shift(rng));
    Eigen::Matrix3Xd obs = Apply(truth, ref);
    for (Eigen::Index c = 0; c < obs.cols(); ++c) obs.col(c) += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    const RigidFit fit = EstimateRigid(ref, obs, RigidOptions{});
    ASSERT_TRUE(fit.valid);
    // Rotation error as a lab-frame rotation vector (degrees).
    const Eigen::AngleAxisd err(fit.transform.rotation * truth.rotation.transpose());
    const Eigen::Vector3d rot_deg = err.axis() * err.angle() * 180.0 / kPi;
    const Eigen::Vector3d t_mm = fit.transform.translation - truth.translation;
    sum_rot += rot_deg;
    sum_t += t_mm;
    sum2_deg += rot_deg.squaredNorm();
    sum2_mm += t_mm.squaredNorm();
  }
  const Eigen::Vector3d bias_deg = sum_rot / frames;
  const Eigen::Vector3d bias_mm = sum_t / frames;
  const double rms_deg = std::sqrt(sum2_deg / frames);
  const double rms_mm = std::sqrt(sum2_mm / frames);
  RecordProperty("bias_deg", std::to_string(bias_deg.cwiseAbs().maxCoeff()));
  RecordProperty("bias_mm", std::to_string(bias_mm.cwiseAbs().maxCoeff()));
  RecordProperty("rms_deg", std::to_string(rms_deg));
  RecordProperty("rms_mm", std::to_string(rms_mm));
  EXPECT_LT(bias_deg.cwiseAbs().maxCoeff(), 0.05);
  EXPECT_LT(bias_mm.cwiseAbs().maxCoeff(), 0.05);
  // Least-squares limits: translation sigma * sqrt(3 / N) = 0.141 mm; rotation
  // about 0.14 deg for this shape. Allow 30% for the Cauchy loss.
  EXPECT_LT(rms_mm, 0.2 * std::sqrt(3.0 / 6.0) * 1.3);
  EXPECT_LT(rms_deg, 0.2);
}

TEST(RigidMotion, FortyPercentMissing) {
  const Eigen::Matrix3Xd ref = HeadShape();
  const RigidTransform truth = MakeTransform(-0.2, 0.9, 0.1, 5, 6, 7);
  Eigen::Matrix3Xd obs = Apply(truth, ref);
  // 6 markers, 40%: drop columns 1 and 4 (2 of 6 = 33%) plus a 10-marker case below.
  obs.col(1).setConstant(kNaN);
  obs.col(4).setConstant(kNaN);
  RigidFit fit = EstimateRigid(ref, obs);
  ASSERT_TRUE(fit.valid);
  EXPECT_EQ(fit.used_markers, (std::vector<int>{0, 2, 3, 5}));
  EXPECT_TRUE(std::isnan(fit.per_marker_residual_mm(1)));
  EXPECT_LE((fit.transform.rotation - truth.rotation).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LE((fit.transform.translation - truth.translation).cwiseAbs().maxCoeff(), 1e-9);

  // 10 markers with 4 missing (40%).
  Eigen::Matrix3Xd ref10(3, 10);
  ref10.leftCols(6) = ref;
  ref10.rightCols(4) = ref.leftCols(4) * 0.5 + Eigen::Matrix3Xd::Constant(3, 4, 7.0);
  Eigen::Matrix3Xd obs10 = Apply(truth, ref10);
  for (int c : {0, 3, 6, 9}) obs10.col(c).setConstant(kNaN);
  fit = EstimateRigid(ref10, obs10);
  ASSERT_TRUE(fit.valid);
  EXPECT_EQ(fit.used_markers.size(), 6u);
  EXPECT_LE((fit.transform.rotation - truth.rotation).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LE((fit.transform.translation - truth.translation).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(RigidMotion, MislabelledMarkerRobust) {
  const Eigen::Matrix3Xd ref = HeadShape();
  const RigidTransform truth = MakeTransform(0.1, 0.2, -0.3, 10, 20, 30);
  Eigen::Matrix3Xd obs = Apply(truth, ref);
  obs.col(2) += Eigen::Vector3d(30, -40, 0);  // 50 mm off
  const RigidFit plain = EstimateRigidKabsch(ref, obs);
  RigidOptions cauchy;  // default: Cauchy, 1 mm
  const RigidFit robust = EstimateRigid(ref, obs, cauchy);
  RigidOptions huber;
  huber.loss = RobustLoss::kHuber;
  huber.loss_scale_mm = 0.5;
  const RigidFit hub = EstimateRigid(ref, obs, huber);
  ASSERT_TRUE(plain.valid && robust.valid && hub.valid);
  const double plain_deg = AngleDeg(plain.transform.rotation, truth.rotation);
  const double plain_mm = (plain.transform.translation - truth.translation).norm();
  const double robust_deg = AngleDeg(robust.transform.rotation, truth.rotation);
  const double robust_mm = (robust.transform.translation - truth.translation).norm();
  const double hub_deg = AngleDeg(hub.transform.rotation, truth.rotation);
  const double hub_mm = (hub.transform.translation - truth.translation).norm();
  RecordProperty("plain_deg", std::to_string(plain_deg));
  RecordProperty("plain_mm", std::to_string(plain_mm));
  RecordProperty("cauchy_deg", std::to_string(robust_deg));
  RecordProperty("cauchy_mm", std::to_string(robust_mm));
  RecordProperty("huber_deg", std::to_string(hub_deg));
  RecordProperty("huber_mm", std::to_string(hub_mm));
  EXPECT_GT(plain_deg + plain_mm, 1.0);
  EXPECT_LT(robust_deg, 0.1);
  EXPECT_LT(robust_mm, 0.1);
  // Huber's influence never vanishes: its bias grows with the loss scale.
  // At 0.5 mm it is still an order of magnitude below plain Kabsch.
  EXPECT_LT(hub_deg, plain_deg / 10.0);
  EXPECT_LT(hub_mm, plain_mm / 10.0);
  huber.loss_scale_mm = 0.1;
  const RigidFit hub_small = EstimateRigid(ref, obs, huber);
  EXPECT_LT(AngleDeg(hub_small.transform.rotation, truth.rotation), 0.1);
  EXPECT_LT((hub_small.transform.translation - truth.translation).norm(), 0.1);
  // The mislabelled marker stands out in the residuals (about 50 mm).
  EXPECT_NEAR(robust.per_marker_residual_mm(2), 50.0, 0.5);
}

TEST(RigidMotion, FewerThanThreeVisibleIsInvalid) {
  const Eigen::Matrix3Xd ref = HeadShape();
  Eigen::Matrix3Xd obs = Apply(MakeTransform(0.1, 0, 0, 1, 2, 3), ref);
  for (int c : {0, 1, 2, 3}) obs.col(c).setConstant(kNaN);
  const RigidFit fit = EstimateRigid(ref, obs);
  EXPECT_FALSE(fit.valid);
  EXPECT_EQ(fit.used_markers.size(), 2u);
  // Three collinear markers do not fix the rotation either.
  Eigen::Matrix3Xd line(3, 3);
  line << 0, 1, 2, 0, 1, 2, 0, 1, 2;
  EXPECT_FALSE(EstimateRigid(line, line).valid);
  // Infinite coordinates count as missing; overflowing ones give no fit.
  Eigen::Matrix3Xd inf_obs = Apply(MakeTransform(0.1, 0, 0, 1, 2, 3), ref);
  inf_obs(0, 0) = std::numeric_limits<double>::infinity();
  const RigidFit five = EstimateRigid(ref, inf_obs);
  EXPECT_TRUE(five.valid);
  EXPECT_EQ(five.used_markers, (std::vector<int>{1, 2, 3, 4, 5}));
  const Eigen::Matrix3Xd huge = ref * 1e307;
  const RigidFit overflow = EstimateRigid(ref, huge);
  EXPECT_FALSE(overflow.valid);
  EXPECT_THROW(EstimateRigid(ref, ref.leftCols(3)), InvalidInput);
}

// A take: head cluster (markers 0..5) moving rigidly, plus two free markers.
MarkerArray MakeTake(const Eigen::Matrix3Xd& ref, int frames, std::vector<RigidTransform>* truth) {
  MarkerArray m(frames, 8);
  for (int f = 0; f < frames; ++f) {
    const double s = f * 0.05;
    const RigidTransform t = MakeTransform(0.2 * std::sin(s), 0.1 * std::cos(1.3 * s), 0.05 * s, 100 + 10 * std::sin(s),
                                           -50 + 3 * s, 1200 + 5 * std::cos(0.7 * s));
    truth->push_back(t);
    const Eigen::Matrix3Xd obs = Apply(t, ref);
    for (int c = 0; c < 6; ++c) {
      for (int k = 0; k < 3; ++k) m.at(f, c)[k] = static_cast<float>(obs(k, c));
    }
    for (int c = 6; c < 8; ++c) {
      const Eigen::Vector3d lip = t.Apply(Eigen::Vector3d(c * 3.0, 10.0 * std::sin(s * c), -20.0));
      for (int k = 0; k < 3; ++k) m.at(f, c)[k] = static_cast<float>(lip(k));
    }
  }
  return m;
}

TEST(RigidMotion, SeriesReferenceAndFrames) {
  const Eigen::Matrix3Xd ref = HeadShape();
  std::vector<RigidTransform> truth;
  MarkerArray take = MakeTake(ref, 200, &truth);
  take.SetMissing(10, 0);
  take.SetMissing(10, 1);
  take.SetMissing(20, 0);
  take.SetMissing(20, 1);
  take.SetMissing(20, 2);
  take.SetMissing(20, 3);  // only 2 cluster markers visible: invalid
  const std::vector<int> cols = {0, 1, 2, 3, 4, 5};
  const Eigen::Matrix3Xd est_ref = ClusterReference(take, cols);
  // Same shape as the truth: all pairwise distances agree (float storage: 1e-3 mm).
  for (int i = 0; i < 6; ++i) {
    for (int j = i + 1; j < 6; ++j) {
      EXPECT_NEAR((est_ref.col(i) - est_ref.col(j)).norm(), (ref.col(i) - ref.col(j)).norm(), 1e-3);
    }
  }
  EXPECT_NEAR(est_ref.rowwise().mean().norm(), 0.0, 1e-9);

  Progress progress;
  const RigidSeries series = EstimateRigidSeries(take, cols, ref, RigidOptions{}, &progress);
  ASSERT_EQ(series.frames(), 200);
  EXPECT_EQ(series.CountValid(), 199);
  EXPECT_FALSE(series.valid[20]);
  EXPECT_TRUE(series.valid[10]);
  for (int f = 0; f < 200; ++f) {
    if (f == 20) continue;
    const RigidTransform t = series.Transform(f);
    EXPECT_LT(AngleDeg(t.rotation, truth[static_cast<size_t>(f)].rotation), 1e-4) << f;
    EXPECT_LT((t.translation - truth[static_cast<size_t>(f)].translation).norm(), 1e-3) << f;
  }
  EXPECT_EQ(series.ValidParameters().rows(), 199);
  EXPECT_EQ(std::count(series.converged.begin(), series.converged.end(), uint8_t{1}), 199);

  // Local frame: the cluster markers sit at the reference; lab frame is recovered.
  const MarkerArray local = ToLocalFrame(take, series);
  for (int f : {0, 10, 199}) {
    for (int c = 2; c < 6; ++c) {
      const float* p = local.at(f, c);
      EXPECT_NEAR((Eigen::Vector3d(p[0], p[1], p[2]) - ref.col(c)).norm(), 0.0, 1e-3);
    }
  }
  EXPECT_FALSE(local.Visible(20, 5));
  EXPECT_FALSE(local.Visible(10, 0));
  const MarkerArray back = ToLabFrame(local, series);
  double worst = 0.0;
  for (int f = 0; f < 200; ++f) {
    for (int c = 0; c < 8; ++c) {
      if (f == 20) {
        EXPECT_FALSE(back.Visible(f, c));
        continue;
      }
      EXPECT_EQ(back.Visible(f, c), take.Visible(f, c));
      if (!take.Visible(f, c)) continue;
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(double(back.at(f, c)[k]) - take.at(f, c)[k]));
    }
  }
  EXPECT_LT(worst, 1e-3);  // float32 rounding of millimetre coordinates near 1200 mm

  // Motion PCA: the 6-parameter series of a pure translation along one axis
  // has one component, on tx.
  MarkerArray slide(50, 6);
  for (int f = 0; f < 50; ++f) {
    for (int c = 0; c < 6; ++c) {
      for (int k = 0; k < 3; ++k) slide.at(f, c)[k] = static_cast<float>(ref(k, c) + (k == 0 ? f : 0));
    }
  }
  const Pca motion = FitPca(EstimateRigidSeries(slide, cols, ref).ValidParameters(), 0);
  EXPECT_NEAR(motion.explained_fraction(0), 1.0, 1e-9);
  EXPECT_NEAR(std::abs(motion.components(3, 0)), 1.0, 1e-9);
  EXPECT_NEAR(motion.variances(0), 50.0 * 51.0 / 12.0, 1e-6);  // variance of 0..49
}

TEST(RigidMotion, Cancel) {
  std::vector<RigidTransform> truth;
  const MarkerArray take = MakeTake(HeadShape(), 10, &truth);
  Progress progress;
  progress.Cancel();
  EXPECT_THROW(EstimateRigidSeries(take, {0, 1, 2, 3, 4, 5}, HeadShape(), RigidOptions{}, &progress), Cancelled);
  EXPECT_THROW(EstimateRigidSeries(take, {0, 1, 9}, HeadShape().leftCols(3)), InvalidInput);
}

}  // namespace
}  // namespace csw

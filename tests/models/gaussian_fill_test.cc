// Gaussian gap filler (models/gaussian_fill.h): EM estimates of a known
// normal from incomplete samples, the conditional mean against its closed
// form, the pattern cache, and clear errors.
#include "models/gaussian_fill.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <random>

#include "core/error.h"
#include "core/progress.h"

namespace csw {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A known 3-marker (9-D) normal: mean, covariance L·Lᵀ + 0.5·I.
struct KnownNormal {
  Eigen::VectorXd mean;
  Eigen::MatrixXd cov, chol;
  explicit KnownNormal(std::mt19937& rng) {
    std::normal_distribution<double> n(0, 1);
    mean.resize(9);
    for (int i = 0; i < 9; ++i) mean(i) = 10 * n(rng);
    Eigen::MatrixXd l(9, 3);
    for (int i = 0; i < 9; ++i)
      for (int k = 0; k < 3; ++k) l(i, k) = 4 * n(rng);
    cov = l * l.transpose() + 0.5 * Eigen::MatrixXd::Identity(9, 9);
    chol = cov.llt().matrixL();
  }
  Eigen::MatrixXd Sample(int frames, std::mt19937& rng) const {
    std::normal_distribution<double> n(0, 1);
    Eigen::MatrixXd x(frames, 9);
    for (int f = 0; f < frames; ++f) {
      Eigen::VectorXd z(9);
      for (int i = 0; i < 9; ++i) z(i) = n(rng);
      x.row(f) = (mean + chol * z).transpose();
    }
    return x;
  }
};

TEST(GaussianFill, EmRecoversAKnownNormalFromIncompleteFrames) {
  std::mt19937 rng(11);
  const KnownNormal truth(rng);
  Eigen::MatrixXd x = truth.Sample(20000, rng);
  // Hide each marker in 30 % of the frames at random (never all three).
  std::uniform_real_distribution<double> u(0, 1);
  for (Eigen::Index f = 0; f < x.rows(); ++f) {
    const int keep = static_cast<int>(f % 3);
    for (int m = 0; m < 3; ++m) {
      if (m != keep && u(rng) < 0.3) x.row(f).segment<3>(3 * m).setConstant(kNaN);
    }
  }
  GaussianFillOptions opt;
  opt.ridge_mm2 = 0;
  opt.tolerance_mm = 1e-6;
  opt.max_iterations = 500;
  const GaussianFill fill = FitGaussianFill(x, opt);
  EXPECT_EQ(fill.frames, 20000);
  EXPECT_LT(fill.iterations, 500);
  // Sampling error of 20,000 frames: sd/√n ≈ 0.05 for the mean.
  EXPECT_LT((fill.mean - truth.mean).cwiseAbs().maxCoeff(), 0.25);
  EXPECT_LT((fill.covariance - truth.cov).norm() / truth.cov.norm(), 0.03);
}

TEST(GaussianFill, ConditionalMeanMatchesTheClosedForm) {
  std::mt19937 rng(5);
  const KnownNormal truth(rng);
  GaussianFill fill;
  fill.mean = truth.mean;
  fill.covariance = truth.cov;
  fill.ridge_mm2 = 0;
  GaussianFiller filler(fill);
  const Eigen::MatrixXd x = truth.Sample(3, rng);
  for (int hidden = 0; hidden < 3; ++hidden) {
    Eigen::Matrix3Xd m = Eigen::Map<const Eigen::Matrix3Xd>(Eigen::VectorXd(x.row(hidden).transpose()).data(), 3, 3);
    m.col(hidden).setConstant(kNaN);
    ASSERT_EQ(filler.Fill(&m), 1);
    // μ_h + Σ_hv Σ_vv⁻¹ (x_v − μ_v), written out with blocks.
    std::vector<int> v, h;
    for (int i = 0; i < 9; ++i) (i / 3 == hidden ? h : v).push_back(i);
    Eigen::MatrixXd svv(6, 6), shv(3, 6);
    Eigen::VectorXd dv(6);
    for (int a = 0; a < 6; ++a) {
      dv(a) = x(hidden, v[a]) - truth.mean(v[a]);
      for (int b = 0; b < 6; ++b) svv(a, b) = truth.cov(v[a], v[b]);
      for (int b = 0; b < 3; ++b) shv(b, a) = truth.cov(h[b], v[a]);
    }
    const Eigen::VectorXd expected = truth.mean.segment<3>(3 * hidden) + shv * svv.inverse() * dv;
    EXPECT_LT((m.col(hidden) - expected).norm(), 1e-9) << hidden;
    // Seen markers are untouched.
    for (int k = 0; k < 3; ++k) {
      if (k != hidden) {
        EXPECT_EQ(m.col(k), x.row(hidden).segment<3>(3 * k).transpose());
      }
    }
  }
  // Nothing seen or nothing missing: nothing filled.
  Eigen::Matrix3Xd none = Eigen::Matrix3Xd::Constant(3, 3, kNaN);
  EXPECT_EQ(filler.Fill(&none), 0);
  EXPECT_TRUE(none.array().isNaN().all());
  Eigen::Matrix3Xd all = Eigen::Matrix3Xd::Zero(3, 3);
  EXPECT_EQ(filler.Fill(&all), 0);
}

// Predict(pattern, marker, markers) is the closed-form conditional mean of one
// marker missing from the pattern, whatever the markers hold in the columns
// the pattern does not see (the gap-edge correction predicts a frame with
// another frame's pattern).
TEST(GaussianFill, PredictWithAPatternIsTheConditionalMeanOfThatPattern) {
  std::mt19937 rng(9);
  const KnownNormal truth(rng);
  GaussianFill fill;
  fill.mean = truth.mean;
  fill.covariance = truth.cov;
  fill.ridge_mm2 = 0;
  GaussianFiller filler(fill);
  const Eigen::MatrixXd x = truth.Sample(1, rng);
  Eigen::Matrix3Xd m = Eigen::Map<const Eigen::Matrix3Xd>(Eigen::VectorXd(x.row(0).transpose()).data(), 3, 3);
  const std::vector<uint8_t> pattern = {1, 0, 0};  // marker 0 seen; 1 and 2 missing
  // Closed form for marker 1 given marker 0: μ_1 + Σ_10 Σ_00⁻¹ (x_0 − μ_0).
  const Eigen::Matrix3d s00 = truth.cov.block<3, 3>(0, 0), s10 = truth.cov.block<3, 3>(3, 0);
  const Eigen::Vector3d expected =
      truth.mean.segment<3>(3) + s10 * s00.inverse() * (m.col(0) - truth.mean.segment<3>(0));
  EXPECT_LT((filler.Predict(pattern, 1, m) - expected).norm(), 1e-9);
  // Columns the pattern does not see are not read.
  m.col(2).setConstant(1e6);
  EXPECT_LT((filler.Predict(pattern, 1, m) - expected).norm(), 1e-9);
  // And it agrees with Fill for the same pattern.
  Eigen::Matrix3Xd filled = m;
  filled.col(1).setConstant(kNaN);
  filled.col(2).setConstant(kNaN);
  ASSERT_EQ(filler.Fill(&filled), 2);
  EXPECT_LT((filled.col(1) - expected).norm(), 1e-9);
  // A seen marker, or nothing seen: NaN.
  EXPECT_TRUE(filler.Predict(pattern, 0, m).array().isNaN().all());
  EXPECT_TRUE(filler.Predict({0, 0, 0}, 1, m).array().isNaN().all());
}

TEST(GaussianFill, BeatsCompleteCaseTrainingWhenHidingDependsOnThePosture) {
  // A marker hidden whenever it lies beyond a threshold (as a folded finger
  // hides behind the palm): complete frames alone never show that region,
  // so their mean is biased; EM on the incomplete frames is not.
  std::mt19937 rng(3);
  const KnownNormal truth(rng);
  const Eigen::MatrixXd clean = truth.Sample(20000, rng);
  Eigen::MatrixXd x = clean;
  const double threshold = truth.mean(6);
  for (Eigen::Index f = 0; f < x.rows(); ++f) {
    if (x(f, 6) > threshold) x.row(f).segment<3>(6).setConstant(kNaN);
  }
  GaussianFillOptions opt;
  opt.max_iterations = 300;
  const GaussianFill em = FitGaussianFill(x, opt);
  double complete_mean = 0;
  int complete = 0;
  for (Eigen::Index f = 0; f < x.rows(); ++f) {
    if (!std::isnan(x(f, 6))) {
      complete_mean += x(f, 6);
      ++complete;
    }
  }
  complete_mean /= complete;
  const double sd = std::sqrt(truth.cov(6, 6));
  EXPECT_GT(truth.mean(6) - complete_mean, 0.5 * sd);         // complete frames: biased low
  EXPECT_LT(std::abs(em.mean(6) - truth.mean(6)), 0.1 * sd);  // EM: unbiased
  // Filling the hidden samples: mean error well below the complete-case mean's.
  GaussianFiller filler(em);
  double error = 0;
  int hidden = 0;
  for (Eigen::Index f = 0; f < x.rows(); ++f) {
    if (!std::isnan(x(f, 6))) continue;
    Eigen::Matrix3Xd m = Eigen::Map<const Eigen::Matrix3Xd>(Eigen::VectorXd(x.row(f).transpose()).data(), 3, 3);
    filler.Fill(&m);
    error += (m.col(2) - clean.row(f).segment<3>(6).transpose()).norm();
    ++hidden;
  }
  EXPECT_GT(hidden, 5000);
  EXPECT_LT(error / hidden, 0.5 * sd);
}

TEST(GaussianFill, ClearErrors) {
  EXPECT_THROW(FitGaussianFill(Eigen::MatrixXd::Zero(10, 4)), InvalidInput);  // not 3 per marker
  EXPECT_THROW(FitGaussianFill(Eigen::MatrixXd::Zero(1, 6)), InvalidInput);   // one frame
  Eigen::MatrixXd never = Eigen::MatrixXd::Zero(10, 6);
  never.col(3).setConstant(kNaN);
  never.col(4).setConstant(kNaN);
  never.col(5).setConstant(kNaN);
  EXPECT_THROW(FitGaussianFill(never), InvalidInput);  // marker 1 never seen
  Eigen::MatrixXd inf = Eigen::MatrixXd::Zero(10, 6);
  inf(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(FitGaussianFill(inf), InvalidInput);
  GaussianFill fill;
  fill.mean = Eigen::VectorXd::Zero(6);
  fill.covariance = Eigen::MatrixXd::Identity(6, 6);
  GaussianFiller filler(fill);
  Eigen::Matrix3Xd three(3, 3);
  EXPECT_THROW(filler.Fill(&three), InvalidInput);
  // Cancel.
  Progress cancelled([](const std::string&, double) { throw Cancelled(); });
  EXPECT_THROW(FitGaussianFill(Eigen::MatrixXd::Random(20, 6), {}, &cancelled), Cancelled);
}

}  // namespace
}  // namespace csw

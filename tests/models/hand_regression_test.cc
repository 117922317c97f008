#include "models/hand_regression.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "core/error.h"
#include "models/joint_angles.h"

namespace csw {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::MatrixXd RandomAngles(int frames, int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-kPi, kPi);
  Eigen::MatrixXd a(frames, n);
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = u(rng);
  return a;
}

Eigen::MatrixXd RandomMatrix(int rows, int cols, double sd, std::mt19937& rng) {
  std::normal_distribution<double> n(0, sd);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = n(rng);
  return m;
}

Eigen::MatrixXd Features(const Eigen::MatrixXd& angles) {
  Eigen::MatrixXd f(angles.rows(), 1 + 2 * angles.cols());
  for (Eigen::Index r = 0; r < angles.rows(); ++r) f.row(r) = AngleFeatures(angles.row(r).transpose());
  return f;
}

TEST(HandRegression, FeaturesFollowTheSeedOrder) {
  const Eigen::RowVectorXd p = AngleFeatures(Eigen::Vector2d(0.0, kPi / 2));
  ASSERT_EQ(p.size(), 5);
  EXPECT_DOUBLE_EQ(p(0), 1.0);
  EXPECT_DOUBLE_EQ(p(1), 1.0);
  EXPECT_NEAR(p(2), 0.0, 1e-16);
  EXPECT_DOUBLE_EQ(p(3), 0.0);
  EXPECT_DOUBLE_EQ(p(4), 1.0);
}

TEST(HandRegression, RecoversAKnownMapExactly) {
  std::mt19937 rng(11);
  const Eigen::MatrixXd angles = RandomAngles(300, 4, rng);
  Eigen::MatrixXd truth = RandomMatrix(9, 30, 20.0, rng);
  truth.row(0).array() += 100.0;  // markers far from the forearm origin
  const Eigen::MatrixXd y = Features(angles) * truth;
  const HandRegression reg = FitHandRegression(angles, y);
  EXPECT_EQ(reg.rank, 8);
  EXPECT_TRUE(reg.warnings.empty());
  const double err = (reg.coefficients - truth).cwiseAbs().maxCoeff();
  std::printf("exact map: max coefficient error %.3g, rms residual %.3g\n", err, reg.rms_residual);
  EXPECT_LT(err, 1e-9);
  EXPECT_LT(reg.rms_residual, 1e-9);
  const Eigen::VectorXd a(Eigen::Vector4d(0.1, -2.0, 3.1, -3.1));
  EXPECT_LT((reg.Predict(a) - (AngleFeatures(a) * truth).transpose()).norm(), 1e-8);
}

TEST(HandRegression, NoisyDataStaysWithinNoise) {
  std::mt19937 rng(12);
  const int frames = 400, n = 4;
  const double sigma = 0.5;
  const Eigen::MatrixXd angles = RandomAngles(frames, n, rng);
  const Eigen::MatrixXd truth = RandomMatrix(9, 30, 20.0, rng);
  const Eigen::MatrixXd y = Features(angles) * truth + RandomMatrix(frames, 30, sigma, rng);
  const HandRegression reg = FitHandRegression(angles, y);
  // Residual RMS of least squares: σ·√(1 − p/N).
  const double expected_residual = sigma * std::sqrt(1.0 - 9.0 / frames);
  EXPECT_NEAR(reg.rms_residual, expected_residual, 0.05 * expected_residual);
  // Prediction error on new angles: about σ·√(p/N) = 0.075.
  const Eigen::MatrixXd test_angles = RandomAngles(200, n, rng);
  const Eigen::MatrixXd diff = reg.PredictFrames(test_angles) - Features(test_angles) * truth;
  const double rms = std::sqrt(diff.squaredNorm() / static_cast<double>(diff.size()));
  std::printf("noisy map (sigma %.2f): residual rms %.4f, prediction rms error %.4f\n", sigma, reg.rms_residual, rms);
  EXPECT_LT(rms, 2 * sigma * std::sqrt(9.0 / frames));
  // A small ridge changes the answer by little.
  HandRegressionOptions ridge;
  ridge.ridge = 1e-6;
  const HandRegression r2 = FitHandRegression(angles, y, ridge);
  EXPECT_LT((r2.coefficients - reg.coefficients).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(HandRegression, ConstantAngleIsDroppedAndStillPredicts) {
  std::mt19937 rng(13);
  Eigen::MatrixXd angles = RandomAngles(200, 4, rng);
  angles.col(2).setConstant(0.7);
  const Eigen::MatrixXd truth = RandomMatrix(9, 12, 10.0, rng);
  const Eigen::MatrixXd y = Features(angles) * truth;
  for (double ridge : {0.0, 1e-12}) {
    HandRegressionOptions opt;
    opt.ridge = ridge;
    const HandRegression reg = FitHandRegression(angles, y, opt);
    ASSERT_EQ(reg.warnings.size(), 1u);  // one line: cos and sin of angle 2
    EXPECT_EQ(reg.warnings[0],
              "1 angle constant over the training frames, dropped from the regression (the intercept holds them): "
              "angle 2");
    EXPECT_EQ(reg.rank, 6);
    EXPECT_EQ(reg.coefficients.row(3).norm(), 0.0);
    Eigen::MatrixXd test = RandomAngles(50, 4, rng);
    test.col(2).setConstant(0.7);
    EXPECT_LT((reg.PredictFrames(test) - Features(test) * truth).cwiseAbs().maxCoeff(), 1e-8) << "ridge " << ridge;
  }
}

// The warning names angles by the names given, and a lone constant feature by cos(name) or sin(name).
TEST(HandRegression, DroppedFeaturesWarningNamesTheAngles) {
  std::mt19937 rng(15);
  Eigen::MatrixXd angles = RandomAngles(100, 4, rng);
  angles.col(1).setZero();  // never moves: cos and sin constant
  // +-pi/3: cos is 0.5 in every frame, sin varies.
  for (Eigen::Index f = 0; f < angles.rows(); ++f) angles(f, 3) = (f % 2 ? 1.0 : -1.0) * std::numbers::pi / 3.0;
  const Eigen::MatrixXd y = Features(angles) * RandomMatrix(9, 6, 10.0, rng);
  HandRegressionOptions opt;
  opt.angle_names = {"thumb1.flexion", "thumb1.twist", "index1.flexion", "index1.spread"};
  const HandRegression reg = FitHandRegression(angles, y, opt);
  ASSERT_EQ(reg.warnings.size(), 1u);
  EXPECT_EQ(reg.warnings[0],
            "2 angles constant over the training frames, dropped from the regression (the intercept holds them): "
            "thumb1.twist, cos(index1.spread)");
}

TEST(HandRegression, DuplicatedAngleGivesMinimumNormExactFit) {
  std::mt19937 rng(14);
  Eigen::MatrixXd angles = RandomAngles(150, 3, rng);
  angles.col(2) = angles.col(0);
  const Eigen::MatrixXd truth = RandomMatrix(7, 6, 10.0, rng);
  const Eigen::MatrixXd y = Features(angles) * truth;
  const HandRegression reg = FitHandRegression(angles, y);
  EXPECT_EQ(reg.rank, 4);
  ASSERT_EQ(reg.warnings.size(), 1u);
  EXPECT_LT(reg.rms_residual, 1e-9);
  // Minimum norm splits the duplicated angle's weight evenly.
  EXPECT_LT((reg.coefficients.row(1) - reg.coefficients.row(3)).norm(), 1e-8);
  Eigen::MatrixXd test = RandomAngles(20, 3, rng);
  test.col(2) = test.col(0);
  EXPECT_LT((reg.PredictFrames(test) - Features(test) * truth).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(HandRegression, RejectsBadInput) {
  std::mt19937 rng(15);
  const Eigen::MatrixXd a = RandomAngles(10, 2, rng);
  const Eigen::MatrixXd y = RandomMatrix(10, 6, 1.0, rng);
  EXPECT_THROW(FitHandRegression(a.topRows(1), y.topRows(1)), InvalidInput);
  EXPECT_THROW(FitHandRegression(a, y.topRows(9)), InvalidInput);
  EXPECT_THROW(FitHandRegression(a, y.leftCols(0)), InvalidInput);
  Eigen::MatrixXd bad = y;
  bad(2, 2) = NAN;
  EXPECT_THROW(FitHandRegression(a, bad), InvalidInput);
  HandRegressionOptions opt;
  opt.ridge = -1;
  EXPECT_THROW(FitHandRegression(a, y, opt), InvalidInput);
  const HandRegression reg = FitHandRegression(a, y);
  EXPECT_THROW(reg.Predict(Eigen::VectorXd::Zero(3)), InvalidInput);
  EXPECT_THROW(FitAnglePca(a, 3), InvalidInput);
  EXPECT_THROW(FitAnglePca(a, 0), InvalidInput);
}

// Angles driven by two components about means near ±π, wrapped.
struct AngleData {
  Eigen::MatrixXd angles;
  Eigen::MatrixXd basis;  // n × 2 orthonormal
  Eigen::VectorXd mean;
};
AngleData MakeAngles(int frames, std::mt19937& rng) {
  AngleData d;
  d.mean = Eigen::VectorXd(5);
  d.mean << 3.0, -3.1, 0.5, -1.0, kPi;
  const Eigen::MatrixXd raw = RandomMatrix(5, 2, 1.0, rng);
  d.basis = Eigen::HouseholderQR<Eigen::MatrixXd>(raw).householderQ() * Eigen::MatrixXd::Identity(5, 2);
  Eigen::MatrixXd scores = RandomMatrix(frames, 2, 1.0, rng);
  scores.col(0) *= 0.4;
  scores.col(1) *= 0.15;
  scores.rowwise() -= scores.colwise().mean();
  d.angles.resize(frames, 5);
  for (int f = 0; f < frames; ++f) {
    const Eigen::VectorXd a = d.mean + d.basis * scores.row(f).transpose();
    for (int i = 0; i < 5; ++i) d.angles(f, i) = WrapAngle(a(i));
  }
  return d;
}

TEST(HandRegression, AnglePcaHandlesWrappingAndRoundTrips) {
  std::mt19937 rng(16);
  const AngleData d = MakeAngles(300, rng);
  const AnglePca pca = FitAnglePca(d.angles, 2);
  // Angles near ±π would give a huge linear variance; circular centring finds the 2-D span.
  double sum = 0;
  for (double v : pca.variance_explained) sum += v;
  EXPECT_NEAR(sum, 1.0, 1e-9);
  EXPECT_GT(pca.variance_explained[0], pca.variance_explained[1]);
  const Eigen::MatrixXd outside = d.basis - pca.components * (pca.components.transpose() * d.basis);
  EXPECT_LT(outside.norm(), 1e-9);
  for (int f = 0; f < 20; ++f) {
    const Eigen::VectorXd a = d.angles.row(f).transpose();
    const Eigen::VectorXd back = pca.Angles(pca.Params(a));
    for (int i = 0; i < 5; ++i) EXPECT_LT(std::abs(WrapAngle(back(i) - a(i))), 1e-9);
  }
}

TEST(HandRegression, ShapeModelPredictsFromAngleParameters) {
  std::mt19937 rng(17);
  const AngleData d = MakeAngles(250, rng);
  const Eigen::MatrixXd truth = RandomMatrix(11, 15, 10.0, rng);
  const Eigen::MatrixXd y = Features(d.angles) * truth;
  const HandShapeModel model = FitHandShapeModel(d.angles, y, 2);
  EXPECT_EQ(model.angle_pca.num_parameters(), 2);
  EXPECT_LT(model.regression.rms_residual, 1e-8);
  // New hand shapes inside the 2-parameter family.
  for (int t = 0; t < 10; ++t) {
    const Eigen::Vector2d params = RandomMatrix(2, 1, 0.3, rng);
    const Eigen::VectorXd angles = model.angle_pca.Angles(params);
    const Eigen::VectorXd expected = (AngleFeatures(angles) * truth).transpose();
    EXPECT_LT((model.Predict(params) - expected).cwiseAbs().maxCoeff(), 1e-7);
  }
}

}  // namespace
}  // namespace csw

#include "models/pca.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

#include "core/error.h"

namespace csw {
namespace {

// Samples = mean + sum_k score_k * component_k with orthonormal components
// (4 dims, 2 components) and zero-mean, uncorrelated scores of known variance.
TEST(Pca, RecoversKnownComponents) {
  Eigen::Vector4d u1(1, 1, 1, 1);
  u1 /= 2.0;
  Eigen::Vector4d u2(1, -1, 1, -1);
  u2 /= 2.0;
  const Eigen::Vector4d mean(10, -5, 3, 7);
  // Scores: a = +-3 and b = +-1 on a 2x2 balanced design repeated, so the sample
  // variances are exactly known: 4 rows per block with a, b in {(3,1),(3,-1),(-3,1),(-3,-1)}.
  const int blocks = 25;
  Eigen::MatrixXd x(4 * blocks, 4);
  const double a[4] = {3, 3, -3, -3};
  const double b[4] = {1, -1, 1, -1};
  for (int r = 0; r < 4 * blocks; ++r) x.row(r) = (mean + a[r % 4] * u1 + b[r % 4] * u2).transpose();
  const double n = 4.0 * blocks;
  const Pca pca = FitPca(x, 0);
  ASSERT_EQ(pca.count(), 4);
  EXPECT_NEAR((pca.mean - mean).norm(), 0.0, 1e-12);
  EXPECT_NEAR(pca.variances(0), 9.0 * n / (n - 1), 1e-9);
  EXPECT_NEAR(pca.variances(1), 1.0 * n / (n - 1), 1e-9);
  EXPECT_NEAR(pca.variances(2), 0.0, 1e-9);
  EXPECT_NEAR(std::abs(pca.components.col(0).dot(u1)), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(pca.components.col(1).dot(u2)), 1.0, 1e-12);
  EXPECT_NEAR(pca.explained_fraction(0), 0.9, 1e-12);
  EXPECT_NEAR(pca.explained_fraction(1), 0.1, 1e-12);
  EXPECT_NEAR((pca.components.transpose() * pca.components - Eigen::Matrix4d::Identity()).norm(), 0.0, 1e-12);
  // Scores equal the generating ones up to the component sign.
  const Eigen::MatrixXd scores = pca.Project(x);
  EXPECT_NEAR(std::abs(scores(0, 0)), 3.0, 1e-12);
  EXPECT_NEAR(std::abs(scores(1, 1)), 1.0, 1e-12);
  // Two components reconstruct the data exactly.
  const Pca two = FitPca(x, 2);
  EXPECT_EQ(two.count(), 2);
  EXPECT_NEAR((two.Reconstruct(two.Project(x)) - x).cwiseAbs().maxCoeff(), 0.0, 1e-12);
  // One component: residual is exactly the u2 part (1 per row in norm).
  const Pca one = FitPcaVariance(x, 0.85);
  EXPECT_EQ(one.count(), 1);
  const Eigen::MatrixXd rest = x - one.Reconstruct(one.Project(x));
  EXPECT_NEAR(rest.row(0).norm(), 1.0, 1e-12);
  EXPECT_EQ(FitPcaVariance(x, 0.95).count(), 2);
  EXPECT_EQ(FitPcaVariance(x, 1.0).count(), 2);
}

TEST(Pca, RandomRotatedGaussian) {
  // Known covariance Q diag(25, 4, 1) Q^T: estimated variances and axes agree.
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Matrix3d q = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const int n = 20000;
  Eigen::MatrixXd x(n, 3);
  for (int r = 0; r < n; ++r) x.row(r) = (q * Eigen::Vector3d(5 * g(rng), 2 * g(rng), g(rng))).transpose();
  const Pca pca = FitPca(x, 3);
  EXPECT_NEAR(pca.variances(0), 25.0, 25.0 * 0.03);
  EXPECT_NEAR(pca.variances(1), 4.0, 4.0 * 0.03);
  EXPECT_NEAR(pca.variances(2), 1.0, 0.03);
  EXPECT_GT(std::abs(pca.components.col(0).dot(q.col(0))), 0.999);
  EXPECT_GT(std::abs(pca.components.col(1).dot(q.col(1))), 0.99);
  // Deterministic sign: largest-magnitude entry positive.
  for (int c = 0; c < 3; ++c) {
    Eigen::Index arg = 0;
    pca.components.col(c).cwiseAbs().maxCoeff(&arg);
    EXPECT_GT(pca.components(arg, c), 0.0);
  }
}

TEST(Pca, RejectsBadInput) {
  EXPECT_THROW(FitPca(Eigen::MatrixXd(1, 3), 0), InvalidInput);
  Eigen::MatrixXd x = Eigen::MatrixXd::Ones(4, 2);
  x(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(FitPca(x, 0), InvalidInput);
  EXPECT_THROW(FitPcaVariance(Eigen::MatrixXd::Random(5, 2), 0.0), InvalidInput);
  const Pca p = FitPca(Eigen::MatrixXd::Random(5, 2), 1);
  EXPECT_THROW(p.Project(Eigen::MatrixXd::Zero(2, 3)), InvalidInput);
  EXPECT_THROW(p.Reconstruct(Eigen::MatrixXd::Zero(2, 2)), InvalidInput);
}

}  // namespace
}  // namespace csw

// DCT-PLS fill (Garcia 2010): the DCT matrix, the direct solution with full
// data, the iteration's fixed point against a dense weighted solve, and gap
// fills of analytic signals.
#include "analysis/cleaning/dct_fill.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "core/error.h"

namespace csw::cleaning {
namespace {

TEST(CleaningDctFill, DctMatrixIsOrthonormalAndDiagonalisesTheReflectiveSecondDifference) {
  const int n = 17;
  const Eigen::MatrixXd c = DctMatrix(n);
  EXPECT_LT((c * c.transpose() - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-12);
  // Second differences with reflective ends: D = tridiag(1, -2, 1), D(0,0) = D(n-1,n-1) = -1.
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    d(i, i) = -2;
    if (i > 0) d(i, i - 1) = 1;
    if (i + 1 < n) d(i, i + 1) = 1;
  }
  d(0, 0) = d(n - 1, n - 1) = -1;
  const Eigen::MatrixXd lambda = c * d * c.transpose();
  for (int k = 0; k < n; ++k) EXPECT_NEAR(lambda(k, k), -2 + 2 * std::cos(k * M_PI / n), 1e-12);
  EXPECT_LT((lambda - Eigen::MatrixXd(lambda.diagonal().asDiagonal())).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_THROW(DctMatrix(0), InvalidInput);
}

// Dense weighted solve of Garcia's problem: (W + s DᵀD) z = W y, DᵀD = Cᵀ Λ² C.
Eigen::VectorXd DenseSolve(const Eigen::VectorXd& y, const Eigen::VectorXd& w, double s) {
  const int n = static_cast<int>(y.size());
  const Eigen::MatrixXd c = DctMatrix(n);
  Eigen::VectorXd l2(n);
  for (int k = 0; k < n; ++k) l2[k] = std::pow(-2 + 2 * std::cos(k * M_PI / n), 2);
  const Eigen::MatrixXd a = Eigen::MatrixXd(w.asDiagonal()) + s * c.transpose() * l2.asDiagonal() * c;
  return a.ldlt().solve(w.asDiagonal() * y);
}

TEST(CleaningDctFill, MissingFramesGiveTheWeightedPenalisedSolution) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.3);
  const int n = 70;
  Eigen::MatrixXd y(n, 1);
  Eigen::VectorXd w = Eigen::VectorXd::Ones(n);
  for (int i = 0; i < n; ++i) y(i, 0) = 40 * std::sin(i / 9.0) + 500 + noise(rng);
  // Full data: one direct step, equal to the dense solve.
  DctSmoothResult full = DctSmooth(y, w, 2.5);
  EXPECT_EQ(full.iterations[0], 1);
  EXPECT_LT((full.z.col(0) - DenseSolve(y.col(0), w, 2.5)).cwiseAbs().maxCoeff(), 1e-9);
  // Missing frames: the weighted solution (the limit of Garcia's iteration),
  // here against the dense solve built from the DCT eigenvalues.
  for (int i = 30; i < 42; ++i) w[i] = 0;
  for (double s : {0.5, 5.0, 50.0}) {
    DctSmoothResult r = DctSmooth(y, w, s, 5000, 1e-9);
    EXPECT_TRUE(r.converged) << s;
    EXPECT_LT((r.z.col(0) - DenseSolve(y.col(0), w, s)).cwiseAbs().maxCoeff(), 1e-5) << "s " << s;
  }
  EXPECT_THROW(DctSmooth(y, Eigen::VectorXd::Zero(n)), InvalidInput);
  EXPECT_THROW(DctSmooth(y, Eigen::VectorXd::Ones(n - 1)), InvalidInput);
}

TEST(CleaningDctFill, FillsASinusoidGapAndRemovesNoise) {
  const int64_t frames = 240;
  auto truth = [](double f, int c) { return 20 * std::sin(2 * M_PI * f / 120.0 + c) + 100.0 * c; };
  std::mt19937_64 rng(9);
  std::normal_distribution<double> noise(0.0, 0.2);
  MarkerArray clean(frames, 1), noisy(frames, 1);
  for (int64_t f = 0; f < frames; ++f)
    for (int c = 0; c < 3; ++c) {
      clean.at(f, 0)[c] = static_cast<float>(truth(static_cast<double>(f), c));
      noisy.at(f, 0)[c] = static_cast<float>(truth(static_cast<double>(f), c) + noise(rng));
    }
  for (int64_t f = 100; f < 110; ++f) {
    clean.SetMissing(f, 0);
    noisy.SetMissing(f, 0);
  }
  DctFiller dct;
  const Gap g = FindGaps(clean, 0).at(0);
  FillRecord rec;
  // Noise-free: the fill follows the sinusoid within 0.05 mm.
  MarkerArray out = clean;
  ASSERT_TRUE(dct.Fill(clean, g, &out, &rec));
  double e = 0;
  for (int64_t f = g.start; f < g.end(); ++f)
    for (int c = 0; c < 3; ++c) e = std::max(e, std::abs(out.at(f, 0)[c] - truth(static_cast<double>(f), c)));
  EXPECT_LT(e, 0.05) << rec.parameters;
  EXPECT_EQ(rec.method, "dct");
  EXPECT_NE(rec.parameters.find("Garcia"), std::string::npos);
  // 0.2 mm noise: the mean 3-D error of the fill stays below the noise alone (0.32 mm).
  out = noisy;
  ASSERT_TRUE(dct.Fill(noisy, g, &out, &rec));
  double sum = 0;
  for (int64_t f = g.start; f < g.end(); ++f) {
    double d2 = 0;
    for (int c = 0; c < 3; ++c) d2 += std::pow(out.at(f, 0)[c] - truth(static_cast<double>(f), c), 2);
    sum += std::sqrt(d2);
  }
  EXPECT_LT(sum / static_cast<double>(g.length), 0.3);
  // Leading gaps cannot be filled.
  MarkerArray lead = clean;
  for (int64_t f = 0; f < 3; ++f) lead.SetMissing(f, 0);
  std::string why;
  EXPECT_FALSE(dct.CanFill(lead, FindGaps(lead, 0).at(0), &why));
  EXPECT_EQ(why, "leading gap: no valid frame before it");
  DctFillOptions bad;
  bad.context_frames = 2;
  EXPECT_THROW(DctFiller{bad}, InvalidInput);
  // A gap too long for the matrix DCT is refused with the reason.
  DctFillOptions small;
  small.max_window_frames = 65;
  MarkerArray longer = clean;
  for (int64_t f = 90; f < 120; ++f) longer.SetMissing(f, 0);
  EXPECT_FALSE(DctFiller(small).CanFill(longer, FindGaps(longer, 0).at(0), &why));
  EXPECT_EQ(why, "gap of 30 frames too long for the DCT window of at most 65 frames");
}

}  // namespace
}  // namespace csw::cleaning

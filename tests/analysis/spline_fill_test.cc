// Spline fills on analytic signals: polynomials reproduced by the
// interpolating splines, the banded penalised solver against a dense solve,
// GCV against the known noise, a sinusoid gap.
#include "analysis/cleaning/spline_fill.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "core/error.h"

namespace csw::cleaning {
namespace {

// One marker whose coordinates are given functions of the frame number, with
// frames [gap_start, gap_start + gap_length) missing.
template <typename F>
MarkerArray Signal(int64_t frames, F f, int64_t gap_start, int64_t gap_length) {
  MarkerArray a(frames, 1);
  for (int64_t i = 0; i < frames; ++i) {
    const Eigen::Vector3d v = f(static_cast<double>(i));
    for (int c = 0; c < 3; ++c) a.at(i, 0)[c] = static_cast<float>(v[c]);
  }
  for (int64_t i = gap_start; i < gap_start + gap_length; ++i) a.SetMissing(i, 0);
  return a;
}

double MaxFillError(const MarkerArray& out, const Gap& g, const std::function<Eigen::Vector3d(double)>& truth) {
  double e = 0;
  for (int64_t i = g.start; i < g.end(); ++i) {
    const Eigen::Vector3d t = truth(static_cast<double>(i));
    for (int c = 0; c < 3; ++c) e = std::max(e, std::abs(out.at(i, 0)[c] - t[c]));
  }
  return e;
}

// Polynomials in t = frame − 50 with dyadic coefficients, so that every
// sample is exact in float32 and the fill error is that of the spline alone
// (plus the float rounding of the output: ulp ≤ 2e-6 mm below 32 mm).
Eigen::Vector3d Cubic(double f) {
  const double t = f - 50.0;
  return {10 + t / 4 - t * t / 8 + t * t * t / 64, -4 + t * t * t / 32, 25 - t / 2 + t * t / 16};
}
Eigen::Vector3d Quintic(double f) {
  const double t = f - 50.0;
  return {10 + t / 4 - std::pow(t, 4) / 1024 + std::pow(t, 5) / 4096, 2 + std::pow(t, 5) / 8192, -3 + t * t * t / 64};
}

TEST(CleaningSplineFill, InterpolatingCubicReproducesCubics) {
  const MarkerArray in = Signal(100, Cubic, 45, 10);
  SplineFillOptions o;
  o.kind = SplineKind::kCubic;
  SplineFiller s(o);
  const Gap g = FindGaps(in, 0).at(0);
  ASSERT_TRUE(s.CanFill(in, g, nullptr));
  MarkerArray out = in;
  FillRecord rec;
  ASSERT_TRUE(s.Fill(in, g, &out, &rec));
  EXPECT_LT(MaxFillError(out, g, Cubic), 5e-6);
  EXPECT_EQ(rec.method, "spline");
  EXPECT_NE(rec.parameters.find("cubic"), std::string::npos);
  // The cubic does not reproduce a quintic; the quintic does.
  const MarkerArray q = Signal(100, Quintic, 45, 10);
  MarkerArray out_c = q;
  ASSERT_TRUE(s.Fill(q, g, &out_c, &rec));
  EXPECT_GT(MaxFillError(out_c, g, Quintic), 1e-2);  // the quintic part is ~0.8 mm in the gap
  o.kind = SplineKind::kQuintic;
  SplineFiller s5(o);
  MarkerArray out_q = q;
  ASSERT_TRUE(s5.Fill(q, g, &out_q, &rec));
  EXPECT_LT(MaxFillError(out_q, g, Quintic), 5e-6);
}

TEST(CleaningSplineFill, SmoothingSplineReproducesItsNullSpaceAndFollowsASinusoid) {
  // A quadratic lies in the null space of the third-difference penalty: exact
  // whatever p (GCV then finds no residual).
  auto quadratic = [](double f) {
    const double t = f / 10.0;
    return Eigen::Vector3d(10 + t - 0.5 * t * t, 3 * t, -7 + 0.25 * t * t);
  };
  const MarkerArray in = Signal(120, quadratic, 50, 12);
  SplineFiller s;  // smoothing quintic, GCV
  const Gap g = FindGaps(in, 0).at(0);
  MarkerArray out = in;
  FillRecord rec;
  ASSERT_TRUE(s.Fill(in, g, &out, &rec));
  EXPECT_LT(MaxFillError(out, g, quadratic), 1e-4);
  EXPECT_NE(rec.parameters.find("kind=smoothing"), std::string::npos);
  // A 1 Hz sinusoid of 20 mm amplitude at 120 Hz, gap of 10 frames: the fill
  // is within 0.05 mm (the quintic's error on a smooth curve).
  auto sine = [](double f) {
    const double w = 2 * M_PI / 120.0;
    return Eigen::Vector3d(20 * std::sin(w * f), 20 * std::cos(w * f), 5 * std::sin(2 * w * f));
  };
  const MarkerArray sin_in = Signal(240, sine, 100, 10);
  const Gap gs = FindGaps(sin_in, 0).at(0);
  MarkerArray sin_out = sin_in;
  ASSERT_TRUE(s.Fill(sin_in, gs, &sin_out, &rec));
  EXPECT_LT(MaxFillError(sin_out, gs, sine), 0.05);
  SplineFillOptions o;
  o.kind = SplineKind::kCubic;
  MarkerArray cub_out = sin_in;
  ASSERT_TRUE(SplineFiller(o).Fill(sin_in, gs, &cub_out, &rec));
  EXPECT_LT(MaxFillError(cub_out, gs, sine), 0.05);
}

TEST(CleaningSplineFill, PenalisedSolveMatchesADenseSolveAndTheTrace) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  const int n = 40;
  Eigen::MatrixXd y(n, 2);
  Eigen::VectorXd w = Eigen::VectorXd::Ones(n);
  for (int i = 0; i < n; ++i) {
    y(i, 0) = std::sin(0.2 * i) * 5 + noise(rng);
    y(i, 1) = 0.01 * i * i + noise(rng);
  }
  for (int i = 15; i < 20; ++i) w[i] = 0;
  for (int m = 1; m <= 4; ++m) {
    const double p = 3.7;
    const PenalisedFit fit = PenalisedSmooth(y, w, m, p);
    // Dense reference: D the m-th difference matrix.
    Eigen::MatrixXd d = Eigen::MatrixXd::Identity(n, n);
    for (int k = 0; k < m; ++k) {
      Eigen::MatrixXd dk = Eigen::MatrixXd::Zero(d.rows() - 1, d.rows());
      for (int i = 0; i + 1 < d.rows(); ++i) {
        dk(i, i) = -1;
        dk(i, i + 1) = 1;
      }
      d = dk * d;
    }
    const Eigen::MatrixXd a = Eigen::MatrixXd(w.asDiagonal()) + p * d.transpose() * d;
    const Eigen::MatrixXd z = a.ldlt().solve(w.asDiagonal() * y);
    const Eigen::MatrixXd inv = a.inverse();
    const double trace = (inv * w.asDiagonal()).trace();
    EXPECT_LT((fit.z - z).cwiseAbs().maxCoeff(), 1e-9) << "order " << m;
    EXPECT_NEAR(fit.trace[0], trace, 1e-9) << "order " << m;
    EXPECT_EQ(fit.valid, n - 5);
  }
  EXPECT_THROW(PenalisedSmooth(y, Eigen::VectorXd::Ones(n - 1), 3), InvalidInput);
  Eigen::VectorXd few = Eigen::VectorXd::Zero(n);
  few[0] = few[1] = few[2] = 1;
  EXPECT_THROW(PenalisedSmooth(y, few, 3), InvalidInput);
}

TEST(CleaningSplineFill, GcvRemovesNoiseWithoutFlatteningTheSignal) {
  // Slow sinusoid plus 0.2 mm white noise: the GCV smoothing fit is closer to
  // the truth than the data, and its residual variance estimates the noise.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.2);
  const int n = 200;
  Eigen::MatrixXd y(n, 3), truth(n, 3);
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      truth(i, c) = 30 * std::sin(2 * M_PI * i / 120.0 + c);
      y(i, c) = truth(i, c) + noise(rng);
    }
  const Eigen::VectorXd w = Eigen::VectorXd::Ones(n);
  for (bool joint : {false, true}) {
    const PenalisedFit fit = PenalisedSmooth(y, w, 3, 0.0, joint);
    const double rms_data = std::sqrt((y - truth).squaredNorm() / (3.0 * n));
    const double rms_fit = std::sqrt((fit.z - truth).squaredNorm() / (3.0 * n));
    EXPECT_LT(rms_fit, 0.4 * rms_data) << joint;
    for (int c = 0; c < 3; ++c) {
      const double sigma2 = (y.col(c) - fit.z.col(c)).squaredNorm() / (n - fit.trace[c]);
      EXPECT_NEAR(std::sqrt(sigma2), 0.2, 0.03) << "column " << c;
      EXPECT_GT(fit.trace[c], 3.0);  // more than the null space (a quadratic)
      EXPECT_LT(fit.trace[c], 30.0);
    }
    if (joint) {
      EXPECT_EQ(fit.p[0], fit.p[2]);
    }
  }
}

TEST(CleaningSplineFill, CanFillSaysWhyNot) {
  MarkerArray in = Signal(
      40, [](double f) { return Eigen::Vector3d(f, 0, 0); }, 3, 4);
  for (int64_t f = 20; f < 30; ++f) in.SetMissing(f, 0);
  for (int64_t f = 36; f < 40; ++f) in.SetMissing(f, 0);
  SplineFillOptions o;
  o.max_gap_frames = 8;
  SplineFiller s(o);
  const std::vector<Gap> gaps = FindGaps(in, 0);
  ASSERT_EQ(gaps.size(), 3u);
  std::string why;
  EXPECT_FALSE(s.CanFill(in, gaps[0], &why));
  EXPECT_EQ(why, "3 valid frames before the gap, 5 needed");
  EXPECT_FALSE(s.CanFill(in, gaps[1], &why));
  EXPECT_EQ(why, "gap of 10 frames longer than the spline's maximum of 8 frames");
  EXPECT_FALSE(s.CanFill(in, gaps[2], &why));
  EXPECT_EQ(why, "trailing gap: no valid frame after it");
  MarkerArray out = in;
  FillRecord rec;
  EXPECT_FALSE(s.Fill(in, gaps[0], &out, &rec));
  o = SplineFillOptions();
  o.kind = SplineKind::kQuintic;
  o.side_frames = 2;
  EXPECT_THROW(SplineFiller{o}, InvalidInput);
  o = SplineFillOptions();
  o.context_frames = 3;
  EXPECT_THROW(SplineFiller{o}, InvalidInput);
}

}  // namespace
}  // namespace csw::cleaning

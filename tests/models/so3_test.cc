// models/so3: Exp against Eigen::AngleAxisd, the left Jacobian against central
// finite differences and a closed form, the small-angle series against
// long-double references on both sides of the threshold, and Log round trips
// up to and at π.
#include "models/so3.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <vector>

namespace csw {
namespace {

constexpr double kPi = std::numbers::pi;

double MaxAbs(const Eigen::Matrix3d& m) { return m.cwiseAbs().maxCoeff(); }

std::vector<Eigen::Vector3d> Axes() {
  return {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
          Eigen::Vector3d(1, 2, 3).normalized(), Eigen::Vector3d(-0.3, 0.9, -0.1).normalized()};
}

// Angles from 0 through the small-angle threshold (√1e-3 ≈ 0.0316) to π.
std::vector<double> Angles() {
  const double edge = std::sqrt(so3::kSo3SmallAngleSq);
  return {0.0,  1e-12, 1e-8, 1e-5, 1e-3, 0.01,       edge * (1 - 1e-9), edge * (1 + 1e-9),
          0.05, 0.3,   1.0,  2.0,  3.0,  kPi - 1e-4, kPi - 1e-8};
}

// sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³ by their power series in long double
// (30 terms: converged far below 1e-19 for θ ≤ π).
void ReferenceCoefficients(long double t, long double* a, long double* b, long double* c) {
  const long double t2 = t * t;
  long double term = 1.0L;  // (−θ²)^n / n!
  *a = *b = *c = 0.0L;
  for (int n = 0; n < 30; ++n) {
    if (n > 0) term *= -t2 / static_cast<long double>(n);
    // sin θ/θ = Σ (−θ²)^n/(2n+1)!, (1−cos θ)/θ² = Σ (−θ²)^n/(2n+2)!, (θ−sin θ)/θ³ = Σ (−θ²)^n/(2n+3)!
    long double f1 = 1.0L;
    for (int k = n + 1; k <= 2 * n + 1; ++k) f1 *= static_cast<long double>(k);  // (2n+1)!/n!
    *a += term / f1;
    *b += term / (f1 * static_cast<long double>(2 * n + 2));
    *c += term / (f1 * static_cast<long double>(2 * n + 2) * static_cast<long double>(2 * n + 3));
  }
}

TEST(So3, ExpEqualsEigenAngleAxis) {
  for (const Eigen::Vector3d& u : Axes()) {
    for (double t : Angles()) {
      SCOPED_TRACE("angle " + std::to_string(t));
      const Eigen::Matrix3d expected = Eigen::AngleAxisd(t, u).toRotationMatrix();
      EXPECT_LT(MaxAbs(so3::Exp(t * u) - expected), 1e-12);
      Eigen::Matrix3d r, jl;
      so3::ExpAndLeftJacobian(t * u, &r, &jl);
      EXPECT_LT(MaxAbs(r - expected), 1e-12);
      EXPECT_LT(MaxAbs(jl - so3::LeftJacobian(t * u)), 1e-15);
    }
  }
  EXPECT_EQ(so3::Exp(Eigen::Vector3d::Zero()), Eigen::Matrix3d::Identity());
  EXPECT_EQ(so3::LeftJacobian(Eigen::Vector3d::Zero()), Eigen::Matrix3d::Identity());
}

TEST(So3, HatIsTheCrossProduct) {
  const Eigen::Vector3d v(1.5, -2, 0.25), x(-3, 0.5, 7);
  EXPECT_LT((so3::Hat(v) * x - v.cross(x)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(so3::Hat(v).transpose(), -so3::Hat(v));
}

// Both sides of the threshold agree with the long-double series to 1e-14 in
// every entry, so switching formulas at θ² = 1e-3 leaves no step.
TEST(So3, SmallAngleSeriesAndClosedFormAgreeWithLongDoubleReference) {
  const Eigen::Vector3d u = Eigen::Vector3d(1, 2, 3).normalized();
  for (double t : Angles()) {
    SCOPED_TRACE("angle " + std::to_string(t));
    long double a, b, c;
    ReferenceCoefficients(t, &a, &b, &c);
    const Eigen::Matrix3d k = so3::Hat(t * u);
    const Eigen::Matrix3d r = Eigen::Matrix3d::Identity() + static_cast<double>(a) * k + static_cast<double>(b) * k * k;
    const Eigen::Matrix3d j = Eigen::Matrix3d::Identity() + static_cast<double>(b) * k + static_cast<double>(c) * k * k;
    EXPECT_LT(MaxAbs(so3::Exp(t * u) - r), 1e-14);
    EXPECT_LT(MaxAbs(so3::LeftJacobian(t * u) - j), 1e-14);
  }
}

// J_l about z in closed form: [[s/θ, −(1−c)/θ, 0], [(1−c)/θ, s/θ, 0], [0, 0, 1]].
TEST(So3, LeftJacobianAboutZMatchesClosedForm) {
  for (double t : {0.2, 1.0, 2.5}) {
    Eigen::Matrix3d expected;
    expected << std::sin(t) / t, -(1 - std::cos(t)) / t, 0,  //
        (1 - std::cos(t)) / t, std::sin(t) / t, 0,           //
        0, 0, 1;
    EXPECT_LT(MaxAbs(so3::LeftJacobian(t * Eigen::Vector3d::UnitZ()) - expected), 1e-14) << t;
  }
}

// exp(w + h eᵢ) ≈ exp(h J eᵢ) exp(w): column i of J is the vee of
// (Exp(w + h eᵢ) − Exp(w − h eᵢ)) / 2h · Exp(w)ᵀ, to O(h²) + O(ε/h) ≈ 1e-10.
TEST(So3, LeftJacobianMatchesCentralDifferences) {
  const double h = 1e-6;
  for (const Eigen::Vector3d& u : Axes()) {
    for (double t : {0.0, 1e-6, 0.02, 0.04, 0.7, 2.0, 3.0}) {
      const Eigen::Vector3d w = t * u;
      const Eigen::Matrix3d j = so3::LeftJacobian(w);
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(i);
        const Eigen::Matrix3d d = (so3::Exp(w + e) - so3::Exp(w - e)) / (2 * h) * so3::Exp(w).transpose();
        // d is skew to O(h²); its vee is the column.
        const Eigen::Vector3d col(0.5 * (d(2, 1) - d(1, 2)), 0.5 * (d(0, 2) - d(2, 0)), 0.5 * (d(1, 0) - d(0, 1)));
        EXPECT_LT((col - j.col(i)).cwiseAbs().maxCoeff(), 1e-8) << "angle " << t << " column " << i;
        EXPECT_LT(MaxAbs(d + d.transpose()), 1e-8);
      }
    }
  }
}

TEST(So3, LogInvertsExpUpToPi) {
  for (const Eigen::Vector3d& u : Axes()) {
    for (double t : Angles()) {
      SCOPED_TRACE("angle " + std::to_string(t));
      const Eigen::Vector3d w = t * u;
      const Eigen::Matrix3d r = Eigen::AngleAxisd(t, u).toRotationMatrix();
      // atan2(sin θ, cos θ) keeps the angle exact near 0 and π (acos of the
      // trace would lose half the digits there), and the axis comes from the
      // symmetric part above π/2.
      EXPECT_LT((so3::Log(r) - w).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT(MaxAbs(so3::Exp(so3::Log(r)) - r), 1e-12);
    }
  }
}

TEST(So3, LogAtExactlyPiReturnsEitherOppositeVector) {
  for (const Eigen::Vector3d& u : Axes()) {
    const Eigen::Matrix3d r = Eigen::AngleAxisd(kPi, u).toRotationMatrix();
    const Eigen::Vector3d w = so3::Log(r);
    EXPECT_NEAR(w.norm(), kPi, 1e-12);
    EXPECT_LT(std::min((w - kPi * u).norm(), (w + kPi * u).norm()), 1e-7);
    EXPECT_LT(MaxAbs(so3::Exp(w) - r), 1e-12);
  }
}

}  // namespace
}  // namespace csw

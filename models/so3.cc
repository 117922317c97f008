#include "models/so3.h"

#include <algorithm>
#include <cmath>

namespace csw::so3 {

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v(2), v(1),  //
      v(2), 0, -v(0),   //
      -v(1), v(0), 0;
  return m;
}

void ExpAndLeftJacobian(const Eigen::Vector3d& w, Eigen::Matrix3d* r, Eigen::Matrix3d* jl) {
  const double t2 = w.squaredNorm();
  const Eigen::Matrix3d k = Hat(w);
  const Eigen::Matrix3d k2 = k * k;
  double a, b, c;  // sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³
  if (t2 < kSo3SmallAngleSq) {
    const double t4 = t2 * t2;
    a = 1.0 - t2 / 6.0 + t4 / 120.0;
    b = 0.5 - t2 / 24.0 + t4 / 720.0;
    c = 1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0;
  } else {
    const double t = std::sqrt(t2);
    const double s = std::sin(t);
    a = s / t;
    b = (1.0 - std::cos(t)) / t2;
    c = (t - s) / (t2 * t);
  }
  if (r) *r = Eigen::Matrix3d::Identity() + a * k + b * k2;
  if (jl) *jl = Eigen::Matrix3d::Identity() + b * k + c * k2;
}

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) {
  Eigen::Matrix3d r;
  ExpAndLeftJacobian(w, &r, nullptr);
  return r;
}

Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& w) {
  Eigen::Matrix3d jl;
  ExpAndLeftJacobian(w, nullptr, &jl);
  return jl;
}

Eigen::Vector3d Log(const Eigen::Matrix3d& r) {
  // R − Rᵀ = 2 sin θ [u]×, tr R = 1 + 2 cos θ.
  const Eigen::Vector3d v(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));  // 2 sin θ u
  const double sin_t = 0.5 * v.norm();
  const double cos_t = std::clamp(0.5 * (r.trace() - 1.0), -1.0, 1.0);
  const double t = std::atan2(sin_t, cos_t);
  const double t2 = t * t;
  if (cos_t >= 0.0) {
    // θ < π/2: w = θ / (2 sin θ) · v, with sin θ / θ from its series for small θ.
    const double a = t2 < kSo3SmallAngleSq ? 1.0 - t2 / 6.0 + t2 * t2 / 120.0 : sin_t / t;
    return 0.5 / a * v;
  }
  // θ ≥ π/2: v loses the axis as θ → π; use the symmetric part instead,
  // (R + Rᵀ)/2 = I + b K² = cos θ I + (1 − cos θ) u uᵀ.
  const Eigen::Matrix3d uu = (0.5 * (r + r.transpose()) - cos_t * Eigen::Matrix3d::Identity()) / (1.0 - cos_t);
  int i = 0;
  uu.diagonal().maxCoeff(&i);
  Eigen::Vector3d u = uu.col(i) / std::sqrt(std::max(uu(i, i), 0.0));
  if (u.dot(v) < 0.0) u = -u;  // the sign of sin θ u
  return t * u.normalized();
}

}  // namespace csw::so3

#pragma once
// Rotations as rotation vectors (axis × angle, radians): the exponential and
// logarithm maps of SO(3) and the left Jacobian, one copy for every model that
// optimises a rotation (face and hand inversion).
//
//   Exp(w)          = I + a K + b K²,   K = Hat(w), θ = |w|
//   LeftJacobian(w) = I + b K + c K²    (exp(w + e) ≈ exp(LeftJacobian(w) e) exp(w))
//   a = sin θ / θ,  b = (1 − cos θ) / θ²,  c = (θ − sin θ) / θ³
//
// Small angles: below kSo3SmallAngleSq (θ² < 1e-3, θ < 0.0316 rad ≈ 1.8°) the
// coefficients come from their Taylor series to θ⁴. The threshold is where the
// two ways are equally good: the truncation error of the series is at most
// θ⁶/5040 ≈ 2e-13 (for a; 2.5e-14 for b, 2.8e-15 for c), and the rounding error
// of the closed forms, which subtract nearly equal numbers in 1 − cos θ and
// θ − sin θ, is about ε/θ² ≈ 2.2e-16/1e-3 ≈ 2e-13 for b and c. Either side of
// the threshold each coefficient is good to ~2e-13, and the matrices (where b
// and c multiply K², of size θ²) to better than 1e-15.
#include <Eigen/Core>

namespace csw::so3 {

inline constexpr double kSo3SmallAngleSq = 1e-3;

// The cross-product matrix: Hat(v) x = v × x.
Eigen::Matrix3d Hat(const Eigen::Vector3d& v);

// Rodrigues: the rotation by |w| about w / |w|.
Eigen::Matrix3d Exp(const Eigen::Vector3d& w);

// Exp(w) and, when jl is not null, LeftJacobian(w), sharing the coefficients.
void ExpAndLeftJacobian(const Eigen::Vector3d& w, Eigen::Matrix3d* r, Eigen::Matrix3d* jl);

Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& w);

// The rotation vector of a rotation matrix, with |w| in [0, π]. At exactly π
// either of the two opposite vectors may be returned. r must be orthonormal
// with determinant +1 (to rounding).
Eigen::Vector3d Log(const Eigen::Matrix3d& r);

}  // namespace csw::so3

#include "models/joint_angles.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace csw {

std::optional<SegmentFrame> FrameFromMarkers(const Eigen::Vector3d& origin, const Eigen::Vector3d& toward_x,
                                             const Eigen::Vector3d& in_plane) {
  if (!origin.allFinite() || !toward_x.allFinite() || !in_plane.allFinite()) return std::nullopt;
  const Eigen::Vector3d ax = toward_x - origin;
  const Eigen::Vector3d b = in_plane - origin;
  const double ax_norm = ax.norm();
  const double b_norm = b.norm();
  if (!(ax_norm > 0) || !(b_norm > 0)) return std::nullopt;
  const Eigen::Vector3d x = ax / ax_norm;
  const Eigen::Vector3d zz = x.cross(b / b_norm);  // |zz| = |sin(angle)|
  const double s = zz.norm();
  if (!(s >= 1e-9)) return std::nullopt;
  const Eigen::Vector3d z = zz / s;
  SegmentFrame frame;
  frame.rotation.col(0) = x;
  frame.rotation.col(1) = z.cross(x);
  frame.rotation.col(2) = z;
  frame.origin = origin;
  return frame;
}

double WrapAngle(double radians) {
  constexpr double kPi = std::numbers::pi;
  if (!std::isfinite(radians)) return radians;
  double r = std::remainder(radians, 2 * kPi);  // [−π, π]
  if (r <= -kPi) r += 2 * kPi;
  return r;
}

Eigen::Matrix3d RotationFromJointAngles(const JointAngles& angles) {
  return (Eigen::AngleAxisd(angles.flexion, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(angles.spread, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(angles.twist, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

JointAngles JointAnglesFromRotation(const Eigen::Matrix3d& r) {
  // R = Ry(a)·Rz(b)·Rx(c) has first column (ca·cb, sb, −sa·cb), second row
  // (sb, cb·cc, −cb·sc); at cb = 0 the (0,2) and (2,2) entries are sin and
  // cos of a ± c (sign of sb), so with c = 0 they give a.
  JointAngles out;
  const double cb = std::hypot(r(0, 0), r(2, 0));
  out.spread = std::atan2(r(1, 0), cb);
  if (cb < 1e-12) {
    out.gimbal_lock = true;
    out.twist = 0;
    out.flexion = WrapAngle(std::atan2(r(0, 2), r(2, 2)));
  } else {
    out.flexion = WrapAngle(std::atan2(-r(2, 0), r(0, 0)));
    out.twist = WrapAngle(std::atan2(-r(1, 2), r(1, 1)));
  }
  return out;
}

JointAngles RelativeJointAngles(const SegmentFrame& parent, const SegmentFrame& child) {
  return JointAnglesFromRotation(parent.rotation.transpose() * child.rotation);
}

}  // namespace csw

#pragma once
// Segment frames from marker triplets and joint angles between two segments
// (hand model, seed Gibert-Bailly-Elisei §3.2: "rotation, twisting, spreading").
//
// Frame convention (right-handed, axes are the columns of `rotation`, in world
// coordinates): x points from the origin marker toward the second marker (the
// segment's long axis), z is normal to the plane of the three markers
// (x × (third − origin), normalised), y = z × x lies in that plane.
//
// Joint angles: the child's orientation relative to its parent,
// R_rel = R_parentᵀ · R_child, is decomposed as the intrinsic Cardan sequence
// Y-Z-X:  R_rel = Ry(flexion) · Rz(spread) · Rx(twist).
//   flexion: about the parent's y axis (in the markers' plane, across the bone), (−π, π]
//   spread : about the once-rotated z axis (normal to the plane),               [−π/2, π/2]
//   twist  : about the child's own long axis x,                                (−π, π]
// Gimbal lock is at spread = ±π/2 (a finger abducted by 90°, which does not
// occur in practice); there twist is set to 0 and the whole rotation about the
// common axis is reported as flexion, with `gimbal_lock` set.
#include <Eigen/Core>
#include <optional>

namespace csw {

struct SegmentFrame {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // columns: x, y, z axes
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

// The frame of three markers, or nullopt when they do not define one: a
// non-finite coordinate, the second marker on the origin, or the three markers
// (nearly) collinear — |sin(angle at the origin)| < 1e-9.
std::optional<SegmentFrame> FrameFromMarkers(const Eigen::Vector3d& origin, const Eigen::Vector3d& toward_x,
                                             const Eigen::Vector3d& in_plane);

struct JointAngles {
  double flexion = 0;  // radians, (−π, π]
  double spread = 0;   // radians, [−π/2, π/2]
  double twist = 0;    // radians, (−π, π]
  bool gimbal_lock = false;
};

// Wraps an angle to (−π, π].
double WrapAngle(double radians);

// Ry(flexion) · Rz(spread) · Rx(twist).
Eigen::Matrix3d RotationFromJointAngles(const JointAngles& angles);

// Decomposes a rotation matrix (assumed orthonormal, det +1) into joint angles.
JointAngles JointAnglesFromRotation(const Eigen::Matrix3d& relative);

// Angles of `child` relative to `parent`: JointAnglesFromRotation(Rpᵀ·Rc).
JointAngles RelativeJointAngles(const SegmentFrame& parent, const SegmentFrame& child);

}  // namespace csw

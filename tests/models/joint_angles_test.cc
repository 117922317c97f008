#include "models/joint_angles.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace csw {
namespace {

constexpr double kPi = std::numbers::pi;

// Angular distance on the circle.
double AngleDiff(double a, double b) { return std::abs(WrapAngle(a - b)); }

Eigen::Matrix3d RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

// Markers that define `frame`: origin, a point on x, a point in the x-y plane.
struct Triplet {
  Eigen::Vector3d a, b, c;
};
Triplet MarkersOf(const SegmentFrame& f) {
  const Eigen::Vector3d x = f.rotation.col(0), y = f.rotation.col(1);
  return {f.origin, f.origin + 0.05 * x, f.origin + 0.03 * x + 0.04 * y};
}

TEST(JointAngles, FrameFromMarkersIsRightHandedAndAlignsWithMarkers) {
  const auto f = FrameFromMarkers({1, 2, 3}, {4, 2, 3}, {1, 5, 3});
  ASSERT_TRUE(f.has_value());
  EXPECT_LT((f->rotation - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  EXPECT_EQ((f->origin - Eigen::Vector3d(1, 2, 3)).norm(), 0.0);
}

TEST(JointAngles, DegenerateTripletsGiveNoFrame) {
  EXPECT_FALSE(FrameFromMarkers({0, 0, 0}, {0, 0, 0}, {0, 1, 0}).has_value());
  EXPECT_FALSE(FrameFromMarkers({0, 0, 0}, {1, 0, 0}, {2, 0, 0}).has_value());
  EXPECT_FALSE(FrameFromMarkers({0, 0, 0}, {1, 0, 0}, {0, 0, 0}).has_value());
  EXPECT_FALSE(FrameFromMarkers({0, 0, NAN}, {1, 0, 0}, {0, 1, 0}).has_value());
  EXPECT_FALSE(FrameFromMarkers({0, 0, 0}, {INFINITY, 0, 0}, {0, 1, 0}).has_value());
}

TEST(JointAngles, WrapAngleMapsToHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(WrapAngle(kPi), kPi);
  EXPECT_DOUBLE_EQ(WrapAngle(-kPi), kPi);
  EXPECT_NEAR(WrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(2 * kPi + 0.25), 0.25, 1e-12);
  EXPECT_NEAR(WrapAngle(-2 * kPi - 0.25), -0.25, 1e-12);
  EXPECT_NEAR(WrapAngle(-kPi + 1e-6), -kPi + 1e-6, 1e-12);
}

TEST(JointAngles, RecoversKnownAnglesFromMarkerFrames) {
  std::mt19937 rng(7);
  const double near_pi = kPi - 1e-7;
  const std::vector<JointAngles> cases = {{0.3, 0.2, -0.1, false},      {-1.2, -0.7, 0.4, false},
                                          {2.5, 1.4, -2.9, false},      {near_pi, 0.1, 0.2, false},
                                          {-near_pi, -0.1, 0.3, false}, {0.4, -0.2, near_pi, false},
                                          {-0.4, 0.3, -near_pi, false}, {kPi, 0.0, kPi, false},
                                          {-3.0, -1.5, 3.0, false},     {0.0, 0.0, 0.0, false}};
  for (const JointAngles& truth : cases) {
    SegmentFrame parent;
    parent.rotation = RandomRotation(rng);
    parent.origin = Eigen::Vector3d(0.1, -0.2, 0.3);
    SegmentFrame child;
    child.rotation = parent.rotation * RotationFromJointAngles(truth);
    child.origin = Eigen::Vector3d(0.4, 0.1, -0.2);
    const Triplet pm = MarkersOf(parent), cm = MarkersOf(child);
    const auto pf = FrameFromMarkers(pm.a, pm.b, pm.c);
    const auto cf = FrameFromMarkers(cm.a, cm.b, cm.c);
    ASSERT_TRUE(pf && cf);
    const JointAngles got = RelativeJointAngles(*pf, *cf);
    EXPECT_FALSE(got.gimbal_lock);
    EXPECT_LT(AngleDiff(got.flexion, truth.flexion), 1e-9) << truth.flexion;
    EXPECT_LT(std::abs(got.spread - truth.spread), 1e-9) << truth.spread;
    EXPECT_LT(AngleDiff(got.twist, truth.twist), 1e-9) << truth.twist;
    EXPECT_GT(got.flexion, -kPi);
    EXPECT_LE(got.flexion, kPi);
    EXPECT_GT(got.twist, -kPi);
    EXPECT_LE(got.twist, kPi);
  }
}

TEST(JointAngles, ExactPiIsReportedAsPlusPi) {
  const JointAngles got = JointAnglesFromRotation(RotationFromJointAngles({kPi, 0.0, 0.0, false}));
  EXPECT_NEAR(got.flexion, kPi, 1e-12);
  EXPECT_NEAR(got.spread, 0.0, 1e-12);
  EXPECT_NEAR(got.twist, 0.0, 1e-12);
}

TEST(JointAngles, GimbalLockKeepsTheRotation) {
  for (double sign : {1.0, -1.0}) {
    const JointAngles truth{0.7, sign * kPi / 2, -0.3, false};
    const Eigen::Matrix3d r = RotationFromJointAngles(truth);
    const JointAngles got = JointAnglesFromRotation(r);
    EXPECT_TRUE(got.gimbal_lock);
    EXPECT_EQ(got.twist, 0.0);
    EXPECT_NEAR(got.spread, sign * kPi / 2, 1e-9);
    // Only flexion ± twist is observable: the rebuilt rotation must match.
    EXPECT_LT((RotationFromJointAngles(got) - r).norm(), 1e-9);
    EXPECT_LT(AngleDiff(got.flexion, 0.7 + sign * -0.3), 1e-9);
  }
}

TEST(JointAngles, NearGimbalLockStillRebuildsTheRotation) {
  const JointAngles truth{1.1, kPi / 2 - 1e-7, 0.5, false};
  const Eigen::Matrix3d r = RotationFromJointAngles(truth);
  const JointAngles got = JointAnglesFromRotation(r);
  EXPECT_LT((RotationFromJointAngles(got) - r).norm(), 1e-9);
  EXPECT_NEAR(got.spread, truth.spread, 1e-8);
}

}  // namespace
}  // namespace csw

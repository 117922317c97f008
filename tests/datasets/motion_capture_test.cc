#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "datasets/capture.h"
#include "datasets/motion.h"

namespace csw {
namespace {

TEST(Motion, MinimumJerkProfile) {
  EXPECT_EQ(MinimumJerk(-1.0), 0.0);
  EXPECT_EQ(MinimumJerk(0.0), 0.0);
  EXPECT_DOUBLE_EQ(MinimumJerk(0.5), 0.5);
  EXPECT_EQ(MinimumJerk(1.0), 1.0);
  EXPECT_EQ(MinimumJerk(2.0), 1.0);
  EXPECT_DOUBLE_EQ(MinimumJerk(0.25), 10 * 0.015625 - 15 * 0.00390625 + 6 * 0.0009765625);
  EXPECT_DOUBLE_EQ(MinimumJerkRate(0.5), 1.875);  // peak speed 15/8 of the mean
  // Numerical derivative agrees.
  for (double t : {0.1, 0.3, 0.7, 0.9})
    EXPECT_NEAR(MinimumJerkRate(t), (MinimumJerk(t + 1e-6) - MinimumJerk(t - 1e-6)) / 2e-6, 1e-6);
}

TEST(Motion, SuperposedGesturesReachTheirTargetsWhenTheyDoNotOverlap) {
  Eigen::VectorXd x0(2);
  x0 << 1.0, -1.0;
  std::vector<Gesture> g = {{0.1, 0.4, Eigen::Vector2d(2.0, 0.0)}, {0.5, 0.7, Eigen::Vector2d(-1.0, 3.0)}};
  EXPECT_TRUE(Superpose(x0, g, 0.0).isApprox(x0));
  EXPECT_TRUE(Superpose(x0, g, 0.4).isApprox(Eigen::Vector2d(3.0, -1.0)));
  EXPECT_TRUE(Superpose(x0, g, 0.45).isApprox(Eigen::Vector2d(3.0, -1.0)));
  EXPECT_TRUE(Superpose(x0, g, 0.7).isApprox(Eigen::Vector2d(2.0, 2.0)));
  EXPECT_TRUE(Superpose(x0, g, 0.25).isApprox(Eigen::Vector2d(2.0, -1.0)));  // half way
  EXPECT_NEAR(SuperposeRate(g, 2, 0.25)[0], 2.0 * 1.875 / 0.3, 1e-9);
  // Overlapping gestures still end at the sum of the displacements.
  std::vector<Gesture> o = {{0.1, 0.4, Eigen::Vector2d(2.0, 0.0)}, {0.3, 0.6, Eigen::Vector2d(-1.0, 3.0)}};
  EXPECT_TRUE(Superpose(x0, o, 0.6).isApprox(Eigen::Vector2d(2.0, 2.0)));
}

TEST(Capture, SegmentDistanceKnownAnswers) {
  using V = Eigen::Vector3d;
  EXPECT_NEAR(SegmentDistance(V(0, 0, 0), V(10, 0, 0), V(5, -5, 3), V(5, 5, 3)), 3.0, 1e-12);  // crossing
  EXPECT_NEAR(SegmentDistance(V(0, 0, 0), V(10, 0, 0), V(0, 2, 0), V(10, 2, 0)), 2.0, 1e-12);  // parallel
  EXPECT_NEAR(SegmentDistance(V(0, 0, 0), V(1, 0, 0), V(4, 4, 0), V(4, 8, 0)), 5.0, 1e-12);    // end points
  EXPECT_NEAR(SegmentDistance(V(0, 0, 0), V(0, 0, 0), V(-1, 1, 0), V(1, 1, 0)), 1.0, 1e-12);   // a point
}

TEST(Capture, SegmentEllipsoidIntersection) {
  const Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d radii(10, 20, 30), c(0, 0, 0);
  EXPECT_TRUE(SegmentHitsEllipsoid({-50, 0, 0}, {50, 0, 0}, c, axes, radii));
  EXPECT_FALSE(SegmentHitsEllipsoid({-50, 0, 0}, {-20, 0, 0}, c, axes, radii));   // stops short
  EXPECT_FALSE(SegmentHitsEllipsoid({11, -50, 0}, {11, 50, 0}, c, axes, radii));  // passes beside x = 10
  EXPECT_TRUE(SegmentHitsEllipsoid({9, -50, 0}, {9, 50, 0}, c, axes, radii));
  EXPECT_TRUE(SegmentHitsEllipsoid({0, 0, 29}, {0, 0, 100}, c, axes, radii));  // starts inside
  // Rotated 90° about z: the long axis (20) is now along x.
  Eigen::Matrix3d rz = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(SegmentHitsEllipsoid({15, -50, 0}, {15, 50, 0}, c, rz, radii));
}

TEST(Capture, StandardNormalHasUnitMoments) {
  std::mt19937_64 rng(3);
  double s = 0, s2 = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    double x = StandardNormal(rng);
    s += x;
    s2 += x * x;
  }
  EXPECT_NEAR(s / n, 0.0, 0.01);
  EXPECT_NEAR(s2 / n, 1.0, 0.015);
}

}  // namespace
}  // namespace csw

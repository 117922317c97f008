#pragma once
// Smooth movement primitives of the virtual cuer: the minimum-jerk profile
// (Flash & Hogan) and a superposition of overlapping point-to-point gestures.
#include <Eigen/Core>
#include <vector>

namespace csw {

// s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ for τ in [0, 1], 0 before, 1 after.
double MinimumJerk(double tau);
// ds/dτ (zero outside [0, 1]).
double MinimumJerkRate(double tau);

// A point-to-point gesture: the value moves by `delta` between start_s and
// target_s along the minimum-jerk profile.
struct Gesture {
  double start_s = 0.0;
  double target_s = 0.0;
  Eigen::VectorXd delta;
};

// initial + Σ_k delta_k · s((t − start_k) / (target_k − start_k)). When the
// gestures do not overlap in time, each target is reached exactly at its
// target time and the speed profile of each gesture is single-peaked;
// overlapping gestures blend (coarticulation of the hand).
Eigen::VectorXd Superpose(const Eigen::VectorXd& initial, const std::vector<Gesture>& gestures, double t);
// Its time derivative.
Eigen::VectorXd SuperposeRate(const std::vector<Gesture>& gestures, Eigen::Index size, double t);

}  // namespace csw

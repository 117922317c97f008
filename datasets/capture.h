#pragma once
// Capture artefacts of the virtual cuer's takes: occlusions from the line of
// sight of virtual cameras (the hand hides face markers and vice versa; a marker
// is reconstructed when at least min_cameras cameras see it), dropped samples,
// Gaussian marker noise, optional label swaps. The clean positions stay in
// SimulationResult::clean and the mask in SimulationResult::state.
#include <Eigen/Core>
#include <random>
#include <vector>

namespace csw {

struct SimulateOptions;
struct SimulationResult;
class VirtualCuer;

struct CaptureSetup {
  std::vector<Eigen::Vector3d> cameras;  // lab positions (mm)
  int min_cameras = 2;
  double noise_mm = 0.2;
  bool occlusions = true;
  double dropouts_per_s = 0.0;
  bool label_swaps = false;
};

// Cameras on an arc in front of the cuer (radius 2.4 m, heights alternating).
CaptureSetup MakeCaptureSetup(const SimulateOptions& options);

// Shortest distance between segments [p0, p1] and [q0, q1].
double SegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                       const Eigen::Vector3d& q1);
// Whether segment [p0, p1] meets the ellipsoid {x : |diag(1/radii) R^T (x - c)| <= 1}.
bool SegmentHitsEllipsoid(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& centre,
                          const Eigen::Matrix3d& axes, const Eigen::Vector3d& radii);

// Fills result->state and result->take.markers from result->clean.
void ApplyCaptureArtefacts(const VirtualCuer& cuer, const CaptureSetup& setup, std::mt19937_64 rng,
                           SimulationResult* result);

// Normal deviate from a 64-bit generator (Box-Muller; portable, unlike
// std::normal_distribution).
double StandardNormal(std::mt19937_64& rng);

}  // namespace csw

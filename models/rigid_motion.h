#pragma once
// Rigid motion of a marker cluster (head, hand): closed-form Kabsch/Umeyama fit
// from any >= 3 visible markers, refined with a robust loss (Ceres) so that one
// mislabelled marker cannot tilt the cluster. Per-take series of 6 parameters
// (rotation vector rx ry rz in radians, translation tx ty tz in millimetres),
// and conversion of all markers to / from the cluster's own frame.
//
// Convention: observed = R * reference + t (reference in the cluster frame,
// observed in the lab frame). ToLocalFrame applies the inverse motion.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/progress.h"
#include "core/take.h"

namespace csw {

struct RigidTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  RigidTransform Inverse() const;
  // (rx, ry, rz, tx, ty, tz): angle-axis rotation vector (rad) and translation (mm).
  Eigen::Matrix<double, 6, 1> Parameters() const;
  static RigidTransform FromParameters(const Eigen::Matrix<double, 6, 1>& p);
};

enum class RobustLoss { kNone, kHuber, kCauchy };

struct RigidOptions {
  RobustLoss loss = RobustLoss::kCauchy;
  double loss_scale_mm = 1.0;  // residual norm where the robust loss starts to bend
  int max_iterations = 50;     // Ceres iterations of the robust refinement
};

struct RigidFit {
  bool valid = false;      // false with fewer than 3 usable, non-collinear markers
  bool converged = false;  // Ceres reported convergence (true for kNone: closed form)
  RigidTransform transform;
  double rms_mm = 0.0;                     // over the used markers
  Eigen::VectorXd per_marker_residual_mm;  // |R ref + t - obs|, NaN when not visible
  std::vector<int> used_markers;           // columns that were visible in both
};

// Closed-form least-squares fit (Kabsch, with the reflection fix) of
// observed ~ R * reference + t over the columns finite in both. No robust step.
RigidFit EstimateRigidKabsch(const Eigen::Matrix3Xd& reference, const Eigen::Matrix3Xd& observed);

// Kabsch start (and, with a robust loss and >= 4 markers, the best leave-one-out
// Kabsch start), then robust refinement with Ceres. Missing columns are NaN.
RigidFit EstimateRigid(const Eigen::Matrix3Xd& reference, const Eigen::Matrix3Xd& observed,
                       const RigidOptions& options = {});

// Mean shape of the cluster (columns of `markers`) over the frames where all of
// them are visible, expressed in its own centroid frame: generalised Procrustes
// (start from the first complete frame, align every complete frame to the
// current mean, average, re-centre; a few rounds), so head motion during the
// take does not blur the shape. Axes stay those of the first complete frame.
// Throws InvalidInput if fewer than 3 columns or no complete frame.
Eigen::Matrix3Xd ClusterReference(const MarkerArray& markers, const std::vector<int>& columns);

struct RigidSeries {
  std::vector<int> columns;        // cluster columns in the MarkerArray
  Eigen::Matrix3Xd reference;      // cluster shape, 3 x columns.size()
  Eigen::MatrixXd parameters;      // frames x 6 (rx ry rz tx ty tz); NaN rows when invalid
  Eigen::VectorXd rms_mm;          // frames; NaN when invalid
  Eigen::MatrixXd residual_mm;     // frames x columns.size(); NaN when not visible / invalid
  std::vector<uint8_t> valid;      // frames
  std::vector<uint8_t> converged;  // frames

  int64_t frames() const { return static_cast<int64_t>(valid.size()); }
  int64_t CountValid() const;
  RigidTransform Transform(int64_t frame) const;
  // The parameter rows of the valid frames (input for FitPca: motion control
  // parameters nmF/nmH are the PCA of this matrix).
  Eigen::MatrixXd ValidParameters() const;
};

// Fits every frame. progress may be null; Update throws Cancelled when asked.
RigidSeries EstimateRigidSeries(const MarkerArray& markers, const std::vector<int>& cluster_columns,
                                const Eigen::Matrix3Xd& reference, const RigidOptions& options = {},
                                Progress* progress = nullptr);

// All markers expressed in the cluster frame: p_local = R^T (p - t). Frames
// where the series is invalid become missing. Throws InvalidInput if the frame
// counts differ.
MarkerArray ToLocalFrame(const MarkerArray& markers, const RigidSeries& series);
// Inverse of ToLocalFrame: p = R p_local + t.
MarkerArray ToLabFrame(const MarkerArray& local, const RigidSeries& series);

}  // namespace csw

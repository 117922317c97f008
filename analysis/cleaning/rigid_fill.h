#pragma once
// Rigid-cluster gap fill (Vicon Nexus "rigid body fill", QTM "rigid body / virtual fill"):
// a missing marker of a rigid cluster is rebuilt, frame by frame, from the cluster's visible
// markers through the cluster's reference shape.
//
// - Reference shape: generalised Procrustes analysis without scale (Gower 1975,
//   Psychometrika 40:33-51) over the frames where all (or, failing that, most) cluster markers
//   are seen; each frame is aligned to the current consensus by Umeyama's least-squares rigid
//   fit, and the new consensus is the coordinate-wise MEDIAN of the aligned frames (not the
//   mean), so spikes and short label swaps in a few frames do not move it. Iterated to
//   convergence.
// - Pose of a gap frame: Umeyama (1991, IEEE TPAMI 13:376-380; the Kabsch rotation with the
//   reflection guard), without scale, Eigen::umeyama, from the visible neighbours' reference
//   coordinates to their captured positions; the missing marker is the pose applied to its
//   reference coordinates.
// - Conditioning: with per-coordinate noise σ at the neighbours, the linearised least-squares
//   fit gives the filled marker the covariance σ² (I/k + [q]x J⁻¹ [q]xᵀ), q its reference
//   offset from the neighbours' centroid, J = Σ(|p|² I − p pᵀ) the neighbours' inertia tensor.
//   The "error gain" is sqrt(trace/3) (predicted RMS error per coordinate in units of σ); the
//   smallest eigenvalue of J is the sum of squared distances of the neighbours from their
//   principal line (0 when collinear). Frames with too small an off-line spread or too large a
//   gain are refused, with the reason.
// The clusters are columns given by the caller (the job layer maps the marker set's
// head_cluster, forearm_cluster and named groups to columns); nothing here knows marker names.
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/cleaning/fill.h"
#include "analysis/cleaning/gaps.h"
#include "core/take.h"

namespace csw::cleaning {

struct RigidFillOptions {
  // Visible neighbours (cluster markers other than the filled one) needed at every gap frame.
  int min_visible = 3;
  // Refuse a gap when, at some gap frame, the RMS residual of the visible neighbours about the
  // fitted reference exceeds this (the cluster is not rigid there: skin motion, a swap, a spike).
  double max_residual_mm = 2.0;
  // Refuse a frame whose neighbours lie within this RMS distance of one line (collinear).
  double min_off_line_mm = 1.0;
  // Refuse a frame where the fit would amplify the neighbours' noise more than this at the
  // filled marker (see above; on the virtual cuer: 0.4-0.9 with a whole 10-marker head cluster,
  // median 1.3 and up to 11 over its 3-marker subsets).
  double max_error_gain = 3.0;
  // Reference estimation: frames used (evenly spread over the take when more qualify), frames
  // each marker must be seen in to get a reference position, GPA iterations and tolerance.
  int max_reference_frames = 2000;
  int min_reference_frames = 10;
  int max_iterations = 20;
  double tolerance_mm = 1e-4;
};

// A cluster's reference shape, in its own frame (origin at the centroid of the markers that have
// a reference position).
struct ClusterReference {
  std::vector<int> columns;  // take columns of the cluster's markers
  Eigen::Matrix3Xd shape;    // 3 × columns.size(), mm; NaN column = no reference for that marker
  std::string problem;       // "" when the reference is usable, else why not
  int64_t frames_used = 0;   // frames that entered the estimate
  int min_visible_used = 0;  // frames used had at least this many cluster markers visible
  int iterations = 0;
  double median_residual_mm = 0.0;  // per-frame RMS residual of the used frames about the reference
  double p95_residual_mm = 0.0;
  bool Has(int column) const;     // column is in the cluster and has a reference position
  int IndexOf(int column) const;  // position in columns, or -1
};

// Estimates the reference shape of the cluster `columns` (≥ 3 distinct columns of `in`) from
// `in`. Throws InvalidInput for bad columns; a cluster that cannot be estimated (too few frames)
// comes back with `problem` set.
ClusterReference EstimateClusterReference(const MarkerArray& in, const std::vector<int>& columns,
                                          const RigidFillOptions& options = {});

// The rigid fit of one frame from the visible cluster markers other than `exclude` (-1: none).
struct RigidFrameFit {
  bool ok = false;
  std::string why_not;                                     // when !ok
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // reference -> lab
  int visible = 0;                                         // neighbours used
  double rms_residual_mm = 0.0;                            // of the neighbours about the fit
  double off_line_mm = 0.0;                                // neighbours' RMS distance from their principal line
  double error_gain = 0.0;                                 // predicted noise gain at `exclude` (0 when exclude = -1)
};
RigidFrameFit FitClusterFrame(const MarkerArray& in, const ClusterReference& ref, int64_t frame, int exclude,
                              const RigidFillOptions& options = {});

// Per-frame RMS fit residual of all visible cluster markers (mm); NaN where the frame cannot be
// fitted (< 3 visible, collinear). A large value flags a frame where the cluster is not rigid.
std::vector<double> ClusterResiduals(const MarkerArray& in, const ClusterReference& ref,
                                     const RigidFillOptions& options = {});

// Per-gap summary of a rigid fill (also what CanFill checks).
struct RigidGapFit {
  std::string why_not;                     // "" when every gap frame can be filled
  std::vector<Eigen::Vector3d> positions;  // one per gap frame, when why_not is ""
  std::vector<double> residual_mm;         // per gap frame (NaN where the fit failed)
  int min_visible = 0;
  double max_residual_mm = 0.0;
  double max_error_gain = 0.0;
};
// Fits every frame of the gap; stops at the first frame that cannot be filled (why_not names
// the frame and the reason). Throws InvalidInput when the gap lies outside `in`.
RigidGapFit FitRigidGap(const MarkerArray& in, const ClusterReference& ref, const Gap& gap,
                        const RigidFillOptions& options = {});

// Free-function fill: writes the gap frames of gap.marker into *out (same shape as in). Returns
// "" on success, else the reason (and *out is untouched).
std::string RigidFillGap(const MarkerArray& in, const ClusterReference& ref, const Gap& gap, MarkerArray* out,
                         const RigidFillOptions& options = {}, RigidGapFit* fit = nullptr);

// The GapFiller for the FillGaps driver ("rigid"). A marker in several clusters is tried in each
// cluster in order; the first that can fill the gap does.
class RigidClusterFiller : public GapFiller {
 public:
  RigidClusterFiller(std::vector<ClusterReference> clusters, RigidFillOptions options = {});
  // Estimates the reference of every cluster (lists of columns) from `in`.
  static RigidClusterFiller FromMarkers(const MarkerArray& in, const std::vector<std::vector<int>>& clusters,
                                        const RigidFillOptions& options = {});

  std::string name() const override { return "rigid"; }
  bool CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const override;
  bool Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const override;

  const std::vector<ClusterReference>& clusters() const { return clusters_; }
  const RigidFillOptions& options() const { return options_; }

 private:
  // Index of the first cluster that can fill the gap (and its fit), or -1 with the reasons.
  int Choose(const MarkerArray& in, const Gap& gap, RigidGapFit* fit, std::string* why_not) const;

  std::vector<ClusterReference> clusters_;
  RigidFillOptions options_;
};

}  // namespace csw::cleaning

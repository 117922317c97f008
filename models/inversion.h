#pragma once
// Common pieces of model inversion (issue 4 §5): options, the per-frame result
// and error statistics. The face (face_model.h) and hand (hand_model.h) models
// each provide Invert*: for every frame, the cluster pose (6) and the shape
// parameters are estimated together from the visible markers by nonlinear
// least squares (ceres::TinySolver, Levenberg-Marquardt, analytic Jacobian),
// warm-started from the previous solved frame; every model marker is then
// reconstructed, so missing samples get a value.
//
// "Model-ordered" marker arrays: models never see a take's own column order.
// The caller (workbench/jobs) binds the marker set and passes, per take, a
// MarkerArray whose columns are the model's markers in the model's order
// (cluster markers first, then shape markers; see each model's layout).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/take.h"

namespace csw {

struct InversionOptions {
  int max_iterations = 30;  // Levenberg-Marquardt iterations per frame
  bool warm_start = true;   // start from the previous solved frame
  // Tikhonov prior on the shape parameters, as a weight in mm per unit of
  // parameter (parameters are normalised to unit sd on the training frames):
  // adds residuals prior_mm · p_k. Keeps frames with few visible markers from
  // running away; 0 disables.
  double prior_mm = 0.05;
  // Hand: fill markers missing from a frame with the model's Gaussian gap
  // filler (HandModel::fill) when it has one; false = the shape model's prediction.
  bool gaussian_fill = true;
  // Frames with fewer visible cluster markers than this, or fewer visible
  // shape markers than min_shape_markers, are not solved (NaN rows).
  int min_cluster_markers = 3;
  int min_shape_markers = 3;
};

// How one frame's solve ended (InversionResult::status).
enum class FrameStatus : uint8_t {
  kTooFewMarkers = 0,  // fewer visible cluster or shape markers than the options ask: not solved
  kNoStart,            // the cold start failed (the cluster's Kabsch fit was degenerate): not solved
  kFailed,             // the solve ended with non-finite values: not solved
  kConverged,          // solved; the solver stopped on a tolerance before its iteration limit
  kMaxIterations,      // solved; the solver hit its iteration limit
};

// "too_few_markers", "no_start", "failed", "converged", "max_iterations".
const char* FrameStatusName(FrameStatus status);

struct InversionResult {
  Eigen::MatrixXd pose;       // frames × 6: rx ry rz (rad) tx ty tz (mm), cluster frame → lab; NaN when unsolved
  Eigen::MatrixXd params;     // frames × P shape parameters; NaN when unsolved
  MarkerArray reconstructed;  // frames × model markers (cluster then shape), lab mm; NaN when unsolved
  // frames × model markers: |reconstructed − observed| in mm where the input
  // sample is visible, NaN elsewhere (missing input or unsolved frame).
  Eigen::MatrixXd error_mm;
  std::vector<uint8_t> solved;     // frames
  std::vector<uint8_t> converged;  // frames: the solver reported convergence
  // Per frame, how the solve went (filled by InvertFace and InvertHand):
  std::vector<FrameStatus> status;  // frames; solved ⇔ kConverged or kMaxIterations
  // Levenberg-Marquardt iterations of the kept solve, as ceres::TinySolver
  // counts them (Summary::iterations: 0 when the start already met a
  // tolerance); 0 when not solved.
  std::vector<int32_t> iterations;
  // The kept solve started cold (cluster Kabsch + shape from the visible
  // markers) rather than from the previous frame: first frame, after an
  // unsolved frame, without warm_start, or a cold retry that won.
  std::vector<uint8_t> cold_start;
  // A warm start ended above the model's retry threshold and the frame was
  // solved again from a cold start, keeping the better (hand only; the face
  // never retries).
  std::vector<uint8_t> cold_retry;
  // Sizes every per-frame vector (status kTooFewMarkers, all else 0).
  void ResizeFrames(int64_t frames);
  int64_t frames() const { return static_cast<int64_t>(solved.size()); }
};

// Error statistics of absolute errors: count, mean, sample sd and max of the
// finite samples added, mergeable (Chan et al.'s pairwise update), so per-take
// statistics pool into per-role and overall ones exactly as if every sample
// had been added to one accumulator. The one implementation used by the model
// jobs (workbench/jobs) and SummariseErrors. Non-finite samples are ignored.
struct ErrorStats {
  int64_t count = 0;  // finite samples
  double mean = 0;    // mean absolute error (mm, or the caller's unit)
  double sd = 0;      // sample sd (divisor count − 1; 0 when count < 2), kept current by Add and Merge
  double max = 0;     // largest sample (0 when count == 0)
  double m2 = 0;      // sum of squared deviations from the mean (for merging)

  void Add(double x);
  void Merge(const ErrorStats& other);
};

// Absolute errors kept whole, for exact percentiles, with their ErrorStats.
// Merge appends, so pooled percentiles are those of all the samples.
struct ErrorSamples {
  ErrorStats stats;
  std::vector<double> values;  // finite samples, in the order added

  void Add(double x);
  void Merge(const ErrorSamples& other);
  // Percentile (0..100) by linear interpolation between closest ranks: with
  // the n samples sorted, x[0..n-1], h = (n − 1)·percent/100 and the result
  // x[⌊h⌋] + (h − ⌊h⌋)·(x[⌊h⌋+1] − x[⌊h⌋]) (numpy's default, Hyndman & Fan
  // type 7); 0 = min, 100 = max. NaN when empty.
  double Percentile(double percent) const;
};

// The same percentile of any list of values (non-finite ones ignored).
double Percentile(std::vector<double> values, double percent);

// Statistics of the finite entries of error_mm restricted to the given columns
// (empty = all columns) and rows [first, first + count) (count < 0 = to the end).
ErrorStats SummariseErrors(const Eigen::MatrixXd& error_mm, const std::vector<int>& columns = {}, int64_t first = 0,
                           int64_t count = -1);

// Marker arrays (frames × markers) → per-sample Euclidean distance (mm),
// NaN where either is missing. Throws InvalidInput on a shape mismatch.
Eigen::MatrixXd MarkerDistances(const MarkerArray& a, const MarkerArray& b);

}  // namespace csw

namespace csw {

// Temporal correction of the reconstruction inside gaps. The model's misfit
// (observed − reconstructed) of a marker changes slowly: it is the part of the
// posture or articulation the model's few parameters do not capture. For every
// run of frames where a marker is missing from `input` but reconstructed, the
// misfit just before the run and just after it (each the mean over up to 8
// visible frames, so one sample's noise is not copied) is interpolated
// linearly across the run and added to the reconstruction (one
// edge only: that edge's misfit, fading linearly to zero over fade_frames).
// Returns the number of samples corrected. Throws InvalidInput on a shape
// mismatch.
int64_t CorrectGapsWithEdgeResiduals(const MarkerArray& input, InversionResult* result, int64_t fade_frames = 60);

}  // namespace csw

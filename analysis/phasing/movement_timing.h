#pragma once
// Kinematic onset and target of hand movements (issue 11, scope item 5a;
// docs/analysis-phasing.md). A feature trajectory (the placement fingertip in the
// head frame, the seven hand distances, any frames × dimensions array sampled at
// rate_hz, NaN = missing) moves from one key's target to the next. Each movement
// is fitted by a superposition of minimum-jerk gestures, as the virtual cuer and
// Flash & Hogan's model produce them:
//   x(t) = c + Σ_k Σ_{p=1..P} β_kp · s((t − onset_k) / (target_k − onset_k))^p
// with s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ (0 before, 1 after). The onset and target times
// are the nonlinear parameters (Levenberg-Marquardt); c and β are solved by
// linear least squares for every trial of the times (variable projection), per
// dimension over that dimension's finite samples. P = 1 fits a straight path
// (the exact model of a minimum-jerk movement); P = 2 or 3 lets every dimension
// follow a curved path (features that are nonlinear functions of the moving
// joints: use P = 3 for the hand distances). Three gestures are fitted together — the movement
// into the previous target, this movement, and the next one — so movements that
// overlap (the next starting before the previous target) are separated.
// Unlike a fraction-of-peak-speed threshold (16–24 ms late at onset and early at
// target), the fit is unbiased on minimum-jerk movements (tests: |mean bias| < 5 ms).
// Pure computation: no files; bad options throw csw::InvalidInput.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace csw::phasing {

// A trajectory: row f is the sample at start_s + f / rate_hz; NaN = missing.
struct SampledTrajectory {
  const Eigen::MatrixXd* samples = nullptr;  // frames × dimensions (not owned)
  double rate_hz = 0.0;
  double start_s = 0.0;
  int64_t frames() const { return samples ? samples->rows() : 0; }
  double Time(int64_t frame) const { return start_s + static_cast<double>(frame) / rate_hz; }
};

struct MovementFitOptions {
  int path_terms = 1;            // P: 1 = straight path, 2 = curved path per dimension
  double min_duration_s = 0.04;  // bounds of each gesture's duration
  double max_duration_s = 1.2;
  // How far the onset and the target may move from their first guesses.
  double max_shift_s = 0.35;
  // Below this endpoint change (norm over the dimensions, feature units) a
  // movement counts as "no change" and is left out (moved = false).
  double min_amplitude = 4.0;
  int max_iterations = 60;
  // Data fitted: from lookback_s before the previous target to
  // target + lookahead_fraction · (next target − target).
  double lookback_s = 0.12;
  // How far each fitted target may lie from its rough time (the rough times'
  // accuracy: labels, posterior peaks).
  double target_tolerance_s = 0.08;
  // EstimateMovements: passes that refit each movement with its neighbours
  // started from their own estimates.
  int refinement_passes = 1;
  double lookahead_fraction = 0.5;
  // EstimateMovements: the window of movement i reaches back at least this far
  // before its rough target (gestures into the earlier targets of that stretch
  // are fitted with it), so that an early onset lies inside the data. Movements
  // of overlapping keys often start 200-400 ms before the previous target.
  // Off by default: on the virtual cuer it did not lower the placement-onset
  // bias and made the 3-term shape fits ten times slower
  // (docs/analysis-phasing.md).
  double onset_window_s = 0.0;
  // Quality gate: a moved estimate whose onset or target standard error
  // (MovementEstimate::onset_sd_s, target_sd_s) exceeds this is flagged
  // determined = false (reason "undetermined"). Infinity = no gate.
  double max_time_sd_s = std::numeric_limits<double>::infinity();
  // The gate above holds at this capture rate and tightens by
  // sqrt(reference / rate) above it: the standard errors shrink with the
  // number of samples, the trade between overlapping gestures does not (at
  // 240 Hz the 8 ms gate of csw phasing let through placement onsets 11 ms
  // late on average, 6 ms with this). Below it the gate stays as it is
  // (loosened at 60 Hz, the onsets came out 13 ms late, sd 59 ms).
  // 0 = the gate at every rate as given. docs/analysis-phasing.md.
  double time_sd_reference_rate_hz = 120.0;
  std::string Check() const;  // "" when valid, else the reason
};

struct MovementEstimate {
  bool fitted = false;     // false when the window holds too few samples
  bool moved = false;      // fitted and amplitude >= min_amplitude
  bool converged = false;  // the Levenberg-Marquardt steps became negligible
  // false when moved but the onset or target standard error exceeds
  // MovementFitOptions::max_time_sd_s (reason "undetermined"): overlapping
  // gestures can trade parts of their movements and the data fit equally well.
  bool determined = true;
  bool Usable() const { return moved && determined; }
  double onset_s = 0.0;    // movement start (same clock as the trajectory)
  double target_s = 0.0;   // movement end (target reached)
  double amplitude = 0.0;  // |x(after) − x(before)| of this gesture, feature units
  double rms_residual = 0.0;
  // Standard errors of onset_s and target_s (s) from the fit's curvature: large
  // when overlapping gestures can trade parts of their movements (the data do
  // not determine the onset). NaN when not fitted.
  double onset_sd_s = std::numeric_limits<double>::quiet_NaN();
  double target_sd_s = std::numeric_limits<double>::quiet_NaN();
  int64_t samples = 0;  // finite values used (frames × dimensions)
  std::string reason;   // why not fitted / not moved ("" otherwise)
};

// The movement that reaches its target near `target_s`, coming from the
// previous key's target near `previous_target_s` and followed by the next key's
// movement towards `next_target_s` (the three are rough times: labels, posterior
// peaks, or the expected key times; previous < target < next). The data from
// previous_target_s − lookback_s to target_s + lookahead_fraction ·
// (next_target_s − target_s) are fitted with three gestures (into previous,
// this, next; a neighbour is dropped when BIC says it does not move), each
// target within target_tolerance_s of its rough time. Throws InvalidInput for
// bad options or unordered times.
MovementEstimate EstimateMovement(const SampledTrajectory& trajectory, double previous_target_s, double target_s,
                                  double next_target_s, const MovementFitOptions& options = {});

// EstimateMovement with any number of gestures: the rough targets of the
// gestures fitted together (increasing), the measured one at index `central`
// (at least 1: the gesture into the previous target comes first), the data
// from data_start_s to data_end_s. The other gestures are dropped by BIC when
// they do not move, as EstimateMovement's neighbours. E.g. a take's last
// movement, which no movement follows: {previous, target}, central 1, the
// data to the end of the hold. Throws InvalidInput for bad options, unordered
// times or an empty window.
MovementEstimate EstimateMovementAmong(const SampledTrajectory& trajectory, const std::vector<double>& rough_targets_s,
                                       size_t central, double data_start_s, double data_end_s,
                                       const MovementFitOptions& options = {});
// Every movement of a sequence of rough target times (increasing): element i
// (i = 1 .. n−1) is the movement from target i−1 to target i; element 0 is not
// fitted (reason "first target"). The last movement is fitted without a next
// gesture (none follows), on data up to half an interval past its target.
// After the first pass (EstimateMovement on each window), refinement_passes
// refit every movement with its neighbours started from their own estimates
// and kept within 30 ms of them (neighbours estimated as still are left out):
// the recommended entry point.
std::vector<MovementEstimate> EstimateMovements(const SampledTrajectory& trajectory,
                                                const std::vector<double>& target_times_s,
                                                const MovementFitOptions& options = {});

// The standard-error limit of the quality gate on a trajectory sampled at
// rate_hz: max_time_sd_s, tightened by sqrt(time_sd_reference_rate_hz /
// rate_hz) above the reference rate (MovementFitOptions).
double EffectiveTimeSdLimit(const MovementFitOptions& options, double rate_hz);

// The fraction-of-peak-speed threshold (kept to compare: biased), in the window
// [from_s, to_s]: onset = first time before the speed peak where the speed
// exceeds fraction · peak, target = last time after it. Speeds from central
// differences; NaN frames skipped. fitted = false without a finite speed.
MovementEstimate ThresholdMovement(const SampledTrajectory& trajectory, double from_s, double to_s,
                                   double fraction = 0.2);

}  // namespace csw::phasing

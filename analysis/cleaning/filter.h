#pragma once
// Filtering of marker trajectories (issue 12, scope item 3; docs/cleaning-filter.md):
//   - a zero-phase low-pass Butterworth filter (forward-backward, like MATLAB/SciPy
//     filtfilt) whose cut-off is where the ZERO-PHASE response is -3 dB (half power),
//     corrected for the double pass as Winter describes;
//   - a Rauch-Tung-Striebel Kalman smoother per coordinate (constant velocity or
//     constant acceleration), measurement noise given or estimated from the data,
//     process noise given or estimated by maximum likelihood;
//   - speeds and accelerations by central differences on valid runs.
// Gaps (NaN samples) are respected everywhere: nothing is filtered across a
// missing sample and missing samples stay missing (unless a fill is asked for).
// Pure computation: no files, no printing; bad options throw csw::InvalidInput.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/take.h"

namespace csw::cleaning {

// A maximal run of valid (non-NaN) samples: [start, start + length).
struct SampleRun {
  int64_t start = 0;
  int64_t length = 0;
};

// The runs of valid samples of one channel (NaN = missing).
std::vector<SampleRun> ValidRuns(const std::vector<double>& x);
// The runs of frames where a marker is visible (all three coordinates finite).
std::vector<SampleRun> ValidRuns(const MarkerArray& markers, int64_t marker);

// ---------------------------------------------------------------------------
// Zero-phase Butterworth low-pass.

struct ButterworthOptions {
  // Frequency (Hz) at which the zero-phase (forward + backward) response is
  // -3 dB, i.e. amplitude 1/sqrt(2). Must be in (0, rate/2).
  double cutoff_hz = 15.0;
  // Order of the single-pass design: even, 2 to 8. The forward-backward
  // response has twice this order (order 2 = Winter's "2nd-order filter passed
  // twice", a 4th-order zero-lag filter; order 4 = scipy filtfilt(butter(4))).
  int order = 2;
};

// One second-order section, y[n] = b0 x[n] + b1 x[n-1] + b2 x[n-2] - a1 y[n-1] - a2 y[n-2].
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};

// Winter's correction factor for n_passes passes of a Butterworth filter of the
// given order: C = (2^(1/n_passes) - 1)^(1/(2 order)).
double ButterworthPassCorrection(int order, int n_passes = 2);
// The single-pass design frequency (Hz) such that the zero-phase response is
// -3 dB at options.cutoff_hz: tan(pi f_design / rate) = tan(pi f_c / rate) / C.
double ButterworthDesignFrequency(const ButterworthOptions& options, double rate_hz);
// The single-pass low-pass design (cascade of order/2 sections) by the bilinear
// transform with the design frequency pre-warped.
std::vector<Biquad> DesignButterworth(const ButterworthOptions& options, double rate_hz);
// The analytic amplitude gain of the zero-phase (double pass) filter at f_hz:
// |H(f)|^2 = 1 / (1 + (tan(pi f / rate) / tan(pi f_design / rate))^(2 order)).
double ZeroPhaseButterworthGain(const ButterworthOptions& options, double rate_hz, double f_hz);
// Odd reflection padding (samples) added at each end of a run: max(3 (order + 1),
// the samples for the slowest pole's transient to decay below 1e-6); a shorter run
// is padded by its length - 1. Runs shorter than ButterworthMinRunLength,
// 3 (order + 1) + 1 (SciPy filtfilt's minimum), are left unfiltered.
int64_t ButterworthPadding(const ButterworthOptions& options, double rate_hz);
int64_t ButterworthMinRunLength(const ButterworthOptions& options, double rate_hz);

// What a filter did: the runs it left unfiltered because they were too short.
struct FilterReport {
  struct Run {
    int64_t marker = -1;  // -1 for a single channel
    int64_t start = 0;
    int64_t length = 0;
  };
  int64_t min_run_length = 0;
  int64_t runs_filtered = 0;  // per channel (a marker's run counts once, not per coordinate)
  std::vector<Run> unfiltered;
};

// Filters one channel sampled at rate_hz. NaN samples are gaps: each run of
// valid samples is filtered on its own (odd reflection padding at both ends,
// steady-state initial conditions), missing samples stay NaN, runs shorter than
// ButterworthMinRunLength are copied unchanged and listed in the report.
// Throws InvalidInput for bad options or infinite samples.
std::vector<double> ButterworthFilter(const std::vector<double>& x, double rate_hz, const ButterworthOptions& options,
                                      FilterReport* report = nullptr);
Eigen::VectorXd ButterworthFilter(const Eigen::VectorXd& x, double rate_hz, const ButterworthOptions& options,
                                  FilterReport* report = nullptr);
// All markers, all three coordinates, run by run (a frame is valid when its three
// coordinates are finite; any other frame comes out missing).
MarkerArray ButterworthFilter(const MarkerArray& markers, double rate_hz, const ButterworthOptions& options,
                              FilterReport* report = nullptr);
// The same in place (no new frames x markers array: the cleaning job filters the
// take version it already owns).
void ButterworthFilterInPlace(MarkerArray& markers, double rate_hz, const ButterworthOptions& options,
                              FilterReport* report = nullptr);

// ---------------------------------------------------------------------------
// Kalman (Rauch-Tung-Striebel) smoother.

enum class MotionModel { kConstantVelocity, kConstantAcceleration };

struct KalmanOptions {
  MotionModel model = MotionModel::kConstantAcceleration;
  // Measurement noise sd (mm) per coordinate; 0 = estimated per coordinate
  // from the data (EstimateNoiseSd).
  double measurement_sd_mm = 0.0;
  // Spectral density of the white-noise driving term: acceleration for the
  // constant-velocity model (mm^2/s^3), jerk for constant acceleration
  // (mm^2/s^5). 0 = estimated per coordinate by maximum likelihood of the
  // innovations (channels longer than 12,000 samples: on 10 windows of 1,200).
  double process_noise = 0.0;
  // Fill the interior gaps with the smoothed prediction (default: they stay
  // missing). Leading and trailing gaps are never filled.
  bool fill_gaps = false;
};

// Difference-based estimate of the white measurement noise sd of a channel:
// robust scale (MAD / 0.6745) of the 4th-order differences within valid runs,
// divided by sqrt(70) (the norm of the binomial difference 1 -4 6 -4 1); the
// pseudo-residual estimators of Gasser, Sroka & Jennen-Steinmetz (1986) and
// Hall, Kay & Titterington (1990) with the MAD scale of Donoho & Johnstone
// (1994). Returns 0 when fewer than 5 valid consecutive samples exist.
double EstimateNoiseSd(const std::vector<double>& x);

struct KalmanChannel {
  std::vector<double> position;  // smoothed (NaN where missing, unless filled)
  std::vector<double> velocity;  // smoothed velocity (mm/s), same NaN pattern
  double measurement_sd = 0.0;   // used (given or estimated)
  double process_noise = 0.0;    // used (given or estimated)
};

// Smooths one channel (NaN = missing: prediction only there).
KalmanChannel KalmanSmooth(const std::vector<double>& x, double rate_hz, const KalmanOptions& options);
// All markers, all coordinates (each coordinate its own channel).
MarkerArray KalmanSmooth(const MarkerArray& markers, double rate_hz, const KalmanOptions& options);

// ---------------------------------------------------------------------------
// Speeds and accelerations (central differences; NaN at run ends and in gaps).

struct Kinematics {
  Eigen::MatrixXd speed;         // frames x markers (mm/s)
  Eigen::MatrixXd acceleration;  // frames x markers, magnitude (mm/s^2)
};
// Per marker: speed |p[i+1] - p[i-1]| / (2 dt) and acceleration magnitude
// |p[i+1] - 2 p[i] + p[i-1]| / dt^2, where frames i-1, i, i+1 are all visible.
Kinematics MarkerKinematics(const MarkerArray& markers, double rate_hz);

struct PointKinematics {
  Eigen::MatrixXd position;      // frames x 3: mean of the markers (NaN unless all visible)
  Eigen::VectorXd speed;         // mm/s
  Eigen::VectorXd acceleration;  // mm/s^2
};
// A point given as the mean of several markers (e.g. the hand), valid where all
// of them are visible (a mean over a changing subset would jump).
PointKinematics MeanPointKinematics(const MarkerArray& markers, const std::vector<int>& columns, double rate_hz);

}  // namespace csw::cleaning

#pragma once
// Face synthesis from fragments (seed-003: Edge et al., "concatenating small
// fragments of speech movements"), the alternative to the diphone Viterbi of
// synth/concatenation.h (issue 15 item 4):
//   1. greedy longest-match selection: from the first target phone, the
//      longest run of the dictionary's diphones that are consecutive in one
//      take and spell the target's next phones (a fragment of several phones,
//      up to a whole sentence), then on from its last phone; among fragments
//      of that length the one whose neighbouring phones in its take match the
//      target's context, then the one closest in phone durations;
//   2. time-warping to the target phone labels: piecewise linear through the
//      fragment's first and last phone middles and every phone boundary
//      inside it, so that each source boundary lands on the target's;
//   3. resampling to the uniform output frame rate: the warped samples are
//      scattered in time (those closer than half an output frame merged);
//      an inverse-multiquadric radial-basis interpolant with a linear
//      polynomial term passes through all of them and is read at the output
//      frames (or linear interpolation, for comparison);
//   4. blended overlaps: around each join (the middle of the phone two
//      fragments share) both fragments run on into the other's time — with
//      the take's neighbouring diphones as context, or their end value held —
//      and are blended with a weight g(u) falling smoothly from 1 to 0.
// A target diphone the dictionary never holds is a one-diphone fragment
// interpolated (minimum jerk) between the two phones' mean face parameters.
//
// Pure: no file I/O. Nothing depends on the virtual cuer's phones or rates.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "synth/concatenation.h"
#include "synth/dictionary.h"

namespace csw::dict {

enum class Resampling { kLinear, kRbf };
const char* ResamplingName(Resampling r);                      // "linear", "rbf"
bool ParseResampling(const std::string& name, Resampling* r);  // false when unknown

struct FragmentOptions {
  double rate_hz = 100;  // output frame rate
  Resampling resampling = Resampling::kRbf;
  // Inverse-multiquadric shape: φ(r) = 1 / sqrt(r² + c²), c = rbf_shape ×
  // the smallest spacing of the fragment's warped (merged) samples. Wide
  // bases follow a clean smooth curve closely but, like a high-degree
  // polynomial, swing on noisy samples; narrow ones dip between samples.
  // Measured: a 3 Hz sine sampled unevenly every ~26 ms, largest error 0.054
  // at c = 1 spacing, 0.035 at 2, 0.0073 at 4, 0.0005 at 8 (linear: 0.043);
  // the face parameters of 30 synthesised sentences (363 fragments), largest
  // overshoot beyond a fragment's sample range 8 % of that range at 1, 19 %
  // at 2, 78 % at 3, and at 4 seven fragments strayed (resampled linearly).
  double rbf_shape = 2.0;
  // Warp through every phone boundary (true) or stretch the fragment
  // uniformly between its end middles (false).
  bool align_phones = true;
  // Each join's overlap: this fraction of the shared phone's duration,
  // centred on its middle (0 = no blend: the later fragment takes over at
  // the middle). At most 1.
  double blend_fraction = 0.5;
  // Longest fragment in diphones (0 = no limit; 1 = diphone by diphone).
  int max_fragment_diphones = 0;
  std::string Check() const;  // "" or the reason
};

struct FragmentReport {
  std::string take;    // the source take ("" when interpolated)
  int first_slot = 0;  // the target diphones it covers: first_slot .. first_slot + slots - 1
  int slots = 0;
  std::vector<int> units;        // Dictionary::diphones indices, in order (empty when interpolated)
  bool interpolated = false;     // no unit held this diphone
  int context_matches = 0;       // neighbouring phones (0-2) equal to the target's
  double timing_rms_s = 0;       // RMS of the covered phones' duration mismatches
  bool linear_fallback = false;  // the RBF interpolant strayed (numerically): resampled linearly
  std::string phones;            // "p1 p2 ... pn"
};

struct FragmentTrack {
  double rate_hz = 0;
  Eigen::MatrixXd face_params;  // frames × Q, frames = round(duration · rate) + 1
  std::vector<FragmentReport> fragments;
  double mean_diphones_per_fragment() const;
  int64_t frames() const { return face_params.rows(); }
};

// Throws InvalidInput as ConcatenateDiphones for a dictionary without
// diphones, bad phones or times, and for options out of range.
FragmentTrack ConcatenateFragments(const Dictionary& dictionary, const std::vector<PhoneTarget>& phones,
                                   double duration_s, const FragmentOptions& options = {});

// The same track as ConcatenateDiphones returns (face_params, one report per
// phone succession: level kWhole when a fragment covers it, kInterpolated
// when none did, units = the unit used for it).
FaceTrack ToFaceTrack(const FragmentTrack& track, const std::vector<PhoneTarget>& phones);

// Resampling primitives (rows of `values` are samples at strictly
// increasing `times`; the result has one row per query time; a query
// outside [times.front(), times.back()] gets the nearest end sample).
Eigen::MatrixXd ResampleLinear(const Eigen::VectorXd& times, const Eigen::MatrixXd& values,
                               const Eigen::VectorXd& query);
// The inverse-multiquadric interpolant f(t) = a + b t + Σ α_i φ(|t − t_i|)
// with Σ α_i = Σ α_i t_i = 0, through every sample; shape c in seconds.
// Beyond kRbfBlock + 2 kRbfPad samples (a long fragment) the interpolant is
// local: the samples in blocks of kRbfBlock, each block's queries read from
// the interpolant through its samples and kRbfPad on each side (exact at
// every sample, continuous where blocks meet, cost linear in the samples).
inline constexpr Eigen::Index kRbfBlock = 128, kRbfPad = 64;
Eigen::MatrixXd ResampleRbf(const Eigen::VectorXd& times, const Eigen::MatrixXd& values, const Eigen::VectorXd& query,
                            double shape_s);

// The blend weight of the earlier fragment at u in [0, 1] of an overlap:
// 1 − MinimumJerk(u) (1 → 0, flat at both ends).
double BlendWeight(double u);

}  // namespace csw::dict

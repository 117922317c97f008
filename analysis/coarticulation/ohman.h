#pragma once
// Öhman's coarticulation model (MOTHER §5; docs/coarticulation.md): any
// articulatory parameter x of a VCV continuum is
//     p(x, t) = v(x, t) + k_c(t) · w_c(x) · [c(x) − v(x, t)]
// with v the "pure" vocalic gesture, c(x) the consonant's target, w_c(x) its
// coarticulation factor (1: the consonant imposes its own value whatever the
// vowel; 0: it takes the vowel's) and k_c(t) the consonant's emergence (1 at
// its maximum realisation).
//
// Fitting (FitOhman) works on parameter series (e.g. a face model's
// guided-PCA parameters, one row per frame) with their phone intervals:
//   1. vowel references v_V(x): the series at the centre of isolated vowels
//      (a vowel between pauses), or, when a vowel never occurs alone, the
//      mean at the centres of the vowels of its VCV tokens (biased towards
//      the consonants; a warning says so);
//   2. VCV tokens: V C V between pauses, the two vowels equal and in
//      options.vowels, C no vowel;
//   3. the consonant's maximum realisation in each token: the frame of the
//      consonant interval farthest from v_V (Σ_x ((p − v_V)/range_x)²),
//      averaged over ± realisation_window_s inside the interval;
//   4. per consonant and parameter, the line p_V = (1 − w) v_V + w c through
//      the contexts (least squares on the mean realisation per vowel): slope
//      1 − w, intercept a = w c; c = a / w where |w| ≥ min_w, else not
//      identifiable (NaN): the consonant effect w (c − v_V) = a − w v_V is
//      what is judged then. Where the vowels' values spread over less than
//      min_vowel_spread of the parameter's range the slope is not fitted
//      (w, c NaN; effect = measured). The RMS residual of the line is reported.
//   5. k(t) of every token between its two vowel centres: per parameter
//      (p − v_V) / (w (c − v_V)) where the fitted effect is at least
//      min_effect of the parameter's range, and pooled over every parameter
//      by least squares with range-normalised effects (VcvToken::k);
//   6. the stylised k_c(t) of each consonant (KStyle): a plateau of 1 on
//      [start + left_inset, end − right_inset] of the consonant interval with
//      raised-cosine flanks of widths left_ramp / right_ramp, fitted to the
//      pooled k of every token by weighted least squares (each flank on the
//      samples on its side of the consonant centre; grid search then a finer
//      grid) — the same as fitting K(t)·w(c − v_V) to the range-normalised
//      trajectories of every parameter at once.
//
// Generation (GenerateOhman): the vocalic carrier interpolates (minimum-jerk
// profile) between anchors at the vowel centres (vowel references) and the
// rest value in pauses; then, for every parameter, the consonants are added in
// increasing w order: p ← p + K(t) (a − w p), i.e. K w (c − p), which needs no
// c where c is not identifiable.
//
// Pure functions on in-memory data: no file I/O (the job reads takes).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/take.h"

namespace csw::coarticulation {

// Labels that mean a pause (silence): "", "_", "#", "sil", "sp", "pau", "<p:>".
bool IsPauseLabel(const std::string& text);

// One take's parameter series and phone intervals (IPA labels).
struct ParameterSeries {
  std::string name;           // for messages and reports
  double rate_hz = 0;         // frame rate
  Eigen::MatrixXd values;     // frames × parameters; rows with a non-finite value are ignored
  std::vector<Label> phones;  // phone intervals; gaps between them count as pauses
};

struct OhmanOptions {
  std::vector<std::string> vowels = {"a", "i", "u"};  // the symmetric contexts V
  double min_w = 0.1;                                 // |w| below: c(x) not identifiable
  // The contexts' vowel values must spread over at least this fraction of
  // the parameter's range for a slope (w) to be fitted; else w and c are
  // undefined (NaN) and the effect is the measured one.
  double min_vowel_spread = 0.05;
  double min_effect = 0.1;             // k from parameters whose fitted |w (c − v_V)| ≥ this × range
  double realisation_window_s = 0.02;  // averaging half-window around the maximum realisation
  double min_pause_s = 0.0;            // shorter gaps between phones are not pauses
  double k_grid_step_s = 0.005;        // time step of the mean k_c(t) curve
  std::string Check() const;           // "" or the reason
};

// The stylised emergence k_c(t) of a consonant with interval [start, end]:
//   left(t)  = 0 before start + left_inset − left_ramp, 1 after start + left_inset,
//              0.5 (1 − cos(π s)) in between (s = elapsed fraction of the ramp);
//   right(t) = the mirror image about end − right_inset;
//   K(t)     = min(left(t), right(t)).
struct KStyle {
  double left_inset_s = 0;
  double left_ramp_s = 0.05;
  double right_inset_s = 0;
  double right_ramp_s = 0.05;
  double rms = 0;   // RMS residual of the fit to the token samples
  int samples = 0;  // samples fitted
  double Evaluate(double t_s, double start_s, double end_s) const;
};

// Fits a KStyle to samples (t, k) of consonant intervals [start, end] by
// weighted least squares (weights empty = all 1): all vectors the same
// length. InvalidInput when sizes differ or no sample.
KStyle FitKStyle(const std::vector<double>& t_s, const std::vector<double>& start_s, const std::vector<double>& end_s,
                 const std::vector<double>& k, const std::vector<double>& weights = {});

// One V C V token.
struct VcvToken {
  int series = 0;  // index into the fitted series
  std::string vowel, consonant;
  double v1_centre_s = 0, c_start_s = 0, c_end_s = 0, v2_centre_s = 0;
  double realisation_s = 0;     // time of the maximum realisation
  Eigen::VectorXd realisation;  // p at the maximum realisation (P)
  // k(t) between the vowel centres, one sample per frame: times (take clock),
  // pooled k over every parameter with a non-zero effect (least squares on
  // the range-normalised deviations: k = Σ ê d̂ / Σ ê², NaN when no effect)
  // and its weight Σ ê² (the stylisation and the mean curve weigh samples by
  // it, so parameters with small effects, whose ratio is mostly noise, count
  // little), per parameter (samples × P, NaN where the effect is below
  // min_effect of the range).
  std::vector<double> k_times_s;
  std::vector<double> k;
  std::vector<double> k_weight;
  Eigen::MatrixXd k_per_parameter;
};

struct OhmanConsonant {
  std::string consonant;
  std::vector<std::string> vowels;  // contexts with at least one token, in options.vowels order
  int tokens = 0;
  Eigen::VectorXd w;          // P: coarticulation factor (NaN when the vowel values do not spread)
  Eigen::VectorXd intercept;  // P: a = w c
  Eigen::VectorXd c;          // P: target; NaN where |w| < min_w (not identifiable)
  Eigen::VectorXd residual;   // P: RMS residual of the line over the contexts
  // contexts × P: the fitted effect w (c − v_V) = a − w v_V, and the measured
  // one (mean realisation − v_V).
  Eigen::MatrixXd effect;
  Eigen::MatrixXd measured_effect;
  Eigen::MatrixXd realisation;  // contexts × P: mean realisation per context
  KStyle k_style;
  // Mean pooled k over the tokens (weighted by their k_weight) on a grid of
  // time relative to the consonant centre.
  std::vector<double> mean_k_times_s;
  std::vector<double> mean_k;
  bool Identifiable(int parameter) const;  // c(parameter) finite
};

struct OhmanFit {
  int num_parameters = 0;
  std::vector<std::string> vowels;         // options.vowels
  Eigen::MatrixXd vowel_targets;           // vowels × P: v_V
  std::vector<std::string> vowel_source;   // per vowel: "isolated", "vcv" or "none"
  std::vector<int> vowel_occurrences;      // per vowel: occurrences averaged
  Eigen::VectorXd rest;                    // P: mean at pause centres
  Eigen::VectorXd range;                   // P: max − min over every series frame
  std::vector<OhmanConsonant> consonants;  // in order of first appearance
  std::vector<VcvToken> tokens;
  std::vector<std::string> warnings;
  const OhmanConsonant* Find(const std::string& consonant) const;  // nullptr when absent
  int VowelIndex(const std::string& vowel) const;                  // -1 when absent
};

// Fits the model. InvalidInput (naming the series) on a bad rate, parameter
// counts that differ between series, no VCV token at all, or options that
// fail Check().
OhmanFit FitOhman(const std::vector<ParameterSeries>& series, const OhmanOptions& options = {});

struct GenerateOptions {
  // A pause longer than 2 × pause_inset_s + 0.04 s anchors the rest value
  // pause_inset_s inside each of its edges; a shorter one at its centre.
  double pause_inset_s = 0.06;
  double lead_s = 0.1;  // rest anchors this far outside the first and last phones
  // Phones the fit does not know (neither a vowel context nor a fitted
  // consonant nor a pause): false = InvalidInput; true = left out (no anchor,
  // no consonant effect).
  bool skip_unknown = false;
  std::string Check() const;
};

// Parameter trajectories (times × P) for phones (vowels of fit.vowels,
// consonants of fit.consonants, pauses) at the given times. InvalidInput
// naming the phone for a phone the fit does not know (unless skip_unknown).
Eigen::MatrixXd GenerateOhman(const OhmanFit& fit, const std::vector<Label>& phones, const std::vector<double>& times_s,
                              const GenerateOptions& options = {});

// The vocalic carrier v(x, t) alone (the first stage of GenerateOhman).
Eigen::MatrixXd OhmanCarrier(const OhmanFit& fit, const std::vector<Label>& phones, const std::vector<double>& times_s,
                             const GenerateOptions& options = {});

// Phones with the gaps filled by pause labels (""), sorted, over [0, end_s]
// (end_s ≤ 0: up to the last phone). Gaps shorter than min_pause_s are closed
// by stretching the previous phone.
std::vector<Label> NormalisePhones(std::vector<Label> phones, double end_s, double min_pause_s = 0.0);

}  // namespace csw::coarticulation

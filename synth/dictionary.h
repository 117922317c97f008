#pragma once
// Unit dictionaries of the text-to-cued-speech synthesizer (the seed's §5,
// issue 15): the dikey dictionary. A dikey is the movement between two
// successive keys of a take (rest 00 included at both ends), from the first
// key's target to the second's, multi-represented: hand-shape parameters,
// the forearm pose relative to the head and the head pose, per frame, as the
// inverted face and hand models give them, with the two key codes, times,
// duration and (when the take's keys can be matched to its phones) the
// phasing of the arriving key relative to its syllable.
//
// Pure: no file I/O. io/dictionary reads and writes dictionary files
// (docs/dictionary-format.md); workbench/jobs/dict_job builds them.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/labels.h"
#include "core/take.h"
#include "synth/cueing.h"

namespace csw {

struct FaceModel;
struct HandModel;

namespace dict {

// One take's inputs to the extraction, every per-frame series on the take's
// frame clock (row f = time f / rate_hz), NaN rows where the inversion did not
// solve the frame.
struct TakeSeries {
  std::string take;
  double rate_hz = 0;
  Eigen::MatrixXd hand_params;   // frames × P: the hand model's shape parameters
  Eigen::MatrixXd forearm_pose;  // frames × 6: forearm cluster → lab (rx ry rz rad, tx ty tz mm)
  Eigen::MatrixXd head_pose;     // frames × 6: head cluster → lab
  std::vector<KeyMark> keys;     // the key tier's marks, in time order
  // Acoustic onset (s) of the syllable each key codes, one per mark, NaN when
  // unknown (rests, or no phone tier): gives DikeyUnit::phasing_s.
  std::vector<double> syllable_onset_s;
  // The LfPC type of each mark's key (CV, lone V, lone C; kRest for rests),
  // one per mark, empty = unknown: gives DikeyUnit::to_type. A1 is the
  // consonant onset for CV and lone-C keys and the vowel onset for lone-V
  // keys, so phasing_s of different types are not comparable.
  std::vector<KeyType> key_type;
  // Placement target time (s) of each mark's key, one per mark, NaN when
  // unknown (empty = none known): the placement arrives after the shape
  // target the mark holds (the placement_targets tier). Gives the units'
  // placement lags.
  std::vector<double> placement_target_s;
  // For diphones: the face model's parameters (frames × Q; empty = no
  // diphones) and the phones, contiguous, in time order, label "_" = pause.
  Eigen::MatrixXd face_params;
  std::vector<Label> phones;
  std::string audio_path;  // the take's source WAV, "" when none
  int64_t frames() const { return hand_params.rows(); }
};

struct DikeyUnit {
  std::string take;
  int index = 0;            // the first key's index in the take's key list (after rests were added)
  KeyCode from;             // the key left
  KeyCode to;               // the key reached
  double start_s = 0;       // the first key's target time (take clock)
  double end_s = 0;         // the second key's target time
  int64_t first_frame = 0;  // take frame of row 0 of the series below: round(start_s · rate)
  double rate_hz = 0;
  // Rows = frames first_frame .. round(end_s · rate) inclusive.
  Eigen::MatrixXd hand_params;      // frames × P
  Eigen::MatrixXd forearm_in_head;  // frames × 6: forearm cluster frame in the head cluster frame
  Eigen::MatrixXd head_pose;        // frames × 6: head cluster → lab
  // The arriving key's target time minus the acoustic onset of its syllable
  // (s; negative = the hand arrives before the sound); NaN when unknown.
  double phasing_s = 0;
  // The arriving key's type (whose A1 phasing_s is measured from); empty when
  // unknown. One code may be of two types: shape 5 at a vowel placement is a
  // lone vowel or a CV key of [m t f].
  std::optional<KeyType> to_type;
  // Placement target minus shape target (s) of the key left and of the key
  // reached, NaN when unknown: the leaving key's placement arrives
  // from_placement_lag_s after the unit's first row (in its rows when
  // positive), the reached key's to_placement_lag_s after its last.
  double from_placement_lag_s = std::numeric_limits<double>::quiet_NaN();
  double to_placement_lag_s = std::numeric_limits<double>::quiet_NaN();
  double duration_s() const { return end_s - start_s; }
  int64_t frames() const { return hand_params.rows(); }
};

struct DikeyOptions {
  // Assume a rest 00 at the take's first frame when the first mark is not a
  // rest, and at its last frame when the last is not.
  bool add_rests = true;
  // A unit with more unsolved frames than this fraction is not kept (a badly
  // solved frame must not become a dictionary unit); 0 = every frame solved.
  double max_unsolved_fraction = 0.0;
  std::string Check() const;
};

// Why units were left out, counted.
struct ExtractionStats {
  int successions = 0;  // successive key pairs seen (units kept + rejected)
  int kept = 0;
  int rejected_unsolved = 0;  // too many unsolved frames
  int rejected_outside = 0;   // a target outside the take's frames
};

// The dikeys of one take, in time order. Throws InvalidInput naming the take
// when the series' sizes disagree, the rate is not positive, or a time is not
// finite; marks closer than one frame are kept (a unit of one frame).
std::vector<DikeyUnit> ExtractDikeys(const TakeSeries& series, const DikeyOptions& options = {},
                                     ExtractionStats* stats = nullptr);

// The key list the extraction uses: the marks with rests added as options say.
std::vector<KeyMark> KeysWithRests(const std::vector<KeyMark>& keys, double last_time_s, const DikeyOptions& options);

// Pose helpers (6-vectors rx ry rz tx ty tz): the pose of `b` in the frame of
// `a` (a⁻¹ ∘ b), NaN when either has a NaN.
Eigen::Matrix<double, 6, 1> RelativePose(const Eigen::Matrix<double, 6, 1>& a, const Eigen::Matrix<double, 6, 1>& b);

// A diphone: from the middle of one phone to the middle of the next (pauses
// "_" included, so that units leave and reach silence), with the face model's
// parameters per frame and a reference to the audio segment.
struct DiphoneUnit {
  std::string take;
  int index = 0;  // the first phone's index in the take's phones
  std::string phone1, phone2;
  double phone1_start_s = 0, phone1_end_s = 0;  // the phones' own intervals (take clock)
  double phone2_start_s = 0, phone2_end_s = 0;
  double start_s = 0, end_s = 0;  // the unit: middle of phone 1 to middle of phone 2
  int64_t first_frame = 0;        // round(start_s · rate)
  double rate_hz = 0;
  std::string audio_path;       // the take's source WAV ("" when none); the segment is [start_s, end_s]
  Eigen::MatrixXd face_params;  // frames × Q, rows = frames first_frame .. round(end_s · rate)
  double duration_s() const { return end_s - start_s; }
  int64_t frames() const { return face_params.rows(); }
};

// The diphones of one take (series.phones and series.face_params), in time
// order. Units with unsolved frames are left out as DikeyOptions says
// (counted in stats). Throws InvalidInput naming the take when face_params
// has another number of frames than the hand parameters, or the phones
// overlap or are out of order.
std::vector<DiphoneUnit> ExtractDiphones(const TakeSeries& series, const DikeyOptions& options = {},
                                         ExtractionStats* stats = nullptr);

// Distinct diphones "p1+p2" and their candidates, sorted.
std::vector<std::pair<std::string, int>> DiphoneCoverage(const std::vector<DiphoneUnit>& units);

struct Dictionary {
  std::string models_fingerprint;  // ModelsFingerprint of the models the parameters belong to
  // Provenance (as given to csw dict build; "" when unknown).
  std::string corpus, models_file, keys_file, key_tier;
  std::vector<std::string> hand_parameter_names;  // P
  std::vector<DikeyUnit> dikeys;
  std::vector<std::string> face_parameter_names;  // Q
  std::vector<DiphoneUnit> diphones;
  // The corpus's own continuity, for `csw say --check`: the 99th percentile
  // and the maximum of the frame-to-frame jumps (mm) of every model marker as
  // the models reconstruct the corpus's takes (solved frame pairs only), at
  // the corpus's frame rate; NaN when unknown (older files).
  double corpus_rate_hz = std::numeric_limits<double>::quiet_NaN();
  double corpus_p99_jump_mm = std::numeric_limits<double>::quiet_NaN();
  double corpus_max_jump_mm = std::numeric_limits<double>::quiet_NaN();
};

// Frame-to-frame jumps (mm) of every marker between successive frames where
// both samples are visible, appended to `jumps`.
void AppendMarkerJumps(const MarkerArray& markers, std::vector<double>* jumps);
// The q-quantile (0–1, linear interpolation) of `values` (reordered); NaN when empty.
double Quantile(std::vector<double>& values, double q);

// Coverage of successions: counts[from][to] of placement (6 × 6, 0 = rest /
// free space) and shape (9 × 9, 0 = rest) successions, of whole keys, and the
// possible successions missing (every ordered pair but 0 → 0).
struct Coverage {
  Eigen::MatrixXi placement = Eigen::MatrixXi::Zero(kMaxPlacement + 1, kMaxPlacement + 1);
  Eigen::MatrixXi shape = Eigen::MatrixXi::Zero(kMaxShape + 1, kMaxShape + 1);
  std::vector<std::pair<std::string, int>> dikeys;  // ("PS-PS", count), sorted by code
  int units = 0;
  std::vector<std::pair<int, int>> MissingPlacements() const;
  std::vector<std::pair<int, int>> MissingShapes() const;
};

Coverage CoverageOfUnits(const std::vector<DikeyUnit>& units);
// The coverage a corpus's own key lists call for (every succession of the
// lists, rests added as options say): what a complete dictionary holds.
Coverage CoverageOfKeys(const std::vector<std::vector<KeyMark>>& key_lists, const std::vector<double>& last_times_s,
                        const DikeyOptions& options = {});

// "PS-PS" of a succession.
std::string SuccessionCode(const KeyCode& from, const KeyCode& to);

// SHA-256 (hex) of the models' parameter arrays: the face model's head
// reference, shape mean and loadings, and the hand model's forearm reference,
// angle PCA, regression coefficients and parameter scale (sizes included);
// either may be null. The same models give the same fingerprint whatever file
// holds them.
std::string ModelsFingerprint(const FaceModel* face, const HandModel* hand);

// Throws InvalidInput "<where>: the dictionary was built with models
// <dict>, not with <models> (...)" when the fingerprints differ.
void CheckModelsMatch(const Dictionary& dictionary, const std::string& fingerprint, const std::string& where);

}  // namespace dict
}  // namespace csw

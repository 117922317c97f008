#pragma once
// Selection and concatenation of dictionary units (the seed's §5.1, issue 15
// item 4): dynamic programming over the multi-represented dikeys of a
// Dictionary (hand shape, forearm-in-head and head pose trajectories) and over
// its diphones (face parameters), each chosen unit linearly time-warped onto
// its slot, with a documented fallback chain when a succession is missing and
// the seed's anticipatory smoothing (each boundary jump spread linearly over
// the previous unit). docs/synthesis.md describes the costs and the chain.
//
// Pure: no file I/O. Everything (parameter scales, class means, the closeness
// of placements) is learned from the dictionary itself; nothing depends on
// the virtual cuer's marker names or proportions.
#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/labels.h"
#include "synth/dictionary.h"

namespace csw::dict {

// An intended key and its target time (s) on the output clock; a sequence
// holds rest 00 at both ends and strictly increasing times.
struct KeyTarget {
  KeyCode code;
  double target_s = 0;
  // The acoustic onset of the key's syllable (output clock; NaN: unknown,
  // rests) and the key's type: ConcatOptions::movement_onsets plans each
  // movement's onset from them.
  double a1_s = std::numeric_limits<double>::quiet_NaN();
  std::optional<KeyType> type = std::nullopt;
};

struct ConcatOptions {
  double rate_hz = 100;  // output frame rate
  // Selection cost weight × RMS duration mismatch (s): one duration for a
  // whole dikey, the two streams' for a two-stream dikey, the two half-phone
  // durations for a diphone.
  double selection_weight = 1.0;
  // Concatenation cost weight × weighted RMS jump across a boundary, each
  // parameter divided by its standard deviation over the dictionary's frames.
  double concatenation_weight = 1.0;
  // Per-parameter weights (e.g. the variance each explains): hand_weights
  // has one per hand parameter (forearm-in-head and head pose columns weigh
  // 1 each), face_weights one per face parameter; empty = all 1.
  Eigen::VectorXd hand_weights, face_weights;
  // Target cost weight × how far from its key class a candidate puts the
  // hand at the key it leaves (the posture the rendered track holds at that
  // key's target: the smoothing moves the previous unit's end onto it) and,
  // for the last slot, at the key it reaches: the RMS standardised distance
  // of the hand parameters from the shape's mean plus that of the
  // forearm-in-head pose from the placement's mean, both means over every
  // unit's key instants. A unit cut where the cuer only approached a key
  // (fast syllables) is then chosen only when nothing better is there.
  // 0 = off (the seed's costs alone).
  double target_weight = 0.0;
  bool smoothing = true;  // anticipatory smoothing of every boundary jump
  // Highest fallback level allowed (FallbackLevel, 0-3); a slot that needs a
  // higher one throws InvalidInput.
  int max_fallback_level = 3;
  // Two-stream and half-unit candidates: at most this many units per stream
  // (the closest in duration), so a slot has at most its square.
  int max_stream_candidates = 8;
  // Largest time compression of a dikey unit: a unit longer than
  // max_compression × its slot shows only its last max_compression × slot
  // seconds (its start — the leaving key's hold and the slow start of the
  // movement — is trimmed, the smoothing absorbing the difference), so that
  // no movement runs much faster than the corpus ever made it. 0 = never
  // trim (every unit warped whole onto its slot).
  double max_compression = 1.25;
  // Keep each stream's movements at their own duration (false: every unit
  // is warped linearly onto its slot, its start trimmed as above). The hand
  // shape stream (hand parameters) and the pose stream (forearm-in-head,
  // with the head) of a unit are warped apart. Each first arrives at its
  // leaving key (the pose stream until from_placement_lag_s when that is
  // positive; the shape stream starts there), holds it, then moves: the
  // movement starts at the last frame before the stream's peak speed (after
  // the arrival) whose speed, averaged over 5 frames, is at most a tenth of
  // that peak. A stream whose key component does not change only holds.
  // Arrival and movement keep their durations, the movement ending at the
  // slot's end; the hold fills what is left, stretched, or compressed at
  // most max_compression times with its middle cut beyond. A slot shorter
  // than arrival and movement cuts the hold and compresses both (at most
  // max_compression times, the start trimmed beyond). Measured on the 30
  // held-out sentences (docs/synthesis.md): lone consonants' shape onsets
  // move from 49 ms to 18 ms early against the corpus's, but the p99
  // marker jump rises from 16.9 to 17.4 mm (the bar: 17.0), as movements
  // the linear warp stretched keep their speed; hence off by default.
  bool keep_movement_duration = false;
  // Movement onsets from the units' own phasing (exclusive with
  // keep_movement_duration). In each stream (hand shape; forearm-in-head
  // with the head) whose key component changes, the unit's movement (from
  // its onset, found as for keep_movement_duration, to its end) is laid
  // linearly from a planned onset to the arriving key's target, the
  // leaving key's arrival and hold before it. The planned onset is the
  // arriving key's A1 (KeyTarget::a1_s) plus the unit's own onset phasing:
  // DikeyUnit::phasing_s minus the movement's duration, i.e. where the
  // movement started relative to its syllable in the corpus. It is kept
  // late enough that the movement is compressed at most max_compression
  // times. When it falls before the slot's start, the movement overlaps the
  // previous slot, as a cuer's does: its displacement from the posture
  // where it starts is added to the previous slot's frames from the onset
  // on. The overlap is at most max_onset_overlap × the previous slot (an
  // earlier onset is moved there; a slot whose compressed movement would
  // need more is warped as without this option). Units of another key type
  // than the planned key's, keys without A1 and unknown phasing: as without
  // it. Measured on 30 held-out sentences (docs/synthesis.md), 0.3: lone-C
  // shape onsets 49 -> 30 ms early against the corpus's, CV placement onsets
  // 34 -> 31 ms late, key accuracy 95.4 -> 95.7 %; but the CV placement
  // targets 2 ms further from the corpus's (to its 20 ms bar); off by default.
  bool movement_onsets = false;
  double max_onset_overlap = 0.3;
  // A trimmed unit still starts at its leaving key's posture: the trimmed
  // part's offset is added back, fading linearly to 0 over the slot, so
  // the key is reached at its frame and the movement that follows is
  // compressed into the rest of the slot. false (default): the slot starts
  // where the trimmed unit does, part of the way to the next key, and the
  // leaving key is only approached (the smoothing moves the previous unit's
  // end there). On 30 held-out sentences (docs/synthesis.md) true reads
  // 92.8 % of the keys instead of 89.6 %, but moves the CV placement
  // target 4 ms earlier, 20.6 ms from the corpus's (the bar: 20).
  bool trim_keeps_key_posture = false;
  // Key posture pull: at each key's frame, the hand (shape parameters and
  // forearm-in-head pose together) is compared with the instances of that
  // key code in the dictionary (units' first and last rows), in the code's
  // own standard deviations (each at least a tenth of the parameter's spread
  // over all frames; RMS over the P + 6 values). Farther than posture_radius
  // from the code's mean, it is moved toward the code's exemplar — the
  // instance nearest that mean, a real posture whose shape and pose belong
  // together — until it is posture_radius from the exemplar. The
  // corrections are blended between successive keys' frames by minimum-jerk
  // ramps, so each key keeps its frame and the slots carry the difference.
  // Codes with fewer than posture_min_instances instances are left as they
  // are. 0 = off. Why the exemplar and not the mean: a placement is where
  // the fingertip lands, which depends on the forearm's rotation and
  // translation and the wrist together; their means, taken apart, are no
  // posture the cuer makes (pulling onto the means read 64 % of the
  // placements instead of 89 %; docs/synthesis.md).
  double posture_radius = 0.0;
  int posture_min_instances = 5;
  std::string Check() const;  // "" or the reason
};

// How a dikey slot k_i → k_{i+1} was filled.
enum class FallbackLevel {
  kWhole = 0,             // units with both key codes
  kClosestPlacement = 1,  // the seed's: the arriving key's placement replaced by the closest present
  kTwoStreams = 2,        // hand shape from the shape succession, forearm/head from the placement succession
  kInterpolated = 3,      // minimum-jerk interpolation between the two keys' class means
};
const char* FallbackLevelName(FallbackLevel level);  // "whole", "closest placement", ...

// One slot: the arriving key (code, target time), the level used and the
// dictionary indices used (Dictionary::dikeys): one unit for levels 0 and 1,
// {shape unit, pose unit} for level 2, none for level 3.
struct KeyReport {
  KeyCode code;
  double target_s = 0;
  FallbackLevel level = FallbackLevel::kWhole;
  std::vector<int> units;
  KeyCode used_to;  // level 1: the arriving code of the unit used (placement replaced); else = code
  // When the slot's pose unit reaches the key it leaves's placement, after
  // the slot's start (s, output clock): the unit's from_placement_lag_s
  // through the slot's warp (0 when trimmed away; unwarped when negative,
  // i.e. the placement arrived first). NaN when unknown (no lag stored,
  // level 3).
  double leaving_placement_lag_s = std::numeric_limits<double>::quiet_NaN();
};

// ConcatOptions::posture_radius, per key: the rendered posture's distance
// from its code's mean before the pull (NaN: fewer instances than
// posture_min_instances, or no pull asked) and whether it was moved.
struct KeyPosture {
  double distance = std::numeric_limits<double>::quiet_NaN();
  bool pulled = false;
};

struct HandTrack {
  double rate_hz = 0;
  // frames = round(duration_s · rate) + 1, row f = time f / rate.
  Eigen::MatrixXd hand_params;       // frames × P
  Eigen::MatrixXd forearm_in_head;   // frames × 6 (rx ry rz rad, tx ty tz mm)
  Eigen::MatrixXd head_pose;         // frames × 6 (head → lab)
  std::vector<KeyReport> keys;       // one per slot (per arriving key), in order
  std::vector<KeyPosture> postures;  // one per key (rest keys included), in order; empty without the pull
  double total_cost = 0;             // of the selected path (selection + concatenation terms)
  int64_t frames() const { return hand_params.rows(); }
};

// Selects and concatenates dikeys for `keys` (≥ 2, times strictly
// increasing in [0, duration_s]). Slot i runs from key frame
// F_i = round(t_i · rate) to F_{i+1}; its unit is warped linearly so that its
// first row lands on F_i and its last row on F_{i+1} (the frame F_{i+1}
// belongs to slot i). Before F_0 and after the last key the end values are
// held. Throws InvalidInput naming the problem for an empty dictionary, bad
// times or NaN, weights of the wrong size, a key whose shape or placement the
// dictionary never holds (when level 3 is needed) or a slot needing a level
// above options.max_fallback_level.
HandTrack ConcatenateDikeys(const Dictionary& dictionary, const std::vector<KeyTarget>& keys, double duration_s,
                            const ConcatOptions& options = {});

// A phone of the target utterance, contiguous with the previous, "_" = pause.
struct PhoneTarget {
  std::string phone;
  double start_s = 0, end_s = 0;
};

// How a diphone slot was filled.
enum class DiphoneLevel {
  kWhole = 0,      // units with both phones
  kHalfUnits = 1,  // phone 1's second half from a unit with that phone1, phone 2's first half from one with that phone2
  kInterpolated = 2,  // minimum-jerk interpolation between the two phones' mean face parameters
  kUnknownPhone = 3,  // as 2, a phone the dictionary never holds replaced by the mean of all phone middles
};

struct DiphoneReport {
  std::string phone1, phone2;
  double start_s = 0, end_s = 0;  // the target phones' middles
  DiphoneLevel level = DiphoneLevel::kWhole;
  std::vector<int> units;  // Dictionary::diphones indices: {unit} or {left, right} or {}
};

struct FaceTrack {
  double rate_hz = 0;
  Eigen::MatrixXd face_params;            // frames × Q
  std::vector<int> fallback_per_diphone;  // = int(diphones[i].level)
  std::vector<DiphoneReport> diphones;    // one per phone succession
  double total_cost = 0;
  int64_t frames() const { return face_params.rows(); }
};

// Selects and concatenates diphones for `phones` (≥ 2, contiguous, in
// order, within [0, duration_s]). Slot j runs from the middle of phone j to
// the middle of phone j+1 and is warped piecewise linearly so that the
// unit's phone boundary lands on the target's boundary too. Throws as
// ConcatenateDikeys (no diphones, bad times, NaN, weights' size).
FaceTrack ConcatenateDiphones(const Dictionary& dictionary, const std::vector<PhoneTarget>& phones, double duration_s,
                              const ConcatOptions& options = {});

// Checks a target phone list (at least two, contiguous, each longer than 0,
// within [0, duration_s]) and returns the phones' middles; throws
// InvalidInput naming the phone.
std::vector<double> PhoneMiddles(const std::vector<PhoneTarget>& phones, double duration_s);
// Throws InvalidInput naming the unit when the dictionary has no diphone, or
// one whose face parameters have another size, or values or times that are
// not finite.
void CheckDiphoneUnits(const Dictionary& dictionary);

// Minimum-jerk blend 10u³ − 15u⁴ + 6u⁵ of u in [0, 1] (0 → 0, 1 → 1, zero
// velocity and acceleration at both ends).
double MinimumJerk(double u);

}  // namespace csw::dict

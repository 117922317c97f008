#pragma once
// The text-to-cued-speech synthesizer (issue 15 item 5, the seed's §5): an
// utterance's phones and audio (synth/phonetics: espeak-ng) → keys (LfPC,
// synth/cueing) → the timing plan (synth/synthesis_plan) → dikeys and
// diphones selected and concatenated (synth/concatenation) → parameter
// tracks → every model marker (synth/marker_synthesis). The dikeys drive the
// hand, the forearm relative to the head and the head itself; the diphones
// drive the face. docs/synthesis.md describes each step.
//
// Pure: no file I/O (csw say, workbench/jobs/say_job, writes the files).
#include <string>
#include <vector>

#include "core/take.h"
#include "synth/concatenation.h"
#include "synth/dictionary.h"
#include "synth/fragments.h"
#include "synth/marker_synthesis.h"
#include "synth/phonetics.h"
#include "synth/synthesis_plan.h"

namespace csw {

struct FaceModel;
struct HandModel;

namespace dict {

struct SynthesisOptions {
  PlanOptions plan;
  // concat.rate_hz is the output frame rate; 0 = the dictionary's corpus rate
  // (Dictionary::corpus_rate_hz, else its first unit's rate).
  // selection_weight 10 (s⁻¹): 0.1 s of duration mismatch weighs as much as
  // a join one standard deviation apart (measured on 30 held-out sentences,
  // docs/synthesis.md). target_weight 10: a unit whose key postures are a
  // standard deviation from their classes' means costs as much as 1 s of
  // duration mismatch, so units cut where the cuer only approached a key are
  // left out whenever the succession has another (30 held-out sentences: key
  // accuracy through the recogniser 80.9 % -> 89.6 %; 3 and 30 gave 89.9
  // and 89.4 %). Key postures: a trimmed unit still starts at its key's
  // posture, and each key's hand is pulled to within 0.5 of its code's
  // standard deviations of the code's exemplar (30 held-out sentences: key
  // accuracy 89.4 % without either, 92.8 % with the first, 94.9 % with the
  // second, 96.6 % with both; docs/synthesis.md). Movement onsets
  // (concat.movement_onsets) stay off: on the same sentences they move the
  // lone-C shape onsets from 49 to 30 ms early against the corpus's, but the
  // CV placement targets 2 ms further from the corpus's, to its 20 ms bar.
  ConcatOptions concat = [] {
    ConcatOptions c;
    c.rate_hz = 0;
    c.selection_weight = 10;
    c.target_weight = 10;
    c.trim_keeps_key_posture = true;
    c.posture_radius = 0.5;
    return c;
  }();
  // Speed limit (LimitMarkerSpeed, synth/marker_synthesis.h): no marker
  // moves further between two frames than max_jump_factor × the largest
  // jump of the corpus's markers (Dictionary::corpus_max_jump_mm, scaled from
  // the corpus's frame rate to the output's); 0 = no limit, or when the
  // dictionary has no corpus measure. At most speed_limit_passes passes.
  double max_jump_factor = 1.0;
  int speed_limit_passes = 200;
  // The face from seed-003's fragments (synth/fragments.h: greedy longest
  // match, phone-aligned warp, RBF resampling, blended overlaps) instead of
  // the diphone Viterbi; fragments.rate_hz is replaced by the output rate.
  bool face_fragments = false;
  FragmentOptions fragments;
  std::string Check() const;  // "" or the reason
};

struct Synthesis {
  SynthesisPlan plan;                    // key targets on the output clock
  std::vector<Phone> phones;             // the utterance's phones on the output clock (lead-in added)
  std::vector<PhoneTarget> face_phones;  // what the face track was built for (pauses "_" at both ends)
  HandTrack hand;                        // dikeys: hand parameters, forearm in head, head pose
  FaceTrack face;                // diphones: face parameters (zeros = the mean face when the dictionary has none)
  FragmentTrack fragments;       // with face_fragments: the fragments the face came from
  ParameterTracks tracks;        // the tracks the markers come from (after the speed limit)
  SpeedLimitResult speed_limit;  // what the speed limit did (nothing when off)
  double speed_limit_mm = 0;     // the limit applied (0 = none)
  // Every model marker at the output rate, its tiers: "words", "phones"
  // (IPA, pauses "_"), "keys" (point tier: each key's target, code "PS"),
  // "placement_targets" (each key's target plus the placement lag of the
  // unit leaving it, HandTrack's leaving_placement_lag_s, kept within 40 %
  // of the slots around it; the key's target when unknown), "expected_keys" (interval tier:
  // each key from its syllable's acoustic onset to the next's, as csw cue
  // writes it) and "gestures" (interval tier: each key's movement, from
  // the previous target to its own, "PS <fallback level>").
  Take take;
  Audio audio;  // the utterance's audio after lead_in_s of silence, padded with silence to the take's duration
  std::vector<std::string> warnings;
};

// Synthesises one utterance (phones with times, and its audio when it has
// one). Throws InvalidInput naming `name` when the utterance has no phone or
// no key, the dictionary has no dikey, or the models' parameter counts are
// not the dictionary's; the concatenation's errors pass through.
Synthesis Synthesize(const Utterance& utterance, const Dictionary& dictionary, const FaceModel& face,
                     const HandModel& hand, const SynthesisOptions& options, const std::string& name);

// The espeak-ng rate (words per minute) whose mean phone duration matches
// `mean_phone_s` (MeanPhoneDuration of a dictionary) for `text`: two
// secant steps from 150 wpm on espeak-ng's own phone durations, clamped to
// [80, 450]. 150 when mean_phone_s is not finite and positive.
int MatchSpeakingRate(const std::string& text, double mean_phone_s, const PhonetiseOptions& base = {});

}  // namespace dict
}  // namespace csw

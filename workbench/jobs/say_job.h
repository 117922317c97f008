#pragma once
// `csw say`: French text → cued speech (issue 15 items 5 and 6; synth/
// synthesizer.h, docs/synthesis.md). Per sentence: espeak-ng's phones and
// audio at the corpus's speaking rate (the dictionary's mean phone duration)
// unless --rate, the LfPC keys, the timing plan (per-dikey phasing or the
// seed's global rule), dikeys and diphones selected and concatenated, every
// model marker. Writes, for one sentence, OUT/speech.wav, OUT/cues.TextGrid
// (words, phones, expected keys, key targets, gestures), OUT/markers.c3d,
// OUT/markerset.json (the models' marker set) and OUT/pointlight.mp4; for
// several (--text-file, or several texts), the same in OUT/001/, OUT/002/, ...
// Always OUT/synthesis.h5 (a corpus of the synthesised takes, to open in
// csw-workbench or analyse with the other commands) and OUT/say.json (the
// report).
//
// --check (with --keys): the synthesised markers scored by the key
// recogniser at every intended key's target frame (both components must be
// the intended ones), the continuity of the markers against the corpus's
// (stored in the dictionary) and the gesture timing measured by csw phasing
// on OUT/synthesis.h5, against the corpus's phasing (--corpus-phasing: the
// JSON of csw phasing on the corpus).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct SayOptions {
  std::vector<std::string> texts;        // sentences given on the command line
  std::string text_file;                 // one sentence per line (blank lines and lines starting with # skipped)
  std::string dict;                      // dictionary file (csw dict build)
  std::string models;                    // the model file the dictionary was built with
  std::string output;                    // output folder (created)
  int rate_wpm = 0;                      // espeak-ng rate; 0 = match the corpus's mean phone duration
  std::string phasing = "dikey";         // "dikey" (stored per-dikey phasing) or "global" (the seed's rule)
  double rate_hz = 0;                    // output frame rate; 0 = the corpus's
  double selection_weight = 10;          // per s of RMS duration mismatch (ConcatOptions)
  double concatenation_weight = 1;       // per standardised RMS jump (ConcatOptions)
  double target_weight = 10;             // per standardised distance of a key posture from its class (ConcatOptions)
  bool keep_key_postures = true;         // a trimmed dikey still starts at its key's posture (ConcatOptions)
  double posture_radius = 0.5;           // key posture pull toward the code's exemplar (ConcatOptions), 0 = off
  bool keep_movement_durations = false;  // each dikey stream's movement keeps its duration (ConcatOptions)
  bool movement_onsets = false;          // movements start at A1 + the units' onset phasing (ConcatOptions)
  double max_onset_overlap = 0.3;        // ... overlapping the previous slot by at most this fraction of it
  std::string face_units = "diphones";   // "diphones" (Viterbi) or "fragments" (seed-003, synth/fragments.h)
  std::string resampling = "rbf";        // fragments: "rbf" (inverse multiquadric) or "linear"
  double rbf_shape = 2;                  // fragments: inverse-multiquadric shape, in smallest sample spacings
  double blend = 0.5;                    // fragments: overlap at a join, fraction of the shared phone
  bool align_phones = true;              // fragments: warp through every phone boundary
  bool video = true;                     // write pointlight.mp4
  double fps = 25;                       // video frame rate
  bool check = false;                    // close the loop (needs keys)
  std::string keys;                      // key model file (csw keys train)
  std::string corpus_phasing;            // JSON of csw phasing on the corpus ("" = timing without the corpus's)
  std::string Check() const;             // "" or the reason
};

// {"dict", "models", "output", "rate_wpm", "phasing", "rate_hz",
//  "sentences": [{"text", "folder", "duration_s", "keys", "phones", "rate_wpm",
//                 "fallback": {"whole", "closest placement", "two streams", "interpolated"},
//                 "files": {"wav", "textgrid", "c3d", "video"}, "speed_limit": {"limit_mm" (null = none),
//                 "smoothed_frames", "max_jump_before_mm", "max_jump_after_mm"}, "warnings": [...]}],
//  "fallback": {totals as above}, "corpus": "OUT/synthesis.h5",
//  "check": {"keys": {"intended", "correct", "accuracy", "substitutions", "insertions", "deletions",
//                     "at_targets": {"correct", "accuracy", "shape_accuracy", "placement_accuracy"}},
//            "continuity": {"rate_hz", "p99_jump_mm", "max_jump_mm", "corpus_p99_jump_mm",
//                           "corpus_max_jump_mm", "corpus_rate_hz"},
//            "timing": {"CV": {"placement_target_ms", "corpus_placement_target_ms", "placement_onset_ms",
//                              "corpus_placement_onset_ms", "shape_target_ms", ..., "count"}, "V": ..., "C": ...}}}
// ("check" only with --check; per sentence "check": {"intended", "recognised",
// "correct", "accuracy", "at_targets", "at_targets_correct"}). Key accuracy:
// the recogniser's free decoding of the synthesised markers (rests left out)
// aligned to the intended keys by edit distance, matches / intended keys, as
// csw keys score counts "sequence.free"; "at_targets": the most probable shape
// and placement at each key's planned target frame (strict: the placement of
// a key may arrive some tens of ms from its shape target). Times in ms
// relative to A1, the kinematic estimates of csw phasing; null where not
// measured.
nlohmann::json Say(const SayOptions& options, Progress& progress);
std::string SayText(const nlohmann::json& result);

}  // namespace csw::jobs

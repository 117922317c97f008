#pragma once
// `csw phasing`: how hand gestures are timed against speech (issue 11, item 5;
// docs/analysis-phasing.md). Per selected take:
//   1. the expected keys from the phone tier (LfPC rules, as `csw cue`);
//   2. the hand features and the gestural score with a trained key model
//      (`csw keys train`); a rough target time for every key's shape and
//      placement: the take's labelled targets (tiers `keys`, `placement_targets`)
//      when their codes follow the cued keys, else the expected keys aligned
//      to the gestural score (aligned decoding, less accurate: ~90 ms);
//   3. per key, its shape gesture (the seven distances) and its placement
//      gesture (the tip of its longest extended finger in the head frame,
//      blended from one finger to the other over each measured shape movement
//      that changes the finger) measured two ways: kinematic (superposed
//      minimum-jerk fits of every movement of the take with its neighbours,
//      shapes first, analysis/phasing/movement_timing.h EstimateMovements) and
//      posterior (onset when the key's class starts to dominate, target at its
//      posterior peak); successions where the component does not change are
//      left out, and so are, for the kinematic statistics, changes whose rough
//      target is within 50 ms of a neighbour's (only approached) and placement
//      estimates whose onset or target standard error exceeds 8 ms
//      ("undetermined"), all counted in "kinematic_changes";
//   4. times relative to A1 (consonant onset for CV and lone-C keys, vowel
//      onset for lone-V keys) and to the vowel onset, per key type (CV, V, C):
//      mean, sd, 95 % confidence interval, count.
// Writes nothing into the corpus; --csv writes one row per key, --figures the
// histograms per key type and the gestural score of each take.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct PhasingOptions {
  std::string corpus;
  std::string keys;                // model file with a /keys group (csw keys train)
  std::vector<std::string> takes;  // take selection; empty = every take but fill versions
  std::string phones = "phones";
  std::string symbols = "auto";
  std::string markerset;  // "" = the one the corpus remembers for each take
  std::string csv;        // per-key CSV file ("" = none)
  std::string figures;    // folder for the figures ("" = none)
  // Folder with <take>.truth.json (csw simulate): each key's true gesture times
  // are added to the CSV and the JSON reports the estimates' errors.
  std::string truth;
  std::string reference;  // phasing model JSON drawn as the histograms' reference ("" = Attina's means)
  // Rough target times around which each movement is fitted: "labels" (the
  // label tiers, whose codes must follow the cued keys), "aligned" (the
  // expected keys aligned to the gestural score), "auto" (labels when they
  // follow the cued keys, else aligned).
  std::string targets = "auto";
  std::string labels = "keys";                        // shape targets
  std::string label_placement = "placement_targets";  // placement targets (else `labels`)
  std::string Check() const;
};

// {"corpus", "keys", "takes": [{"take", "keys", "measured": {...}}],
//  "kinematic": {"CV": {"placement": {"onset": {"mean_ms", "sd_ms", "ci95_ms", "count"},
//  "target": {...}}, "shape": {...}}, "V": {...}, "C": {...}}, "posterior": {same},
//  "relative_to_vowel_onset": {"kinematic": {...}, "posterior": {...}},
//  "truth": {...} (with --truth: the true times' summary), "errors_vs_truth": {...},
//  "kinematic_changes": {"placement": {"measured", "undetermined", "approached",
//  "no_change", "not_fitted": counts}, "shape": {...}},
//  "csv", "figures"}
nlohmann::json Phasing(const PhasingOptions& options, Progress& progress);
std::string PhasingText(const nlohmann::json& result);

}  // namespace csw::jobs

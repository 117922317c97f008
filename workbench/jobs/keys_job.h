#pragma once
// `csw keys train` and `csw keys score`: the Gaussian key recogniser of the
// seed's §4 (analysis/keys, docs/analysis.md).
//
// train: per selected take, the seven hand distances and the placement feature
// (hand_features.h) at the labelled target frames of a point tier of key codes
// "PS" (default `keys`; placement targets from a second point tier, default
// `placement_targets`, when the take has it, else the same points), then one
// Gaussian per shape and per placement; the key model is written into a model
// file (group /keys, docs/model-format.md), other models in it are kept.
//
// score: per selected take, the gestural score (posteriors), free decoding and
// the gesture extents, written as tiers of the take in one transaction:
//   keys_decoded          interval tier: the free decoding's keys ("PS")
//   keys_decoded_targets  point tier: each decoded key's target frame
//   shape_extents         interval tier: where one shape dominates ("S p=0.97": class and peak posterior)
//   placement_extents     interval tier: the same for placements
//   keys_aligned          point tier (takes with a label tier): the expected
//                         keys (the label tier's codes in order) aligned to
//                         the posteriors, at their kinematic target times
//                         (analysis/keys/key_timing.h)
//   placement_aligned     point tier: the same keys' placement targets, where
//                         the placement changes
// and the gestural score itself as the take's score set "keys" (io/corpus
// TakeScores, docs/corpus-format.md): matrices "shape" (frames × 9) and
// "placement" (frames × 6) of posteriors, columns "0".."8" / "0".."5", at the
// take's frame rate from time 0, source = the key model file.
// With --figures DIR and labels: DIR/shape_confusion.png and
// DIR/placement_confusion.png (labelled class vs the posterior argmax at the
// labelled frames, over every scored take).
// Takes whose label tier is present are scored: accuracy at the labelled
// frames, edit-distance alignment of the free decoding, aligned target error
// (an aligned key is correct when its target lies within 40 ms of its label).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/keys/key_decoding.h"
#include "analysis/keys/key_model.h"
#include "analysis/keys/key_timing.h"
#include "core/progress.h"

namespace csw::jobs {

struct KeysTrainOptions {
  std::string corpus;
  std::vector<std::string> takes;  // take selection; required
  std::string tier = "keys";
  std::string placement_tier = "placement_targets";  // used when the take has it
  std::string markerset;                             // marker-set JSON; "" = the one the corpus remembers for each take
  // JSON file with a "hand_layout" section naming the markers (docs/analysis.md);
  // "" = derived from the marker set's roles.
  std::string layout;
  std::string output;  // model file (created or updated)
  keys::KeyModelOptions model;
  std::string Check() const;
};

struct KeysScoreOptions {
  std::string corpus;
  std::string keys;                                  // model file with a /keys group
  std::vector<std::string> takes;                    // empty = every take but fill versions
  std::string tier = "keys";                         // label tier scored against, when present
  std::string placement_tier = "placement_targets";  // placement targets, when present (else `tier`)
  std::string markerset;
  // Phone tier, when present: its keys (LfPC rules, phone symbols detected)
  // give each labelled key its acoustic onset A1 when they match the label
  // tier's codes, and the aligned decoding's targets are checked against the
  // speech (analysis/keys/key_timing.h, "speech anchors"). "" = never.
  std::string phones = "phones";
  keys::DecodeOptions decode;
  // Speech anchors: a changing target nearer a neighbouring key's A1 + lag
  // than its own is replaced too (KeyTimingOptions::anchor_nearest).
  bool anchor_nearest = keys::KeyTimingOptions{}.anchor_nearest;
  // A fitted target the anchors keep is combined with its A1 + lag, the fit's
  // standard error multiplied by this (KeyTimingOptions::anchor_fit_sd_factor;
  // 0 = fits kept as they are).
  double fit_sd_factor = keys::KeyTimingOptions{}.anchor_fit_sd_factor;
  // A fitted target beyond the anchors' gate is kept where the hand holds the
  // key's own class (KeyTimingOptions::anchor_keep_in_class).
  bool keep_in_class = keys::KeyTimingOptions{}.anchor_keep_in_class;
  bool dry_run = false;  // report only, write no tier nor scores
  std::string figures;   // folder for the confusion-matrix figures; "" = none
  std::string Check() const;
};

// {"corpus", "output", "takes": [{"take", "shape_targets", "placement_targets"}],
//  "layout": {...}, "shape": {"classes": [{"label", "count"}]}, "placement": {...}}
nlohmann::json KeysTrain(const KeysTrainOptions& options, Progress& progress);
std::string KeysTrainText(const nlohmann::json& result);

// {"corpus", "keys", "takes": [{"take", "frames", "decoded_keys", "tiers_written", "scores_written",
//   "speech_anchors" (true when the phone tier's keys matched the labels), ...}],
//  "shape": {"accuracy", "count", "confusion"}, "placement": {...},
//  "decoding": {"min_key_ms", "aligned_floor", "anchor_nearest", "fit_sd_factor", "keep_in_class"}
//    (the options used),
//  "sequence": {"free": {"keys_correct", "keys_expected", "insertions", "deletions", "substitutions"},
//               "aligned": {"keys_correct", "keys_expected", "target_error_ms": {"mean", "sd"}}}}
// (the scoring members only when some take has the label tier), "figures": [paths] when drawn.
nlohmann::json KeysScore(const KeysScoreOptions& options, Progress& progress);
std::string KeysScoreText(const nlohmann::json& result);

// Confusion matrix as JSON rows (truth) of counts (decided).
nlohmann::json ConfusionJson(const keys::Confusion& c);

}  // namespace csw::jobs

#pragma once
// `csw transitions`: the transition analysis of Naert, Larboulette & Gibet
// (issue 14, items 3 and 4; docs/transitions.md). Per selected take (a
// skeleton capture: BVH import or `csw simulate signs`), per hand tier, every
// transition between two signs (analysis/signing/transitions.h): its duration,
// the mean Euclidean and geodesic distances between the postures that bound it
// over that hand's arm joints (shoulder to finger tips; or every joint), raw
// and normalised, and the sign types on either side; then statistics per
// transition type (the seed's Table 2) and the four duration models (SIMPLE,
// SIMPLE_BOUNDED, LINEAR, SURFACE) fitted on every transition and evaluated by
// k-fold cross-validated mean absolute error. -o saves the fitted models (JSON,
// docs/transitions.md) with the best one named; --csv one row per transition.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/signing/duration_models.h"
#include "analysis/signing/transitions.h"
#include "core/progress.h"
#include "core/take.h"

namespace csw::jobs {

struct TransitionsOptions {
  std::string corpus;
  std::vector<std::string> takes;                                // take selection; empty = every take but fill versions
  std::vector<std::string> tiers = {"right_hand", "left_hand"};  // sign/transition tiers, one per hand
  std::string types = "sign_types";                              // sign-type tier ("" = none); absent tiers are fine
  // "TIER=JOINT" pairs naming each hand tier's wrist joint; a tier without one
  // gets the wrist of its side (a tier name with "right"/"left" or r_/l_, and a
  // joint named like a wrist or hand of that side: FindWrist).
  std::vector<std::string> wrists;
  std::string joints = "arm";     // "arm": the hand's arm joints (shoulder to tips); "all": every joint
  std::string length_unit = "m";  // unit of Euclidean distances and speeds: m, dm, cm or mm
  std::vector<std::string> models = {"simple", "simple_bounded", "linear", "surface"};
  int folds = 5;  // cross-validation folds (fewer transitions than folds: leave-one-out)
  signing::DurationModelOptions model;
  signing::TransitionOptions transition;
  std::string output;   // JSON file for the fitted models ("" = none)
  std::string csv;      // one row per transition ("" = none)
  std::string figures;  // folder for transitions.png (durations against the distances, predicted against measured)
  std::string Check() const;
};

// The wrist joint of one side ("right" or "left") of a skeleton, by the rules
// of csw segment (analysis/signing/segmentation.h FindWrists: a name with
// "wrist", else one whose stem ends in "hand", of that side). -1 when none.
int FindWrist(const std::vector<SkeletonJoint>& skeleton, const std::string& side);

// The analysis on takes in memory (what Transitions does after loading them).
// Fills `transitions` when not null. Throws InvalidInput naming the take and
// tier for a take without skeleton or orientations, a wrist that is not found.
nlohmann::json AnalyseTransitions(const std::vector<Take>& takes, const TransitionsOptions& options, Progress& progress,
                                  std::vector<signing::Transition>* transitions = nullptr);

// {"corpus", "takes": [{"take", "tiers": [{"tier", "wrist", "joints", "transitions"}]}],
//  "transitions", "length_unit", "per_type": [{"type", "count", "mean_s", "sd_s"}],
//  "distances": {"geodesic": {"min", "mean", "max"}, "euclidean": {...}},
//  "models": [{"model", "fit": {...}, "training_mae_s", "cv_mae_s"}], "best", "folds", "output", "csv", "figures"}
nlohmann::json Transitions(const TransitionsOptions& options, Progress& progress);
std::string TransitionsText(const nlohmann::json& result);

}  // namespace csw::jobs

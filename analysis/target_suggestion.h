#pragma once
// Suggested target frames (issue 11, item 3; docs/analysis.md, "Suggested
// targets"): for every expected key, the frame where the hand's feature
// trajectory comes to rest nearest the key's expected target time, so that a
// user labelling target frames confirms a suggestion instead of hunting for it.
//
// The feature trajectory is any multi-dimensional series in millimetres
// (the seven hand-shape distances, or the placement point in the head frame).
// Its speed is the norm of the central-difference velocity of the
// zero-phase-filtered series (analysis/cleaning/filter.h, gaps respected); a
// suggested target is a local minimum of that speed inside the search window
// around the expected time, the one nearest the expected time. Pure
// computation: no files, no printing.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace csw::analysis {

struct TargetSuggestionOptions {
  double cutoff_hz = 8.0;         // low-pass cut-off of the feature series (zero-phase Butterworth, order 2)
  double search_s = 0.15;         // half-width of the window around each expected time
  double min_dip_fraction = 0.1;  // a minimum must lie this fraction below the window's peak speed...
  double min_dip_mm_s = 5.0;      // ...and this far (mm/s) below it: noise dips are not targets
  std::string Check() const;      // "" when valid, else the reason
};

struct SuggestedTarget {
  double expected_s = 0.0;  // the expected time it was asked for
  int64_t frame = -1;       // suggested frame, -1 when none was found
  double time_s = 0.0;      // frame / rate (NaN when none)
  double speed_mm_s = 0.0;  // filtered speed at the frame
  double offset_s = 0.0;    // time_s - expected_s
  std::string why;          // when frame == -1: the reason ("no valid samples", ...)
};

// The filtered speed (mm/s) of a frames × dims series (NaN rows or entries =
// missing; a frame counts only when every dimension is valid), NaN where it
// cannot be computed. Throws InvalidInput for bad options or rate.
Eigen::VectorXd FeatureSpeed(const Eigen::MatrixXd& series, double rate_hz, double cutoff_hz);

// One suggestion per expected time (seconds from the first frame, in any
// order). Successive keys get strictly increasing frames in the order of their
// expected times: when windows overlap, the key expected nearest to a minimum
// keeps it and the other takes its next-nearest minimum that keeps the order,
// or none ("its speed minima are the targets of the neighbouring keys"). Throws InvalidInput for bad options, a
// non-positive rate or a non-finite expected time.
std::vector<SuggestedTarget> SuggestTargets(const Eigen::MatrixXd& series, double rate_hz,
                                            const std::vector<double>& expected_s,
                                            const TargetSuggestionOptions& options = {});

// The same on a speed already computed (FeatureSpeed), for several expected
// times over one series.
std::vector<SuggestedTarget> SuggestTargetsFromSpeed(const Eigen::VectorXd& speed_mm_s, double rate_hz,
                                                     const std::vector<double>& expected_s,
                                                     const TargetSuggestionOptions& options = {});

}  // namespace csw::analysis

#pragma once
// `csw segment`: segmentation refinement of sign-language takes (issue 14,
// item 2; docs/signing.md). Per selected take: the manual sign/transition
// interval tier (--tier), each hand's wrist (found from the marker names by
// the rules of analysis/signing/segmentation.h FindWrists, or named with
// --right-wrist / --left-wrist), its zero-phase low-pass filtered speed, its
// local minima (optionally with rests), and every boundary of the tier moved
// to the nearest minimum of that hand within --threshold-s (kept when none is
// in reach). One refined tier per hand (default "<tier>_right",
// "<tier>_left") replaces any tier of that name, all takes in one
// transaction; the manual tier is never changed. Positions only: joint
// orientations are not needed.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct SegmentOptions {
  std::string corpus;
  std::vector<std::string> takes;  // take selection (take_selection.h); empty = every take but fill versions
  std::string tier;                // the manual sign/transition interval tier (required)
  std::string hand = "both";       // right, left or both
  double cutoff_hz = 6.0;          // -3 dB frequency of the zero-phase filter on the wrist positions (0 = none)
  int order = 2;                   // single-pass Butterworth order
  double threshold_s = 0.15;       // the seed's 15 frames at 100 Hz
  double rest_speed_mm_s = 0.0;    // > 0: a still hand (below this for >= min_rest_s) gives arrival/departure
  double min_rest_s = 0.15;
  std::string right_wrist, left_wrist;  // explicit wrist markers ("" = the naming rules)
  std::string right_tier, left_tier;    // output tier names ("" = <tier>_right / <tier>_left)
  bool dry_run = false;                 // report only, write no tier
  // Folder for one figure per take (segment_<take>.png, the figures module):
  // the wrist speeds with the manual tier, the refined tiers and the tiers
  // named in figure_tiers (e.g. a simulation's truth).
  std::string figures;
  std::vector<std::string> figure_tiers;
  std::string Check() const;  // "" when valid, else the reason (a usage error)
};

// {"corpus", "tier", "dry_run", "options": {"cutoff_hz", "order", "threshold_s", "rest_speed_mm_s",
//   "min_rest_s"}, "takes": [{"take", "rate_hz", "hands": [{"hand": "right"|"left", "wrist", "rule",
//   "tier", "boundaries", "moved", "kept", "shift_ms": {"mean", "max"}, "minima",
//   "moves": [{"manual_s", "refined_s", "moved", "why"}]}]}], "boundaries", "moved", "tiers_written",
//   "figures": [paths]}
nlohmann::json Segment(const SegmentOptions& options, Progress& progress);
// The default text: one line per take and hand, then the kept boundaries and a total.
std::string SegmentText(const nlohmann::json& result);

}  // namespace csw::jobs

#pragma once
// Segmentation refinement of sign-language takes (issue 14, item 2;
// docs/signing.md), after Naert, Larboulette & Gibet (2017), §4.2: the manual
// tags that separate signs from transitions are assumed to lie near local
// minima of each hand's speed; each tag moves to the nearest minimum of that
// hand's low-pass filtered wrist speed within a threshold (the seed: 15 frames
// at 100 Hz = 0.15 s), and stays where it is when no minimum is in reach. Each
// hand gets its own refined tier (the hands are partly autonomous).
//
//   speed:   the wrist's positions are low-pass filtered (zero-phase
//            Butterworth, analysis/cleaning/filter.h; gaps are respected) and
//            the speed is |p[i+1] − p[i−1]| / (2 dt) (mm/s, NaN at run ends and in gaps);
//   minima:  frames i with s[i−1] > s[i] < s[i+1]; a flat bottom (equal
//            values) gives its first and last frames, also when a gap or the
//            take's edge bounds it on one side; optionally (RestOptions) a
//            hand at rest gives its arrival and departure;
//   refine:  every interior boundary of the manual interval tier (label i's
//            end = label i+1's start), and the outer edges of labels that do not
//            touch a neighbour, moves to the frame time of the nearest minimum
//            with |t_min − t_tag| <= threshold_s; when two boundaries would
//            land on the same minimum, or out of order, the one farther from it
//            keeps its manual time.
// Pure functions: no files; bad options or data throw csw::InvalidInput.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/take.h"

namespace csw::signing {

// The two wrists of a take. Rules, on the marker (joint) names, case-insensitive:
//   1. side: the name contains "right" / "left", or starts with "r" / "l"
//      followed by '_', '.', '-', ':' or an upper-case letter in the original
//      ("RWrist", "r_wrist", "L.Hand"), or ends with "_r" / "_l" / ".r" / ".l";
//      a namespace prefix up to the last ':' is ignored ("mixamorig:RightHand");
//   2. joint: the name contains "wrist"; when no name of that side does, the
//      name (without side words and separators) ends with "hand"
//      ("RightHand", not "RightHandIndex1"); among several, the shortest name;
//   3. an explicit name (right / left) overrides the rules for that side.
// Throws InvalidInput naming the markers when a side has no wrist.
struct WristJoints {
  int64_t right = -1, left = -1;
  std::string right_name, left_name;
  std::string right_rule, left_rule;  // "given", "wrist" or "hand"
};
// Only the sides asked for are looked for (the other stays -1).
WristJoints FindWrists(const std::vector<std::string>& names, const std::string& right = "",
                       const std::string& left = "", bool find_right = true, bool find_left = true);
// The side a name belongs to by rule 1: 'R', 'L' or 0.
char NameSide(const std::string& name);

struct SpeedOptions {
  // -3 dB frequency of the zero-phase filter applied to the wrist positions
  // (Hz); 0 = no filter.
  double cutoff_hz = 6.0;
  int order = 2;                            // single-pass Butterworth order (2 = a 4th-order zero-lag filter)
  std::string Check(double rate_hz) const;  // "" when valid
};

// The filtered speed (mm/s) of one marker, one value per frame.
Eigen::VectorXd WristSpeed(const MarkerArray& markers, int64_t marker, double rate_hz, const SpeedOptions& options);
// Local minima of a speed series, as above, in frame order (NaN = missing).
std::vector<int64_t> LocalMinima(const Eigen::VectorXd& speed);

// Still hands. A hand at rest has no single speed minimum but a long stretch of
// near-zero speed whose noise makes many; with rest_speed_mm_s > 0, every run
// of at least min_rest_s where the speed stays below rest_speed_mm_s counts as
// a rest: its first and last frames (arrival, departure) are its minima and
// the minima inside it are dropped. Shorter runs (the bottom of a speed dip
// between two movements) keep their local minima. 0 = off (the seed's method).
struct RestOptions {
  double rest_speed_mm_s = 0.0;
  double min_rest_s = 0.15;
  std::string Check() const;  // "" when valid
};
// LocalMinima with rests as above, in frame order.
std::vector<int64_t> SpeedMinima(const Eigen::VectorXd& speed, double rate_hz, const RestOptions& options);

struct RefineOptions {
  double threshold_s = 0.15;  // the seed's 15 frames at 100 Hz
  std::string Check() const;  // "" when valid
};

struct BoundaryRefinement {
  double manual_s = 0.0;   // the tag
  double refined_s = 0.0;  // where it went (== manual_s when kept)
  int64_t frame = -1;      // the minimum's frame, -1 when kept
  bool moved = false;
  std::string why;  // when kept: "no minimum within 0.15 s", "its minimum is nearer to the boundary at 1.230 s", ...
};

// The boundaries of an interval tier, in time order: every interior boundary
// once, and the outer edges of labels that do not touch a neighbour (not the
// tier's domain edges). Throws InvalidInput for a point tier.
std::vector<double> TierBoundaries(const LabelTier& tier);

// Moves boundaries to minima. `minima` are frames of a series sampled at
// rate_hz (frame i at i / rate_hz s).
std::vector<BoundaryRefinement> RefineBoundaries(const std::vector<double>& boundaries,
                                                 const std::vector<int64_t>& minima, double rate_hz,
                                                 const RefineOptions& options);
// The tier with its boundaries replaced (same labels, named `name`): every
// label edge equal to boundaries[i].manual_s becomes boundaries[i].refined_s.
LabelTier ApplyRefinement(const LabelTier& tier, const std::vector<BoundaryRefinement>& boundaries,
                          const std::string& name);

struct HandSegmentation {
  char hand = 'R';  // 'R' or 'L'
  int64_t marker = -1;
  std::string marker_name;
  LabelTier tier;  // the refined tier
  std::vector<BoundaryRefinement> boundaries;
  Eigen::VectorXd speed;  // filtered wrist speed (mm/s)
  std::vector<int64_t> minima;
  int moved() const;
};

struct SegmentationOptions {
  SpeedOptions speed;
  RestOptions rest;
  RefineOptions refine;
  bool right = true, left = true;       // hands to refine
  std::string right_wrist, left_wrist;  // explicit marker names ("" = the rules of FindWrists)
  // Output tier names; "" = "<manual tier>_right" / "<manual tier>_left".
  std::string right_tier, left_tier;
  std::string Check(double rate_hz) const;
};

// Refines `manual` (an interval tier of the take) for each hand asked for.
// Throws InvalidInput (naming the take) for bad options, a point tier, a
// take without frame rate, or wrists that cannot be found.
std::vector<HandSegmentation> RefineSegmentation(const Take& take, const LabelTier& manual,
                                                 const SegmentationOptions& options);

}  // namespace csw::signing

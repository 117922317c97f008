#pragma once
// Label-swap detection between neighbouring markers: two labels a, b whose
// trajectories exchange at frame s and exchange back at frame e (a tracker
// mixing two close markers). Candidate pairs are markers that stay close (each
// marker's nearest markers by median distance, or pairs given by the caller,
// or every pair inside caller-given groups such as a segment or a cluster);
// nothing depends on marker names.
//
// Method (a two-track version of multiple-hypothesis data association, Reid
// 1979, on constant-velocity motion): each label's trajectory breaks where it
// jumps (constant-velocity prediction residual above jump_mm) or reappears after
// a gap. At every break frame of a candidate pair the segments before and after
// the break are linked two ways — unswapped (a→a, b→b) and swapped (a→b, b→a) —
// each link scored by its constant-velocity extrapolation error from both sides
// (across the gap when a label is missing). A break where every unswapped link
// fails (≥ jump_mm) and the swapped links fit (≤ max_cost_ratio × the unswapped
// error) exchanges the labels; successive exchanges of a pair bound the swapped
// intervals. The take is assumed correctly labelled at its start.
// Gaps: a swap that starts or ends while one label is missing is found at the
// other label's jump (exact frame); when both labels are missing it is found at
// the first frame where one reappears (the exchange of the frames before, all
// missing in both, changes nothing). See docs/cleaning-swaps.md.
#include <cstdint>
#include <utility>
#include <vector>

#include "core/take.h"

namespace csw::cleaning {

struct SwapOptions {
  // Candidate pairs (columns). Explicit pairs win; else every pair inside each group; else automatic.
  std::vector<std::pair<int, int>> pairs;
  std::vector<std::vector<int>> groups;
  int neighbours = 8;                   // automatic: each marker's nearest markers by median distance ...
  double max_pair_distance_mm = 150.0;  // ... no farther than this on median
  // Break threshold (mm): > 0 fixed; 0 = max(jump_floor_mm, jump_noise_factor × robust σ of the take's
  // per-coordinate constant-velocity residuals).
  double jump_mm = 0.0;
  double jump_floor_mm = 4.0;
  double jump_noise_factor = 10.0;
  double max_bridge_s = 0.25;        // a label's segment before/after a break is looked for this far
  double max_cost_ratio = 0.35;      // swapped links' error ≤ this × the unswapped links' error
  double max_reference_sd_mm = 2.5;  // reference markers: distance to a label this steady (1.4826 × MAD)
  double max_swapped_misfit = 16.0;  // swapped segments: mean z² of the distances to the references
  double min_evidence = 20.0;        // |log-likelihood ratio| of a segment's state evidence needed to decide it
  double min_confidence = 0.3;       // swaps below are not reported
};

struct DetectedSwap {
  int marker_a = 0, marker_b = 0;          // a < b
  int64_t first_frame = 0, end_frame = 0;  // swapped over [first, end); end = frames when open-ended
  bool open_ended = false;                 // no exchange back before the end of the take
  // In [0, 1]: min over the start and end exchanges of (1 − swapped/unswapped link error) × (links seen / 4),
  // halved when open-ended.
  double confidence = 0.0;
};

struct SwapReport {
  double jump_mm = 0.0;                              // break threshold used
  std::vector<std::pair<int, int>> candidate_pairs;  // pairs examined
  std::vector<DetectedSwap> swaps;                   // by first frame
};

// Each marker's nearest markers by median distance over (a subsample of) the frames where both are seen.
std::vector<std::pair<int, int>> NeighbourPairs(const MarkerArray& markers, int neighbours, double max_distance_mm);

// Throws InvalidInput for a rate ≤ 0, bad columns or bad options.
SwapReport DetectLabelSwaps(const MarkerArray& markers, double rate_hz, const SwapOptions& options = {});

// The fix: exchanges the two markers' samples over every detected interval, in
// order. Throws InvalidInput for a swap outside the array.
void FixLabelSwaps(const std::vector<DetectedSwap>& swaps, MarkerArray* markers);

}  // namespace csw::cleaning

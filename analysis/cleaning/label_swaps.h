#pragma once
// Label-swap detection between neighbouring markers: two labels a, b whose
// trajectories exchange at frame s and exchange back at frame e (a tracker
// mixing two close markers). Candidate pairs are markers that stay close (each
// marker's nearest markers by median distance, or pairs given by the caller,
// or every pair inside caller-given groups such as a segment or a cluster);
// nothing depends on marker names.
//
// Method, per candidate pair (a, b):
//  1. Breaks. Each label's trajectory breaks where it jumps (constant-velocity
//     prediction residual above jump_mm) or reappears after missing samples.
//  2. Exchanges (a two-track form of multiple-hypothesis data association,
//     Reid 1979). At each break the label segments before and after are linked
//     unswapped (a→a, b→b) and swapped (a→b, b→a), each link scored by its
//     constant-velocity extrapolation error (mm) from both sides, across gaps
//     within max_bridge_s. A break where a label continues its own trajectory
//     (an unswapped link below jump_mm) cannot be an exchange. It is a
//     confirmed exchange when the best swapped link fits (≤ max_cost_ratio × the
//     unswapped error) or, both labels seen on both sides, when the pair's
//     relative vector flips sign (robust to fast common hand motion); it is an
//     open boundary when a label has no past within the bridge.
//  3. State. Between boundaries the labels' distances to reference markers
//     (markers whose distance to a or b is steady over the take: 1.4826 × MAD ≤
//     max_reference_sd_mm) give a log-likelihood ratio, swapped over not; a
//     segment is swapped when the ratio exceeds min_evidence and the exchanged
//     labels fit the references (mean z² ≤ max_swapped_misfit). An interval
//     bounded by open boundaries only needs min_unconfirmed_evidence per frame.
//     Pairs without a reference marker use the confirmed exchanges alone,
//     paired in order (the take assumed correctly labelled at its start).
//     A segment between two confirmed exchanges needs no reference fit.
//  4. Intervals shorter than min_frames are dropped (jitter), and a label found
//     swapped with two partners at overlapping times keeps the stronger evidence.
// Gaps: a swap that starts or ends while one label is missing is found at the
// other label's jump (exact frame); when both labels are missing it is found at
// the first frame where one reappears (exchanging the frames before, missing
// in both, changes nothing). See docs/cleaning-swaps.md.
#include <cstdint>
#include <utility>
#include <vector>

#include "core/take.h"

namespace csw::cleaning {

struct SwapOptions {
  // Candidate pairs (columns). Explicit pairs win; else every pair inside each group; else automatic.
  std::vector<std::pair<int, int>> pairs;
  std::vector<std::vector<int>> groups;
  int neighbours = 16;                  // automatic: each marker's nearest markers by median distance ...
  double max_pair_distance_mm = 150.0;  // ... no farther than this on median
  // Break threshold (mm): > 0 fixed; 0 = max(jump_floor_mm, jump_noise_factor × robust σ of the take's
  // per-coordinate constant-velocity residuals).
  double jump_mm = 0.0;
  double jump_floor_mm = 4.0;
  double jump_noise_factor = 10.0;
  double max_bridge_s = 0.25;        // a label's segment before/after a break is looked for this far
  double max_cost_ratio = 0.35;      // swapped links' error ≤ this × the unswapped links' error
  double max_reference_sd_mm = 2.0;  // rigid references: distance to a marker this steady (90th percentile / 1.645)
  int references = 3;                // at most this many rigid references per marker of the pair
  double reference_clip = 8.0;       // a reference's log-likelihood term per frame is within ±this
  double evidence_weight = 0.5;      // segment evidence (sum over frames of the mean term) × this
  double confirmed_bonus = 10.0;     // state change at a confirmed exchange (log-odds)
  double open_penalty = 10.0;        // ... at an open boundary (a label without a past within the bridge)
  double broken_penalty = 20.0;      // ... at a break where the swapped links do not fit either
  double start_penalty = 40.0;       // swapped from the first frame (the take is assumed labelled right at its start)
  double min_run_evidence = 2.0;     // a swapped run's mean evidence per informative frame (unless both ends confirmed)
  double min_one_sided_evidence = 100.0;  // ... when only one marker of the pair has rigid references
  int64_t min_frames = 4;                 // shorter intervals are not reported (jitter)
  double min_confidence = 0.3;            // swaps below are not reported
};

struct DetectedSwap {
  int marker_a = 0, marker_b = 0;          // a < b
  int64_t first_frame = 0, end_frame = 0;  // swapped over [first, end); end = frames when open-ended
  bool open_ended = false;                 // no exchange back before the end of the take
  // In [0, 1]: 1 − exp(−evidence) with reference markers; 1 when found from the
  // trajectories' exchanges alone (no reference marker); halved when open-ended.
  double confidence = 0.0;
  // Mean log-likelihood ratio (swapped over not) per informative frame of the
  // interval; 0 when no reference marker was found (continuity alone).
  double evidence = 0.0;
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

#pragma once
// Label-swap detection between neighbouring markers: two labels a, b whose
// trajectories exchange at frame s and exchange back at frame e (a tracker
// mixing two close markers). Candidate pairs are markers that come close (each
// marker's nearest markers by the 10th percentile of their distance, or pairs
// given by the caller, or every pair inside caller-given groups such as a
// segment or a cluster); nothing depends on marker names.
//
// Method, per candidate pair (a, b):
//  1. Breaks. Each label's trajectory breaks where it jumps (constant-velocity
//     prediction residual above jump_mm) or reappears after missing samples.
//  2. Boundaries (a two-track form of multiple-hypothesis data association,
//     Reid 1979). At each break the label segments before and after are linked
//     unswapped (a→a, b→b) and swapped (a→b, b→a), each link scored by its
//     constant-velocity extrapolation error (mm) from both sides, across gaps
//     within max_bridge_s. A break where a label continues its own trajectory
//     (an unswapped link below jump_mm) cannot be an exchange; every other break
//     is a boundary: confirmed when the best swapped link fits (≤ max_cost_ratio
//     × the unswapped error) or, both labels seen on both sides, when the pair's
//     relative vector flips sign; open when a label has no past within the
//     bridge; broken otherwise (both jump, the swapped links do not fit either).
//  3. Rigid references: markers whose distance to a (or to b) stays fixed over
//     the take (screened first by the own label's 1.4826 × MAD of distance,
//     which a swap over a minority of the frames hardly moves). Judged
//     swap-invariantly: each frame by whichever label is nearer
//     that distance (90th percentile of the deviation / 1.645 ≤
//     max_reference_sd_mm), and the marker's own label must be the one at that
//     distance in at least twice as many frames as the other label.
//  4. State. Per frame and reference, the evidence for "swapped" is the other
//     label's fit to the reference distance minus the own label's (each a
//     Gaussian-with-outliers log-likelihood over its outlier floor, in
//     [0, reference_clip]: a label far from both hypotheses says nothing),
//     averaged per marker of the pair and summed. A two-state Viterbi pass over
//     the segments between boundaries (swapped / not) adds this evidence
//     (× evidence_weight) to the cost of changing state at each boundary
//     (confirmed_bonus, open_penalty, broken_penalty; start_penalty for a take
//     swapped from its first frame).
//  5. Each swapped run is judged as a whole: both markers' references must
//     agree (a marker whose references give exactly no evidence is accepted
//     when an end of the run is a confirmed exchange) and the mean evidence per
//     informative frame must reach min_run_evidence (runs where only one marker
//     has references are dropped unless one_sided); a run between two confirmed exchanges is
//     accepted without it. Pairs without any reference use the confirmed
//     exchanges alone, paired in order; an unpaired one is reported only for
//     caller-named pairs.
//  6. Intervals shorter than min_frames are dropped (jitter), and a label found
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
  int neighbours = 16;                  // automatic: each marker's nearest markers (10th-percentile distance) ...
  double max_pair_distance_mm = 150.0;  // ... no farther than this at the 10th percentile
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
  int64_t max_absorbed_frames =
      3;  // a run takes in next segments with positive evidence and at most this many seen frames
  double min_run_evidence = 2.0;  // a swapped run's mean evidence per informative frame (unless both ends confirmed)
  bool one_sided = false;       // accept runs when only one marker of the pair has rigid references (min_run_evidence)
  int64_t min_frames = 4;       // shorter intervals are not reported (jitter)
  double min_confidence = 0.3;  // swaps below are not reported
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

// Each marker's nearest markers by the 10th percentile of their distance over (a subsample of) the frames
// where both are seen (fingers that come close only in some hand shapes are still neighbours).
std::vector<std::pair<int, int>> NeighbourPairs(const MarkerArray& markers, int neighbours, double max_distance_mm);

// Throws InvalidInput for a rate ≤ 0, bad columns or bad options.
SwapReport DetectLabelSwaps(const MarkerArray& markers, double rate_hz, const SwapOptions& options = {});

// The fix: exchanges the two markers' samples over every detected interval, in
// order. Throws InvalidInput for a swap outside the array.
void FixLabelSwaps(const std::vector<DetectedSwap>& swaps, MarkerArray* markers);

}  // namespace csw::cleaning

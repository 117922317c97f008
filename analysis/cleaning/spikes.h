#pragma once
// Spike detection: isolated outlier samples of a marker trajectory (a marker
// reconstructed once from a wrong ray pair, a reflection). A sample is a spike
// when its acceleration (second central difference × rate², mm/s²) exceeds a
// threshold AND it is the centre of the spike pattern: an outlier of offset d at
// frame f gives second differences (d, -2d, d) at f-1, f, f+1, so the sample's
// acceleration is twice its neighbours'; a step (jump) of height h gives (h, -h)
// at two neighbouring frames and is not reported (docs/cleaning-swaps.md). A
// sample is judged only when frames f-2..f+2 are seen (next to a gap a spike
// and its neighbour cannot be told apart).
// The threshold is automatic by default: max(floor, k × robust scale), the scale
// being the MAD of the take's own acceleration components (Hampel 1974's
// identifier, here on accelerations).
#include <cstdint>
#include <vector>

#include "core/take.h"

namespace csw::cleaning {

struct SpikeOptions {
  std::vector<int> columns;         // markers to check (empty = all)
  double threshold_mm_s2 = 0.0;     // > 0: fixed threshold; 0: automatic (below)
  double mad_factor = 8.0;          // automatic: k × 1.4826 × MAD of the acceleration components
  double floor_mm_s2 = 30000.0;     // automatic: never below this (30 m/s²; smooth hand motion stays under it)
  double localisation_ratio = 1.5;  // |a_f| ≥ ratio × max(|a_f-1|, |a_f+1|) (2 for a pure spike, 1 for a step)
};

struct Spike {
  int marker = 0;
  int64_t frame = 0;
  double acceleration_mm_s2 = 0.0;  // |second central difference| × rate²
  double offset_mm = 0.0;           // distance of the sample from the midpoint of its neighbours
};

struct SpikeReport {
  double threshold_mm_s2 = 0.0;  // the threshold used
  double scale_mm_s2 = 0.0;      // robust scale of the acceleration components (1.4826 × MAD)
  std::vector<Spike> spikes;     // by marker, then frame
};

// Throws InvalidInput for a rate ≤ 0, a bad column or bad options.
SpikeReport DetectSpikes(const MarkerArray& markers, double rate_hz, const SpikeOptions& options = {});

// The fix: marks every reported spike sample missing (gap fills can then fill
// it). Returns the number of samples removed. Throws InvalidInput when a spike
// lies outside the array.
int64_t RemoveSpikes(const std::vector<Spike>& spikes, MarkerArray* markers);

}  // namespace csw::cleaning

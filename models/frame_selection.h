#pragma once
// Training-frame selection by vector quantisation: keep frames whose marker
// configuration differs from every frame already kept by at least d mm.
//
// Distance between two frames = the MAXIMUM over the chosen markers of the 3D
// (Euclidean) distance of each marker between the two frames. A frame is kept
// when that distance to every kept frame is >= min_distance_mm, i.e. it is
// dropped as soon as some kept frame has ALL chosen markers within d mm
// (the seed's "minimum 3D distance" of 2 mm). Frames with any chosen marker
// missing are excluded. Greedy in time order, deterministic. Candidates are
// found with a hash grid (cell = d) on the most mobile chosen marker, then
// checked marker by marker with early exit.
#include <cstdint>
#include <vector>

#include "core/take.h"

namespace csw {

struct FrameSelection {
  std::vector<int64_t> frames;    // kept frames, increasing
  int64_t complete_frames = 0;    // frames with all chosen markers visible
  int64_t incomplete_frames = 0;  // frames excluded for a missing marker
};

// Throws InvalidInput if columns is empty or out of range, or min_distance_mm <= 0.
FrameSelection SelectTrainingFrames(const MarkerArray& markers, const std::vector<int>& columns,
                                    double min_distance_mm = 2.0);

}  // namespace csw

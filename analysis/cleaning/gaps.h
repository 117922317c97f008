#pragma once
// The gap report of a take: per marker, the gaps (maximal runs of missing
// frames), the longest, and the fraction of frames missing. Leading and
// trailing gaps (no valid frame before, resp. after, the gap) are flagged:
// interpolating fills (spline, DCT) cannot fill them, only methods that do not
// need the marker's own data on both sides (rigid cluster, pattern, model).
//
// A sample is missing when any of its three coordinates is not finite (the
// MarkerArray convention is NaN in all three together; a stray NaN or Inf in
// one coordinate counts as missing too, so no fill ever reads it).
//
// Plain structs, no JSON here: the job layer serialises them.
#include <cstdint>
#include <vector>

#include "core/take.h"

namespace csw::cleaning {

// One gap of one marker: frames [start, start + length) are missing.
struct Gap {
  int marker = 0;
  int64_t start = 0;
  int64_t length = 0;
  bool leading = false;                           // no valid frame of this marker before the gap (it starts at frame 0)
  bool trailing = false;                          // no valid frame after the gap (it runs to the last frame)
  int64_t end() const { return start + length; }  // one past the last missing frame
  bool interior() const { return !leading && !trailing; }
};

bool operator==(const Gap& a, const Gap& b);

struct MarkerGaps {
  int marker = 0;
  std::vector<Gap> gaps;        // in time order
  int64_t missing_frames = 0;   // sum of the gap lengths
  double fraction_missing = 0;  // missing_frames / frames (0 for an empty take)
  int64_t longest = 0;          // longest gap length in frames (0 when none)
  bool never_visible = false;   // the whole marker is one gap (leading and trailing)
};

struct GapReport {
  int64_t frames = 0;
  int64_t markers = 0;
  std::vector<MarkerGaps> per_marker;  // one per marker column, in column order
  int64_t gap_count = 0;               // gaps over all markers
  int64_t missing_samples = 0;         // missing marker samples (frames × markers cells)
  double fraction_missing = 0;         // missing_samples / (frames × markers)
  int64_t longest = 0;                 // longest gap over all markers
  int64_t leading_or_trailing = 0;     // gaps that touch the start or the end of the take
  // Every gap, marker by marker, each marker's in time order.
  std::vector<Gap> AllGaps() const;
};

// Whether a sample is missing (any coordinate not finite).
bool SampleMissing(const MarkerArray& markers, int64_t frame, int64_t marker);

// The gaps of one marker column, in time order. Throws InvalidInput when the
// column is out of range.
std::vector<Gap> FindGaps(const MarkerArray& markers, int marker);
// All gaps of a take, marker by marker.
std::vector<Gap> FindAllGaps(const MarkerArray& markers);
// The full report.
GapReport MakeGapReport(const MarkerArray& markers);

// Number of gaps whose length falls in [min_length, max_length] (inclusive;
// max_length 0 = no upper bound): the report's gap-length histogram bins
// (e.g. 1-5, 6-20, 21-60, > 60 frames).
int64_t CountGapsInRange(const std::vector<Gap>& gaps, int64_t min_length, int64_t max_length);

}  // namespace csw::cleaning

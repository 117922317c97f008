#include "analysis/cleaning/gaps.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace csw::cleaning {

bool operator==(const Gap& a, const Gap& b) {
  return a.marker == b.marker && a.start == b.start && a.length == b.length && a.leading == b.leading &&
         a.trailing == b.trailing;
}

bool SampleMissing(const MarkerArray& markers, int64_t frame, int64_t marker) {
  const float* p = markers.at(frame, marker);
  return !(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]));
}

std::vector<Gap> FindGaps(const MarkerArray& markers, int marker) {
  if (marker < 0 || marker >= markers.markers())
    throw InvalidInput("gap report: marker column " + std::to_string(marker) + " out of range (take has " +
                       std::to_string(markers.markers()) + " markers)");
  std::vector<Gap> gaps;
  const int64_t n = markers.frames();
  int64_t f = 0;
  while (f < n) {
    if (!SampleMissing(markers, f, marker)) {
      ++f;
      continue;
    }
    Gap g;
    g.marker = marker;
    g.start = f;
    while (f < n && SampleMissing(markers, f, marker)) ++f;
    g.length = f - g.start;
    g.leading = g.start == 0;
    g.trailing = f == n;
    gaps.push_back(g);
  }
  return gaps;
}

std::vector<Gap> FindAllGaps(const MarkerArray& markers) {
  std::vector<Gap> all;
  for (int m = 0; m < markers.markers(); ++m) {
    std::vector<Gap> g = FindGaps(markers, m);
    all.insert(all.end(), g.begin(), g.end());
  }
  return all;
}

GapReport MakeGapReport(const MarkerArray& markers) {
  GapReport r;
  r.frames = markers.frames();
  r.markers = markers.markers();
  r.per_marker.reserve(static_cast<size_t>(r.markers));
  for (int m = 0; m < r.markers; ++m) {
    MarkerGaps mg;
    mg.marker = m;
    mg.gaps = FindGaps(markers, m);
    for (const Gap& g : mg.gaps) {
      mg.missing_frames += g.length;
      mg.longest = std::max(mg.longest, g.length);
      if (!g.interior()) ++r.leading_or_trailing;
    }
    mg.fraction_missing = r.frames > 0 ? static_cast<double>(mg.missing_frames) / static_cast<double>(r.frames) : 0.0;
    mg.never_visible = r.frames > 0 && mg.missing_frames == r.frames;
    r.gap_count += static_cast<int64_t>(mg.gaps.size());
    r.missing_samples += mg.missing_frames;
    r.longest = std::max(r.longest, mg.longest);
    r.per_marker.push_back(std::move(mg));
  }
  const int64_t cells = r.frames * r.markers;
  r.fraction_missing = cells > 0 ? static_cast<double>(r.missing_samples) / static_cast<double>(cells) : 0.0;
  return r;
}

std::vector<Gap> GapReport::AllGaps() const {
  std::vector<Gap> all;
  all.reserve(static_cast<size_t>(gap_count));
  for (const MarkerGaps& mg : per_marker) all.insert(all.end(), mg.gaps.begin(), mg.gaps.end());
  return all;
}

int64_t CountGapsInRange(const std::vector<Gap>& gaps, int64_t min_length, int64_t max_length) {
  return std::count_if(gaps.begin(), gaps.end(), [&](const Gap& g) {
    return g.length >= min_length && (max_length <= 0 || g.length <= max_length);
  });
}

}  // namespace csw::cleaning

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

namespace {

// Every marker's gaps in one pass over the frames (the array is frame-major:
// scanning one column at a time strides through memory), marker by marker.
std::vector<std::vector<Gap>> GapsPerMarker(const MarkerArray& markers) {
  const int64_t n = markers.frames(), nm = markers.markers();
  std::vector<std::vector<Gap>> per(static_cast<size_t>(nm));
  std::vector<int64_t> open(static_cast<size_t>(nm), -1);  // start of the gap in progress
  for (int64_t f = 0; f < n; ++f) {
    for (int64_t m = 0; m < nm; ++m) {
      const bool missing = SampleMissing(markers, f, m);
      int64_t& start = open[static_cast<size_t>(m)];
      if (missing && start < 0) {
        start = f;
      } else if (!missing && start >= 0) {
        Gap g;
        g.marker = static_cast<int>(m);
        g.start = start;
        g.length = f - start;
        g.leading = start == 0;
        per[static_cast<size_t>(m)].push_back(g);
        start = -1;
      }
    }
  }
  for (int64_t m = 0; m < nm; ++m) {
    const int64_t start = open[static_cast<size_t>(m)];
    if (start < 0) continue;
    Gap g;
    g.marker = static_cast<int>(m);
    g.start = start;
    g.length = n - start;
    g.leading = start == 0;
    g.trailing = true;
    per[static_cast<size_t>(m)].push_back(g);
  }
  return per;
}

}  // namespace

std::vector<Gap> FindAllGaps(const MarkerArray& markers) {
  std::vector<Gap> all;
  for (std::vector<Gap>& g : GapsPerMarker(markers)) all.insert(all.end(), g.begin(), g.end());
  return all;
}

GapReport MakeGapReport(const MarkerArray& markers) {
  GapReport r;
  r.frames = markers.frames();
  r.markers = markers.markers();
  r.per_marker.reserve(static_cast<size_t>(r.markers));
  std::vector<std::vector<Gap>> per = GapsPerMarker(markers);
  for (int m = 0; m < r.markers; ++m) {
    MarkerGaps mg;
    mg.marker = m;
    mg.gaps = std::move(per[static_cast<size_t>(m)]);
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

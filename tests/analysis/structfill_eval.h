#pragma once
// Shared by rigid_fill_test.cc and pattern_fill_test.cc: virtual-cuer takes with artificial gaps
// punched where the marker is captured, scored against the clean capture by gap-length bin.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "analysis/cleaning/gaps.h"
#include "core/take.h"
#include "datasets/virtual_cuer.h"

namespace csw::cleaning::testing {

struct GapBin {
  int min_length, max_length;
  const char* label;
};
inline const std::vector<GapBin>& GapBins() {
  static const std::vector<GapBin> b = {{1, 5, "1-5"}, {6, 20, "6-20"}, {21, 60, "21-60"}};
  return b;
}

// Errors of one bin: per filled frame, 3-D distance to the clean capture (mm).
struct BinScore {
  std::vector<double> errors;
  int gaps = 0, filled = 0;
  double Mean() const {
    double s = 0;
    for (double e : errors) s += e;
    return errors.empty() ? NAN : s / static_cast<double>(errors.size());
  }
  double Percentile(double p) const {
    if (errors.empty()) return NAN;
    std::vector<double> v = errors;
    std::sort(v.begin(), v.end());
    const double pos = p * static_cast<double>(v.size() - 1);
    const auto i = static_cast<size_t>(pos);
    const size_t j = std::min(i + 1, v.size() - 1);
    return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
  }
  double Max() const { return errors.empty() ? NAN : *std::max_element(errors.begin(), errors.end()); }
};

// Punches, into a copy of `markers`, gaps of lengths drawn from every bin in turn into each of
// `columns`, each gap where the marker is captured from `margin` frames before to `margin` frames
// after it (so it is an isolated gap of exactly that length), gaps of one marker at least
// `spacing` frames apart. Returns the gaps (with their bin index in `bins`).
inline std::vector<Gap> PunchGaps(const MarkerArray& markers, const std::vector<int>& columns, std::mt19937_64& rng,
                                  int per_bin, int margin, int spacing, MarkerArray* punched, std::vector<int>* bins) {
  *punched = markers;
  std::vector<Gap> gaps;
  for (int col : columns) {
    std::vector<bool> used(static_cast<size_t>(markers.frames()), false);
    for (int rep = 0; rep < per_bin; ++rep)
      for (size_t b = 0; b < GapBins().size(); ++b) {
        std::uniform_int_distribution<int> len(GapBins()[b].min_length, GapBins()[b].max_length);
        const int L = len(rng);
        for (int attempt = 0; attempt < 200; ++attempt) {
          std::uniform_int_distribution<int64_t> st(margin, markers.frames() - L - margin - 1);
          const int64_t s = st(rng);
          bool ok = true;
          for (int64_t f = s - margin; f < s + L + margin && ok; ++f)
            ok = markers.Visible(f, col) && !used[static_cast<size_t>(f)];
          if (!ok) continue;
          for (int64_t f = std::max<int64_t>(0, s - spacing); f < std::min<int64_t>(markers.frames(), s + L + spacing);
               ++f)
            used[static_cast<size_t>(f)] = true;
          for (int64_t f = s; f < s + L; ++f) punched->SetMissing(f, col);
          gaps.push_back({col, s, L});
          bins->push_back(static_cast<int>(b));
          break;
        }
      }
  }
  return gaps;
}

// Adds the errors of a filled gap (out holds the fill) to its bin.
inline void ScoreGap(const MarkerArray& clean, const MarkerArray& out, const Gap& g, BinScore* score) {
  for (int64_t f = g.start; f < g.start + g.length; ++f) {
    const float* a = out.at(f, g.marker);
    const float* b = clean.at(f, g.marker);
    const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    score->errors.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
  }
}

// Short virtual-cuer sentence takes (no audio synthesis), made once per test program.
inline const std::vector<SimulationResult>& CuerTakes() {
  static const std::vector<SimulationResult> takes = [] {
    std::vector<SimulationResult> out;
    const std::vector<std::string> sentences = ShippedSentences();
    for (int i = 0; i < 2; ++i) {
      SimulateOptions o;
      o.seed = 12 + static_cast<uint64_t>(i);
      o.audio = false;
      VirtualCuer cuer(o);
      out.push_back(cuer.SimulateSentence("structfill_" + std::to_string(i), sentences.at(static_cast<size_t>(i))));
    }
    return out;
  }();
  return takes;
}

inline MarkerSet CuerMarkerSet() {
  SimulateOptions o;
  o.audio = false;
  return VirtualCuer(o).MakeMarkerSet();
}

}  // namespace csw::cleaning::testing

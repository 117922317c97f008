#include "models/frame_selection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <unordered_map>

#include "core/error.h"

namespace csw {
namespace {

struct CellHash {
  size_t operator()(const std::array<int64_t, 3>& c) const {
    uint64_t h = 1469598103934665603ULL;
    for (int64_t v : c) {
      h ^= static_cast<uint64_t>(v);
      h *= 1099511628211ULL;
    }
    return static_cast<size_t>(h);
  }
};

}  // namespace

FrameSelection SelectTrainingFrames(const MarkerArray& markers, const std::vector<int>& columns,
                                    double min_distance_mm) {
  if (columns.empty()) throw InvalidInput("frame selection: no markers chosen");
  if (!(min_distance_mm > 0.0) || !std::isfinite(min_distance_mm)) {
    throw InvalidInput("frame selection: minimum distance must be positive");
  }
  for (int c : columns) {
    if (c < 0 || c >= markers.markers()) {
      throw InvalidInput("frame selection: marker column " + std::to_string(c) + " out of range");
    }
  }
  const int64_t frames = markers.frames();
  const size_t n = columns.size();
  FrameSelection out;

  // Complete frames, and the chosen marker with the largest spread (best pruning).
  std::vector<uint8_t> complete(static_cast<size_t>(frames), 0);
  std::vector<double> sum(n * 3, 0.0), sum2(n * 3, 0.0);
  for (int64_t f = 0; f < frames; ++f) {
    bool all = true;
    for (size_t i = 0; i < n && all; ++i) {
      const float* p = markers.at(f, columns[i]);
      all = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    }
    if (!all) continue;
    complete[static_cast<size_t>(f)] = 1;
    ++out.complete_frames;
    for (size_t i = 0; i < n; ++i) {
      const float* p = markers.at(f, columns[i]);
      for (int k = 0; k < 3; ++k) {
        sum[i * 3 + k] += p[k];
        sum2[i * 3 + k] += static_cast<double>(p[k]) * p[k];
      }
    }
  }
  out.incomplete_frames = frames - out.complete_frames;
  if (out.complete_frames == 0) return out;
  size_t pivot = 0;
  double best_spread = -1.0;
  for (size_t i = 0; i < n; ++i) {
    double spread = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double m = sum[i * 3 + k] / static_cast<double>(out.complete_frames);
      spread += sum2[i * 3 + k] / static_cast<double>(out.complete_frames) - m * m;
    }
    if (spread > best_spread) {
      best_spread = spread;
      pivot = i;
    }
  }

  const double d = min_distance_mm;
  std::unordered_map<std::array<int64_t, 3>, std::vector<int64_t>, CellHash> grid;
  // Clamped so that hostile coordinates (1e38 mm, a tiny d) cannot overflow the
  // conversion; clamped cells only merge far-away points, which the exact check
  // below still tells apart.
  auto index_of = [&](float v) {
    const double c = std::floor(static_cast<double>(v) / d);
    return static_cast<int64_t>(std::clamp(c, -4.0e18, 4.0e18));
  };
  auto cell_of = [&](const float* p) { return std::array<int64_t, 3>{index_of(p[0]), index_of(p[1]), index_of(p[2])}; };
  // True when every chosen marker of frames a and b is within d (distance < d).
  auto close = [&](int64_t a, int64_t b) {
    for (size_t i = 0; i < n; ++i) {
      const float* p = markers.at(a, columns[(i + pivot) % n]);
      const float* q = markers.at(b, columns[(i + pivot) % n]);
      double s = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double diff = static_cast<double>(p[k]) - q[k];
        s += diff * diff;
      }
      if (std::sqrt(s) >= d) return false;
    }
    return true;
  };

  for (int64_t f = 0; f < frames; ++f) {
    if (!complete[static_cast<size_t>(f)]) continue;
    const std::array<int64_t, 3> cell = cell_of(markers.at(f, columns[pivot]));
    bool reject = false;
    for (int64_t dx = -1; dx <= 1 && !reject; ++dx) {
      for (int64_t dy = -1; dy <= 1 && !reject; ++dy) {
        for (int64_t dz = -1; dz <= 1 && !reject; ++dz) {
          const auto it = grid.find({cell[0] + dx, cell[1] + dy, cell[2] + dz});
          if (it == grid.end()) continue;
          for (int64_t kept : it->second) {
            if (close(f, kept)) {
              reject = true;
              break;
            }
          }
        }
      }
    }
    if (reject) continue;
    out.frames.push_back(f);
    grid[cell].push_back(f);
  }
  return out;
}

}  // namespace csw

#include "workbench/gui/minmax.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace csw::gui {

namespace {

constexpr int64_t kBlock = 8;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Folds one (lo, hi) pair into a running extreme, ignoring NaN.
inline void Fold(float lo, float hi, float* out_lo, float* out_hi) {
  if (std::isnan(lo)) return;
  if (std::isnan(*out_lo) || lo < *out_lo) *out_lo = lo;
  if (std::isnan(*out_hi) || hi > *out_hi) *out_hi = hi;
}

}  // namespace

MinMaxPyramid::MinMaxPyramid(std::vector<float> samples, double rate_hz)
    : samples_(std::move(samples)), rate_hz_(rate_hz) {
  // Level 0 from the samples, each further level from the one below.
  int64_t n = size();
  int64_t block = kBlock;
  const std::vector<float>* below = nullptr;
  while (n / block >= 2) {
    int64_t count = (n + block - 1) / block;
    std::vector<float> level(static_cast<size_t>(count * 2), kNaN);
    for (int64_t b = 0; b < count; ++b) {
      float lo = kNaN, hi = kNaN;
      if (below == nullptr) {
        int64_t end = std::min(n, (b + 1) * block);
        for (int64_t i = b * block; i < end; ++i) Fold(samples_[i], samples_[i], &lo, &hi);
      } else {
        int64_t below_count = static_cast<int64_t>(below->size() / 2);
        int64_t end = std::min(below_count, (b + 1) * kBlock);
        for (int64_t i = b * kBlock; i < end; ++i) Fold((*below)[i * 2], (*below)[i * 2 + 1], &lo, &hi);
      }
      level[b * 2] = lo;
      level[b * 2 + 1] = hi;
    }
    levels_.push_back(std::move(level));
    below = &levels_.back();
    block *= kBlock;
  }
}

float MinMaxPyramid::ValueAt(double t) const {
  if (samples_.empty() || rate_hz_ <= 0 || t < 0) return kNaN;
  auto i = static_cast<int64_t>(std::floor(t * rate_hz_ + 1e-9));
  if (i >= size()) return kNaN;
  return samples_[static_cast<size_t>(i)];
}

void MinMaxPyramid::Extremes(int64_t first, int64_t last, float* lo, float* hi) const {
  *lo = kNaN;
  *hi = kNaN;
  // Walk up the levels: raw samples at the ragged ends, whole blocks in between.
  int64_t block = 1;
  int level = -1;
  while (first < last) {
    int64_t next_block = block * kBlock;
    bool can_go_up = level + 1 < static_cast<int>(levels_.size());
    if (can_go_up) {
      int64_t up_first = (first + next_block - 1) / next_block * next_block;
      int64_t up_last = last / next_block * next_block;
      if (up_first < up_last) {
        // Ragged ends at this level, then recurse to the coarser level for the middle.
        for (int64_t i = first; i < up_first; i += block) {
          if (level < 0) {
            Fold(samples_[i], samples_[i], lo, hi);
          } else {
            int64_t j = i / block;
            Fold(levels_[level][j * 2], levels_[level][j * 2 + 1], lo, hi);
          }
        }
        for (int64_t i = up_last; i < last; i += block) {
          if (level < 0) {
            Fold(samples_[i], samples_[i], lo, hi);
          } else {
            int64_t j = i / block;
            Fold(levels_[level][j * 2], levels_[level][j * 2 + 1], lo, hi);
          }
        }
        first = up_first;
        last = up_last;
        block = next_block;
        ++level;
        continue;
      }
    }
    for (int64_t i = first; i < last; i += block) {
      if (level < 0) {
        Fold(samples_[i], samples_[i], lo, hi);
      } else {
        int64_t j = i / block;
        Fold(levels_[level][j * 2], levels_[level][j * 2 + 1], lo, hi);
      }
    }
    break;
  }
}

std::vector<MinMaxBin> MinMaxPyramid::Decimate(double t0, double t1, int columns) const {
  std::vector<MinMaxBin> out;
  if (samples_.empty() || rate_hz_ <= 0 || columns <= 0 || t1 <= t0) return out;
  int64_t first = std::clamp<int64_t>(static_cast<int64_t>(std::floor(t0 * rate_hz_)), 0, size());
  int64_t last = std::clamp<int64_t>(static_cast<int64_t>(std::ceil(t1 * rate_hz_)) + 1, 0, size());
  if (first >= last) return out;
  int64_t count = last - first;
  if (count <= columns) {
    out.reserve(static_cast<size_t>(count));
    for (int64_t i = first; i < last; ++i) {
      float v = samples_[static_cast<size_t>(i)];
      out.push_back({static_cast<double>(i) / rate_hz_, v, v});
    }
    return out;
  }
  out.reserve(static_cast<size_t>(columns));
  for (int c = 0; c < columns; ++c) {
    int64_t a = first + count * c / columns;
    int64_t b = first + count * (c + 1) / columns;
    if (b <= a) continue;
    MinMaxBin bin;
    bin.time_s = static_cast<double>(a) / rate_hz_;
    Extremes(a, b, &bin.min, &bin.max);
    out.push_back(bin);
  }
  return out;
}

}  // namespace csw::gui

#include "models/inversion.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace csw {

namespace {

double SampleSd(double m2, int64_t count) { return count > 1 ? std::sqrt(m2 / static_cast<double>(count - 1)) : 0.0; }

}  // namespace

// Welford's one-pass update: stable for long runs of similar values.
void ErrorStats::Add(double x) {
  if (!std::isfinite(x)) return;
  ++count;
  const double d = x - mean;
  mean += d / static_cast<double>(count);
  m2 += d * (x - mean);
  max = count == 1 ? x : std::max(max, x);
  sd = SampleSd(m2, count);
}

void ErrorStats::Merge(const ErrorStats& o) {
  if (o.count == 0) return;
  if (count == 0) {
    *this = o;
    return;
  }
  const double na = static_cast<double>(count), nb = static_cast<double>(o.count), n = na + nb;
  const double d = o.mean - mean;
  m2 += o.m2 + d * d * na * nb / n;
  mean += d * nb / n;
  max = std::max(max, o.max);
  count += o.count;
  sd = SampleSd(m2, count);
}

const char* FrameStatusName(FrameStatus status) {
  switch (status) {
    case FrameStatus::kTooFewMarkers:
      return "too_few_markers";
    case FrameStatus::kNoStart:
      return "no_start";
    case FrameStatus::kFailed:
      return "failed";
    case FrameStatus::kConverged:
      return "converged";
    case FrameStatus::kMaxIterations:
      return "max_iterations";
  }
  return "unknown";
}

void InversionResult::ResizeFrames(int64_t frames) {
  const size_t n = static_cast<size_t>(frames);
  solved.assign(n, 0);
  converged.assign(n, 0);
  status.assign(n, FrameStatus::kTooFewMarkers);
  iterations.assign(n, 0);
  cold_start.assign(n, 0);
  cold_retry.assign(n, 0);
}

void ErrorSamples::Add(double x) {
  if (!std::isfinite(x)) return;
  stats.Add(x);
  values.push_back(x);
}

void ErrorSamples::Merge(const ErrorSamples& o) {
  stats.Merge(o.stats);
  values.insert(values.end(), o.values.begin(), o.values.end());
}

double ErrorSamples::Percentile(double percent) const { return csw::Percentile(values, percent); }

double Percentile(std::vector<double> values, double percent) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
  if (values.empty() || !(percent >= 0 && percent <= 100)) return std::nan("");
  const double h = static_cast<double>(values.size() - 1) * percent / 100.0;
  const size_t lo = std::min(values.size() - 1, static_cast<size_t>(std::floor(h)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(lo), values.end());
  const double a = values[lo];
  const double frac = h - static_cast<double>(lo);
  if (frac <= 0 || lo + 1 >= values.size()) return a;
  // The next order statistic: the smallest value after position lo.
  const double b = *std::min_element(values.begin() + static_cast<std::ptrdiff_t>(lo) + 1, values.end());
  return a + frac * (b - a);
}

ErrorStats SummariseErrors(const Eigen::MatrixXd& error_mm, const std::vector<int>& columns, int64_t first,
                           int64_t count) {
  const int64_t rows = error_mm.rows();
  if (first < 0 || first > rows) {
    throw InvalidInput("error summary: first frame " + std::to_string(first) + " outside 0.." + std::to_string(rows));
  }
  const int64_t last = count < 0 ? rows : std::min(rows, first + count);
  std::vector<int> cols = columns;
  if (cols.empty()) {
    for (int c = 0; c < static_cast<int>(error_mm.cols()); ++c) cols.push_back(c);
  }
  for (int c : cols) {
    if (c < 0 || c >= error_mm.cols()) {
      throw InvalidInput("error summary: column " + std::to_string(c) + " outside 0.." +
                         std::to_string(error_mm.cols() - 1));
    }
  }
  ErrorStats s;
  for (int64_t r = first; r < last; ++r) {
    for (int c : cols) s.Add(error_mm(r, c));
  }
  return s;
}

Eigen::MatrixXd MarkerDistances(const MarkerArray& a, const MarkerArray& b) {
  if (a.frames() != b.frames() || a.markers() != b.markers()) {
    throw InvalidInput("marker distances: arrays differ in shape (" + std::to_string(a.frames()) + "×" +
                       std::to_string(a.markers()) + " vs " + std::to_string(b.frames()) + "×" +
                       std::to_string(b.markers()) + ")");
  }
  Eigen::MatrixXd d(a.frames(), a.markers());
  for (int64_t f = 0; f < a.frames(); ++f) {
    for (int64_t m = 0; m < a.markers(); ++m) {
      const float* p = a.at(f, m);
      const float* q = b.at(f, m);
      if (IsMissing(p[0]) || IsMissing(q[0])) {
        d(f, m) = std::nan("");
        continue;
      }
      const double dx = double(p[0]) - double(q[0]), dy = double(p[1]) - double(q[1]), dz = double(p[2]) - double(q[2]);
      d(f, m) = std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  }
  return d;
}

}  // namespace csw

namespace csw {

int64_t CorrectGapsWithEdgeResiduals(const MarkerArray& input, InversionResult* result, int64_t fade_frames) {
  MarkerArray& rec = result->reconstructed;
  if (input.frames() != rec.frames() || input.markers() != rec.markers()) {
    throw InvalidInput("gap correction: input is " + std::to_string(input.frames()) + "×" +
                       std::to_string(input.markers()) + " markers, the reconstruction " +
                       std::to_string(rec.frames()) + "×" + std::to_string(rec.markers()));
  }
  const int64_t frames = input.frames();
  int64_t corrected = 0;
  // Mean misfit over up to kEdgeFrames visible, reconstructed samples from
  // frame f outwards (step −1 or +1), or nothing. Averaging keeps the marker
  // noise of one sample from being copied into the whole gap.
  constexpr int kEdgeFrames = 8;
  auto misfit = [&](int64_t f, int64_t m, int step, Eigen::Vector3d* out) {
    out->setZero();
    int n = 0;
    for (; n < kEdgeFrames && f >= 0 && f < frames && input.Visible(f, m) && !IsMissing(rec.at(f, m)[0]);
         ++n, f += step) {
      for (int k = 0; k < 3; ++k) (*out)(k) += double(input.at(f, m)[k]) - double(rec.at(f, m)[k]);
    }
    if (n == 0) return false;
    *out /= n;
    return true;
  };
  for (int64_t m = 0; m < input.markers(); ++m) {
    int64_t f = 0;
    while (f < frames) {
      if (input.Visible(f, m)) {
        ++f;
        continue;
      }
      const int64_t a = f;
      while (f < frames && !input.Visible(f, m)) ++f;
      const int64_t b = f;  // run [a, b)
      Eigen::Vector3d left, right;
      const bool has_left = misfit(a - 1, m, -1, &left), has_right = misfit(b, m, +1, &right);
      if (!has_left && !has_right) continue;
      const double span = static_cast<double>(b - a + 1);
      for (int64_t g = a; g < b; ++g) {
        float* p = rec.at(g, m);
        if (IsMissing(p[0])) continue;
        Eigen::Vector3d add;
        if (has_left && has_right) {
          const double t = static_cast<double>(g - a + 1) / span;
          add = (1 - t) * left + t * right;
        } else {
          const int64_t distance = has_left ? g - a + 1 : b - g;
          const double w = fade_frames > 0
                               ? std::max(0.0, 1.0 - static_cast<double>(distance) / static_cast<double>(fade_frames))
                               : 1.0;
          add = w * (has_left ? left : right);
        }
        for (int k = 0; k < 3; ++k) p[k] = static_cast<float>(p[k] + add(k));
        ++corrected;
      }
    }
  }
  return corrected;
}

}  // namespace csw

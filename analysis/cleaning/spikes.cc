#include "analysis/cleaning/spikes.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace csw::cleaning {

namespace {

Eigen::Vector3d At(const MarkerArray& m, int64_t f, int64_t k) {
  const float* p = m.at(f, k);
  return Eigen::Vector3d(p[0], p[1], p[2]);
}

double Median(std::vector<double>* v) {
  if (v->empty()) return 0.0;
  auto mid = v->begin() + static_cast<std::ptrdiff_t>(v->size() / 2);
  std::nth_element(v->begin(), mid, v->end());
  return *mid;
}

}  // namespace

SpikeReport DetectSpikes(const MarkerArray& markers, double rate_hz, const SpikeOptions& options) {
  if (!(rate_hz > 0.0)) throw InvalidInput("spike detection: the frame rate must be positive");
  if (options.threshold_mm_s2 < 0.0 || !(options.mad_factor > 0.0) || options.floor_mm_s2 < 0.0 ||
      !(options.localisation_ratio >= 1.0))
    throw InvalidInput("spike detection: threshold and floor must be ≥ 0, the MAD factor > 0, the ratio ≥ 1");
  std::vector<int> columns = options.columns;
  if (columns.empty())
    for (int64_t k = 0; k < markers.markers(); ++k) columns.push_back(static_cast<int>(k));
  for (int c : columns)
    if (c < 0 || c >= markers.markers())
      throw InvalidInput("spike detection: column " + std::to_string(c) + " is not in the take's " +
                         std::to_string(markers.markers()) + " markers");
  const int64_t frames = markers.frames();
  const double r2 = rate_hz * rate_hz;
  // Accelerations (NaN where a neighbour is missing), per column.
  std::vector<std::vector<Eigen::Vector3d>> acc(columns.size());
  std::vector<double> components;
  for (size_t i = 0; i < columns.size(); ++i) {
    const int k = columns[i];
    acc[i].assign(static_cast<size_t>(frames), Eigen::Vector3d::Constant(std::nan("")));
    for (int64_t f = 1; f + 1 < frames; ++f) {
      if (!markers.Visible(f - 1, k) || !markers.Visible(f, k) || !markers.Visible(f + 1, k)) continue;
      const Eigen::Vector3d a = (At(markers, f - 1, k) - 2.0 * At(markers, f, k) + At(markers, f + 1, k)) * r2;
      acc[i][static_cast<size_t>(f)] = a;
      for (int c = 0; c < 3; ++c) components.push_back(a[c]);
    }
  }
  SpikeReport report;
  {
    const double med = Median(&components);
    for (double& v : components) v = std::abs(v - med);
    report.scale_mm_s2 = 1.4826 * Median(&components);
  }
  report.threshold_mm_s2 = options.threshold_mm_s2 > 0.0
                               ? options.threshold_mm_s2
                               : std::max(options.floor_mm_s2, options.mad_factor * report.scale_mm_s2);
  for (size_t i = 0; i < columns.size(); ++i) {
    const auto& a = acc[i];
    auto has = [&](int64_t f) { return f >= 0 && f < frames && !std::isnan(a[static_cast<size_t>(f)][0]); };
    auto mag = [&](int64_t f) { return a[static_cast<size_t>(f)].norm(); };
    for (int64_t f = 1; f + 1 < frames; ++f) {
      // Judged only with its neighbours' accelerations (frames f-2..f+2 seen):
      // else a spike and its neighbour cannot be told apart.
      if (!has(f) || !has(f - 1) || !has(f + 1)) continue;
      const double m = mag(f);
      if (m <= report.threshold_mm_s2) continue;
      // Localisation: the outlier is where the acceleration peaks at about twice
      // its neighbours'; the neighbours of a spike and both sides of a step fail.
      if (m < options.localisation_ratio * std::max(mag(f - 1), mag(f + 1))) continue;
      Spike s;
      s.marker = columns[i];
      s.frame = f;
      s.acceleration_mm_s2 = m;
      s.offset_mm = 0.5 * m / r2;
      report.spikes.push_back(s);
    }
  }
  std::sort(report.spikes.begin(), report.spikes.end(), [](const Spike& x, const Spike& y) {
    return x.marker != y.marker ? x.marker < y.marker : x.frame < y.frame;
  });
  return report;
}

int64_t RemoveSpikes(const std::vector<Spike>& spikes, MarkerArray* markers) {
  int64_t removed = 0;
  for (const Spike& s : spikes) {
    if (s.marker < 0 || s.marker >= markers->markers() || s.frame < 0 || s.frame >= markers->frames())
      throw InvalidInput("spike removal: marker " + std::to_string(s.marker) + " frame " + std::to_string(s.frame) +
                         " is outside the take");
    if (!markers->Visible(s.frame, s.marker)) continue;
    markers->SetMissing(s.frame, s.marker);
    ++removed;
  }
  return removed;
}

}  // namespace csw::cleaning

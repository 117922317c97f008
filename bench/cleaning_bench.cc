// Cleaning a 10-minute, 113-marker take at 100 Hz in memory (issue 12):
// gap report, spline and rigid fills (FillGaps), zero-phase Butterworth
// filter; corpus I/O is timed apart (bench_corpus). Single-threaded: the
// analysis code runs on one core. The take is synthetic but shaped like a
// capture: two rigid 5-marker clusters moving rigidly, 103 markers moving
// smoothly, 0.2 mm noise, and about 1 % of the samples missing in gaps of
// 1-60 frames.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "analysis/cleaning/fill.h"
#include "analysis/cleaning/filter.h"
#include "analysis/cleaning/gaps.h"
#include "analysis/cleaning/rigid_fill.h"
#include "analysis/cleaning/spline_fill.h"

namespace {

using namespace csw;
using namespace csw::cleaning;

constexpr double kRate = 100.0;
constexpr int64_t kFrames = 60000;  // 10 minutes
constexpr int kMarkers = 113;

struct SyntheticTake {
  MarkerArray markers;
  std::vector<std::vector<int>> clusters;
};

const SyntheticTake& Take10Minutes() {
  static const SyntheticTake take = [] {
    SyntheticTake t;
    t.markers = MarkerArray(kFrames, kMarkers);
    t.clusters = {{0, 1, 2, 3, 4}, {5, 6, 7, 8, 9}};
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0.0, 0.2);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // Cluster shapes (mm, about their centre).
    std::vector<Eigen::Vector3d> shape[2];
    for (int c = 0; c < 2; ++c)
      for (int i = 0; i < 5; ++i) shape[c].push_back(Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 120);
    // Smooth motion: a few sinusoids per coordinate.
    std::vector<Eigen::Vector3d> amp(kMarkers), freq(kMarkers), phase(kMarkers), base(kMarkers);
    for (int m = 0; m < kMarkers; ++m) {
      for (int k = 0; k < 3; ++k) {
        amp[m](k) = 5 + 40 * u(rng);
        freq[m](k) = 0.2 + 2.5 * u(rng);
        phase[m](k) = 6.283 * u(rng);
        base[m](k) = 1000 * u(rng);
      }
    }
    for (int64_t f = 0; f < kFrames; ++f) {
      const double t_s = static_cast<double>(f) / kRate;
      for (int c = 0; c < 2; ++c) {
        const Eigen::Matrix3d r = (Eigen::AngleAxisd(0.4 * std::sin(0.7 * t_s + c), Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(0.2 * std::sin(1.3 * t_s), Eigen::Vector3d::UnitX()))
                                      .toRotationMatrix();
        const Eigen::Vector3d centre(300 * c + 50 * std::sin(0.5 * t_s), 30 * std::cos(0.9 * t_s), 1200);
        for (int i = 0; i < 5; ++i) {
          const Eigen::Vector3d p = r * shape[c][static_cast<size_t>(i)] + centre;
          float* dst = t.markers.at(f, 5 * c + i);
          for (int k = 0; k < 3; ++k) dst[k] = static_cast<float>(p(k) + noise(rng));
        }
      }
      for (int m = 10; m < kMarkers; ++m) {
        float* dst = t.markers.at(f, m);
        for (int k = 0; k < 3; ++k)
          dst[k] = static_cast<float>(base[m](k) + amp[m](k) * std::sin(6.283 * freq[m](k) * t_s + phase[m](k)) +
                                      noise(rng));
      }
    }
    // Gaps: ~1 % of the samples, lengths 1-60 frames (mostly short).
    std::geometric_distribution<int> length(0.08);
    const int64_t target = kFrames * kMarkers / 100;
    int64_t missing = 0;
    while (missing < target) {
      const int m = static_cast<int>(u(rng) * kMarkers);
      const int64_t len = std::min(60, 1 + length(rng));
      const int64_t start = static_cast<int64_t>(u(rng) * static_cast<double>(kFrames - len));
      for (int64_t f = start; f < start + len; ++f) t.markers.SetMissing(f, m);
      missing += len;
    }
    return t;
  }();
  return take;
}

void BM_GapReport(benchmark::State& state) {
  const SyntheticTake& t = Take10Minutes();
  for (auto _ : state) {
    GapReport r = MakeGapReport(t.markers);
    benchmark::DoNotOptimize(r);
  }
  state.counters["gaps"] = static_cast<double>(MakeGapReport(t.markers).gap_count);
}
BENCHMARK(BM_GapReport)->Unit(benchmark::kMillisecond);

void BM_SplineAndRigidFill(benchmark::State& state) {
  const SyntheticTake& t = Take10Minutes();
  for (auto _ : state) {
    const RigidClusterFiller rigid = RigidClusterFiller::FromMarkers(t.markers, t.clusters);
    const SplineFiller spline{SplineFillOptions{}};
    MarkerArray out;
    FillReport r = FillGaps(t.markers, {&spline, &rigid}, 60, &out);
    benchmark::DoNotOptimize(r);
    state.counters["filled_gaps"] = static_cast<double>(r.filled.size());
  }
}
BENCHMARK(BM_SplineAndRigidFill)->Unit(benchmark::kMillisecond);

void BM_Butterworth(benchmark::State& state) {
  const SyntheticTake& t = Take10Minutes();
  ButterworthOptions o;
  for (auto _ : state) {
    MarkerArray out = ButterworthFilter(t.markers, kRate, o);
    benchmark::DoNotOptimize(out);
  }
}
BENCHMARK(BM_Butterworth)->Unit(benchmark::kMillisecond);

// The whole in-memory cleaning of the take, as `csw clean --fill spline,rigid
// --filter butterworth` runs it.
void BM_CleanTake(benchmark::State& state) {
  const SyntheticTake& t = Take10Minutes();
  for (auto _ : state) {
    GapReport report = MakeGapReport(t.markers);
    benchmark::DoNotOptimize(report);
    const RigidClusterFiller rigid = RigidClusterFiller::FromMarkers(t.markers, t.clusters);
    const SplineFiller spline{SplineFillOptions{}};
    MarkerArray filled;
    FillReport r = FillGaps(t.markers, {&spline, &rigid}, 60, &filled);
    benchmark::DoNotOptimize(r);
    ButterworthFilterInPlace(filled, kRate, ButterworthOptions{});
    benchmark::DoNotOptimize(filled);
  }
}
BENCHMARK(BM_CleanTake)->Unit(benchmark::kMillisecond);

}  // namespace
BENCHMARK_MAIN();

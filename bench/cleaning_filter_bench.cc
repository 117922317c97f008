// Filtering of a 10-minute, 113-marker take at 100 Hz in memory (issue 12:
// cleaning a take, gap report + fills + filter, in under 1 s on one core).
// Synthetic data: each coordinate a random walk (1 mm steps) plus 0.2 mm white
// noise; every marker has 1 % of its frames missing in gaps of 1-30 frames.
// Timed: the zero-phase Butterworth (defaults: order 2, 15 Hz), per-marker
// speeds and accelerations, and both together; the Kalman smoother (ML process
// noise, CA model) for comparison.
#include <benchmark/benchmark.h>

#include <random>

#include "analysis/cleaning/filter.h"

namespace csw::cleaning {
namespace {

constexpr double kRate = 100.0;
constexpr int64_t kFrames = 60000;  // 10 min at 100 Hz
constexpr int64_t kMarkers = 113;

const MarkerArray& BenchTake() {
  static const MarkerArray m = [] {
    std::mt19937_64 rng(12);
    std::normal_distribution<double> step(0, 1.0), noise(0, 0.2);
    std::uniform_int_distribution<int64_t> gap_start(0, kFrames - 31), gap_len(1, 30);
    MarkerArray a(kFrames, kMarkers);
    for (int64_t k = 0; k < kMarkers; ++k) {
      double p[3] = {0, 0, 1000};
      for (int64_t f = 0; f < kFrames; ++f)
        for (int c = 0; c < 3; ++c) {
          p[c] += step(rng);
          a.at(f, k)[c] = static_cast<float>(p[c] + noise(rng));
        }
      int64_t missing = 0;
      while (missing < kFrames / 100) {
        const int64_t s = gap_start(rng), n = gap_len(rng);
        for (int64_t f = s; f < s + n; ++f) a.SetMissing(f, k);
        missing += n;
      }
    }
    return a;
  }();
  return m;
}

void BM_Butterworth(benchmark::State& state) {
  const MarkerArray& m = BenchTake();
  for (auto _ : state) benchmark::DoNotOptimize(ButterworthFilter(m, kRate, ButterworthOptions()));
  state.SetItemsProcessed(state.iterations() * kFrames * kMarkers);
}
BENCHMARK(BM_Butterworth)->Unit(benchmark::kMillisecond);

void BM_ButterworthInPlace(benchmark::State& state) {
  MarkerArray m = BenchTake();
  for (auto _ : state) {
    state.PauseTiming();
    m = BenchTake();  // same pages, refilled
    state.ResumeTiming();
    ButterworthFilterInPlace(m, kRate, ButterworthOptions());
  }
  state.SetItemsProcessed(state.iterations() * kFrames * kMarkers);
}
BENCHMARK(BM_ButterworthInPlace)->Unit(benchmark::kMillisecond);

void BM_Kinematics(benchmark::State& state) {
  const MarkerArray& m = BenchTake();
  for (auto _ : state) benchmark::DoNotOptimize(MarkerKinematics(m, kRate));
  state.SetItemsProcessed(state.iterations() * kFrames * kMarkers);
}
BENCHMARK(BM_Kinematics)->Unit(benchmark::kMillisecond);

void BM_ButterworthAndSpeeds(benchmark::State& state) {
  const MarkerArray& m = BenchTake();
  for (auto _ : state) {
    const MarkerArray f = ButterworthFilter(m, kRate, ButterworthOptions());
    benchmark::DoNotOptimize(MarkerKinematics(f, kRate));
  }
  state.SetItemsProcessed(state.iterations() * kFrames * kMarkers);
}
BENCHMARK(BM_ButterworthAndSpeeds)->Unit(benchmark::kMillisecond);

void BM_KalmanSmoother(benchmark::State& state) {
  const MarkerArray& m = BenchTake();
  for (auto _ : state) benchmark::DoNotOptimize(KalmanSmooth(m, kRate, KalmanOptions()));
  state.SetItemsProcessed(state.iterations() * kFrames * kMarkers);
}
BENCHMARK(BM_KalmanSmoother)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace csw::cleaning

BENCHMARK_MAIN();

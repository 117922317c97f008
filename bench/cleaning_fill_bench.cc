// Gap report and gap fills of a 10-minute, 113-marker take at 100 Hz in
// memory (60,000 frames), one core. Synthetic take: smooth trajectories
// (sums of sinusoids up to 3 Hz, 0.2 mm Gaussian noise) with gaps placed at
// random, 0.1 gap per marker per second (6,780 gaps: about 3× the virtual
// cuer's default dropout rate of 0.03/s, standing in for dropouts plus
// occlusions), lengths 60 % 1-5, 30 % 6-20, 10 % 21-60 frames.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "analysis/cleaning/dct_fill.h"
#include "analysis/cleaning/fill.h"
#include "analysis/cleaning/gaps.h"
#include "analysis/cleaning/spline_fill.h"

namespace {

using namespace csw::cleaning;

constexpr int64_t kFrames = 60000;
constexpr int64_t kMarkers = 113;
constexpr double kRate = 100.0;

const csw::MarkerArray& Take() {
  static const csw::MarkerArray take = [] {
    csw::MarkerArray a(kFrames, kMarkers);
    std::mt19937_64 rng(1);
    std::normal_distribution<double> noise(0.0, 0.2);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int64_t m = 0; m < kMarkers; ++m) {
      double amp[3][3], freq[3][3], phase[3][3];
      for (auto& c : amp)
        for (double& v : c) v = 5 + 40 * u(rng);
      for (auto& c : freq)
        for (double& v : c) v = 0.1 + 2.9 * u(rng);
      for (auto& c : phase)
        for (double& v : c) v = 2 * M_PI * u(rng);
      for (int64_t f = 0; f < kFrames; ++f) {
        const double t = static_cast<double>(f) / kRate;
        float* p = a.at(f, m);
        for (int c = 0; c < 3; ++c) {
          double v = 500.0 * c + static_cast<double>(m);
          for (int k = 0; k < 3; ++k) v += amp[c][k] * std::sin(2 * M_PI * freq[c][k] * t + phase[c][k]);
          p[c] = static_cast<float>(v + noise(rng));
        }
      }
      // Gaps: Poisson, 0.1 per second.
      std::exponential_distribution<double> next(0.1 / kRate);
      for (double f = next(rng); f < static_cast<double>(kFrames); f += next(rng)) {
        const double r = u(rng);
        const int64_t len = r < 0.6   ? 1 + static_cast<int64_t>(u(rng) * 5)
                            : r < 0.9 ? 6 + static_cast<int64_t>(u(rng) * 15)
                                      : 21 + static_cast<int64_t>(u(rng) * 40);
        for (int64_t i = static_cast<int64_t>(f); i < std::min<int64_t>(kFrames, static_cast<int64_t>(f) + len); ++i)
          a.SetMissing(i, m);
      }
    }
    return a;
  }();
  return take;
}

void BM_GapReport(benchmark::State& state) {
  const csw::MarkerArray& take = Take();
  int64_t gaps = 0;
  for (auto _ : state) {
    GapReport r = MakeGapReport(take);
    gaps = r.gap_count;
    benchmark::DoNotOptimize(r);
  }
  state.counters["gaps"] = static_cast<double>(gaps);
}
BENCHMARK(BM_GapReport)->Unit(benchmark::kMillisecond);

void Fill(benchmark::State& state, const GapFiller& filler) {
  const csw::MarkerArray& take = Take();
  csw::MarkerArray out;
  FillReport rep;
  for (auto _ : state) {
    rep = FillGaps(take, {&filler}, 0, &out);
    benchmark::DoNotOptimize(out.data().data());
  }
  state.counters["filled"] = static_cast<double>(rep.filled.size());
  state.counters["unfilled"] = static_cast<double>(rep.unfilled.size());
}

void BM_SplineFillSmoothing(benchmark::State& state) {
  SplineFiller s;  // default: smoothing quintic, GCV, 5 + 30 frames
  Fill(state, s);
}
BENCHMARK(BM_SplineFillSmoothing)->Unit(benchmark::kMillisecond);

void BM_SplineFillSmoothingPerCoordinate(benchmark::State& state) {
  SplineFillOptions o;
  o.per_coordinate = true;
  SplineFiller s(o);
  Fill(state, s);
}
BENCHMARK(BM_SplineFillSmoothingPerCoordinate)->Unit(benchmark::kMillisecond);

void BM_SplineFillInterpolatingCubic(benchmark::State& state) {
  SplineFillOptions o;
  o.kind = SplineKind::kCubic;
  SplineFiller s(o);
  Fill(state, s);
}
BENCHMARK(BM_SplineFillInterpolatingCubic)->Unit(benchmark::kMillisecond);

void BM_DctFill(benchmark::State& state) {
  DctFiller d;
  Fill(state, d);
}
BENCHMARK(BM_DctFill)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();

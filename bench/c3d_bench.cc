// C3D parse throughput: a 60,000-frame x 113-marker float C3D written once with
// WriteC3d into /tmp, then read with C3dReader::ReadFrames in chunks (MB/s of file).
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "io/c3d/c3d.h"

namespace {

constexpr int64_t kFrames = 60000;
constexpr int64_t kMarkers = 113;

const std::string& BenchFile() {
  static const std::string path = [] {
    std::string p = (std::filesystem::temp_directory_path() / "csw_c3d_bench_60000x113.c3d").string();
    csw::Take t;
    t.rate_hz = 200;
    for (int64_t m = 0; m < kMarkers; ++m) t.marker_names.push_back("M" + std::to_string(m));
    t.markers.Resize(kFrames, kMarkers);
    std::vector<float>& d = t.markers.data();
    for (int64_t f = 0; f < kFrames; ++f) {
      for (int64_t m = 0; m < kMarkers; ++m) {
        if ((f + m) % 50 == 0) continue;  // 2 % missing samples
        float* p3 = &d[static_cast<size_t>((f * kMarkers + m) * 3)];
        p3[0] = 100.0f * std::sin(0.01f * static_cast<float>(f + m));
        p3[1] = 100.0f * std::cos(0.013f * static_cast<float>(f)) + static_cast<float>(m);
        p3[2] = 1000.0f + static_cast<float>(m);
      }
    }
    csw::WriteC3d(p, t);
    return p;
  }();
  return path;
}

void BM_C3dReadFrames(benchmark::State& state) {
  const std::string& path = BenchFile();
  const int64_t chunk = state.range(0);
  const int64_t file_bytes = static_cast<int64_t>(std::filesystem::file_size(path));
  std::vector<float> points(static_cast<size_t>(chunk * kMarkers * 3));
  std::vector<float> residuals(static_cast<size_t>(chunk * kMarkers));
  for (auto _ : state) {
    csw::C3dReader reader(path);
    const int64_t frames = reader.info().frames;
    for (int64_t f = 0; f < frames; f += chunk) {
      reader.ReadFrames(f, std::min(chunk, frames - f), points.data(), residuals.data(), nullptr);
      benchmark::DoNotOptimize(points.data());
    }
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(state.iterations() * file_bytes);
}
BENCHMARK(BM_C3dReadFrames)->Arg(1000)->Arg(60000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_C3dValidPointStats(benchmark::State& state) {
  const std::string& path = BenchFile();
  const int64_t file_bytes = static_cast<int64_t>(std::filesystem::file_size(path));
  for (auto _ : state) {
    csw::C3dReader reader(path);
    int64_t n = 0;
    double s = 0;
    reader.ValidPointStats(&n, &s);
    benchmark::DoNotOptimize(s);
  }
  state.SetBytesProcessed(state.iterations() * file_bytes);
}
BENCHMARK(BM_C3dValidPointStats)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_C3dReadTake(benchmark::State& state) {
  const std::string& path = BenchFile();
  const int64_t file_bytes = static_cast<int64_t>(std::filesystem::file_size(path));
  for (auto _ : state) {
    csw::Take t = csw::ReadC3d(path);
    benchmark::DoNotOptimize(t.markers.data().data());
  }
  state.SetBytesProcessed(state.iterations() * file_bytes);
}
BENCHMARK(BM_C3dReadTake)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

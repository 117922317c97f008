// Import throughput (C3D -> HDF5 corpus) and peak RSS of `csw import` on long takes.
// The 113-marker float C3D files are written by the benchmark itself (WriteC3d).
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "core/build_paths.h"
#include "core/take.h"
#include "io/c3d/c3d.h"
#include "workbench/jobs/jobs.h"

namespace {

namespace fs = std::filesystem;

std::string MakeC3d(int64_t frames) {
  fs::path p = fs::temp_directory_path() / ("csw-bench-import-" + std::to_string(frames) + ".c3d");
  if (fs::exists(p)) return p.string();
  csw::Take t;
  t.name = "bench";
  t.rate_hz = 120.0;
  const int64_t markers = 113;
  for (int64_t m = 0; m < markers; ++m) t.marker_names.push_back("M" + std::to_string(m));
  t.markers.Resize(frames, markers);
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < markers; ++m) {
      float* x = t.markers.at(f, m);
      x[0] = static_cast<float>(200.0 * std::sin(0.013 * f + m));
      x[1] = static_cast<float>(150.0 * std::cos(0.007 * f + 0.5 * m));
      x[2] = static_cast<float>(1200.0 + m + 0.01 * f);
    }
    if (f % 97 == 0) t.markers.SetMissing(f, f % markers);
  }
  std::string tmp = p.string() + ".tmp";
  csw::WriteC3d(tmp, t);
  fs::rename(tmp, p);
  return p.string();
}

void BM_ImportC3dIntoCorpus(benchmark::State& state) {
  const int64_t frames = state.range(0);
  std::string c3d = MakeC3d(frames);
  fs::path corpus = fs::temp_directory_path() / "csw-bench-import.h5";
  for (auto _ : state) {
    state.PauseTiming();
    fs::remove(corpus);
    state.ResumeTiming();
    csw::Progress progress;
    csw::jobs::ImportOptions o;
    o.files = {c3d};
    o.corpus = corpus.string();
    csw::jobs::ImportResult r = csw::jobs::Import(o, progress);
    benchmark::DoNotOptimize(r.frames);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(fs::file_size(c3d)));
  state.counters["file_MB"] = static_cast<double>(fs::file_size(c3d)) / 1e6;
  fs::remove(corpus);
}
BENCHMARK(BM_ImportC3dIntoCorpus)->Arg(60000)->Unit(benchmark::kMillisecond)->UseRealTime();

// The whole `csw import` command as a separate process on the same file as
// BM_ImportC3dIntoCorpus: process start-up (dynamic loading), option parsing,
// SHA-256 of the source, C3D parse, corpus write, fsync and exit. Compare its
// MB/s with BM_ImportC3dIntoCorpus (docs/performance.md: goal within 15 %).
void BM_CswImportProcess(benchmark::State& state) {
  const int64_t frames = state.range(0);
  std::string c3d = MakeC3d(frames);
  fs::path corpus = fs::temp_directory_path() / ("csw-bench-process-" + std::to_string(frames) + ".h5");
  for (auto _ : state) {
    state.PauseTiming();
    fs::remove(corpus);
    state.ResumeTiming();
    pid_t pid = fork();
    if (pid == 0) {
      execl(CSW_BINARY, CSW_BINARY, "-q", "import", c3d.c_str(), "-o", corpus.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) state.SkipWithError("csw import failed");
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(fs::file_size(c3d)));
  state.counters["file_MB"] = static_cast<double>(fs::file_size(c3d)) / 1e6;
  fs::remove(corpus);
}
BENCHMARK(BM_CswImportProcess)->Arg(60000)->Unit(benchmark::kMillisecond)->UseRealTime();

// Peak resident memory of a separate `csw import` process: must stay flat as takes grow.
void BM_CswImportPeakRss(benchmark::State& state) {
  const int64_t frames = state.range(0);
  std::string c3d = MakeC3d(frames);
  fs::path corpus = fs::temp_directory_path() / ("csw-bench-rss-" + std::to_string(frames) + ".h5");
  long max_rss_kb = 0;
  for (auto _ : state) {
    fs::remove(corpus);
    pid_t pid = fork();
    if (pid == 0) {
      execl(CSW_BINARY, CSW_BINARY, "-q", "import", c3d.c_str(), "-o", corpus.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    int status = 0;
    struct rusage ru {};
    wait4(pid, &status, 0, &ru);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) state.SkipWithError("csw import failed");
    max_rss_kb = std::max(max_rss_kb, ru.ru_maxrss);
  }
  state.counters["peak_rss_MB"] = static_cast<double>(max_rss_kb) / 1024.0;
  state.counters["file_MB"] = static_cast<double>(fs::file_size(c3d)) / 1e6;
  fs::remove(corpus);
}
BENCHMARK(BM_CswImportPeakRss)
    ->Arg(6000)
    ->Arg(60000)
    ->Arg(240000)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

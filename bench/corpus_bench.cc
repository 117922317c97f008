// Throughput of the HDF5 corpus store: streaming 60,000 frames × 113 markers
// into a new corpus (transaction, chunked writes, shuffle + deflate, commit with
// fsync), and reading a 1,000-frame window back. Format version 2: the cost of
// a commit that replaces one take in a ~20 MB and in a >= 2 GB corpus (should
// be the same), and of a tier-only commit on a 10-minute take. (The corpus
// sizes are ~39 MB and ~3.9 GB: see the corpus_MB counter.)
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/lab_corpus.h"
#include "io/corpus/corpus.h"

namespace {

namespace fs = std::filesystem;
using csw::bench::CachedLabCorpus;
using csw::bench::FolderBytes;
using csw::bench::LabHeader;
using csw::bench::RandomWalk;

constexpr int64_t kFrames = 60000;
constexpr int64_t kMarkers = 113;

// Smooth trajectories with 0.01 mm quantized measurement noise and 2 % of
// samples missing, like a cleaned optical capture at 200 Hz.
const std::vector<float>& CaptureData() {
  static const std::vector<float> data = [] {
    std::vector<float> d(static_cast<size_t>(kFrames * kMarkers * 3));
    uint32_t state = 12345;
    for (int64_t f = 0; f < kFrames; ++f) {
      double t = static_cast<double>(f) / 200.0;
      for (int64_t m = 0; m < kMarkers; ++m) {
        float* p = &d[static_cast<size_t>((f * kMarkers + m) * 3)];
        state = state * 1664525u + 1013904223u;
        if ((state >> 24) < 5 && (f / 50 + m) % 7 == 0) {
          p[0] = p[1] = p[2] = std::nanf("");
          continue;
        }
        for (int k = 0; k < 3; ++k) {
          state = state * 1664525u + 1013904223u;
          double noise = (static_cast<double>(state >> 16) / 65536.0 - 0.5) * 0.1;
          double v = 300.0 * std::sin(0.7 * t + 0.1 * m + k) + 10.0 * m + 1000.0 * (k == 2) + noise;
          p[k] = static_cast<float>(std::round(v * 100.0) / 100.0);
        }
      }
    }
    return d;
  }();
  return data;
}

csw::Take Header(const std::string& name) {
  csw::Take t;
  t.name = name;
  t.rate_hz = 200.0;
  for (int64_t m = 0; m < kMarkers; ++m) t.marker_names.push_back("M" + std::to_string(m));
  return t;
}

double ProcessCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

fs::path BenchDir() {
  fs::path dir = fs::temp_directory_path() / ("csw_corpus_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

void BM_StreamTakeIntoCorpus(benchmark::State& state) {
  const std::vector<float>& data = CaptureData();
  const int64_t block = state.range(0);
  fs::path dir = BenchDir();
  const std::string path = (dir / "stream.h5").string();
  const double cpu_start = ProcessCpuSeconds();
  for (auto _ : state) {
    fs::remove(path);
    fs::remove_all(csw::CorpusTransaction::FolderPath(path));
    csw::CorpusTransaction tx(path);
    csw::CorpusTransaction::TakeWriter w = tx.BeginTake(Header("take"));
    for (int64_t f = 0; f < kFrames; f += block) {
      w.AppendFrames(data.data() + f * kMarkers * 3, std::min(block, kFrames - f));
    }
    w.Finish();
    tx.Commit();
  }
  const double cpu_seconds = ProcessCpuSeconds() - cpu_start;
  const double bytes = static_cast<double>(kFrames * kMarkers * 3 * sizeof(float));
  // Throughput per CPU-second of all threads: what one free core sustains,
  // independent of other load on a shared machine.
  state.counters["MB_per_cpu_s"] = bytes * static_cast<double>(state.iterations()) / 1e6 / cpu_seconds;
  state.SetBytesProcessed(static_cast<int64_t>(bytes) * state.iterations());
  state.counters["MB_per_s"] = benchmark::Counter(bytes / 1e6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["file_MB"] = static_cast<double>(FolderBytes(path)) / 1e6;
  state.counters["ratio"] = bytes / static_cast<double>(FolderBytes(path));
  fs::remove_all(dir);
}
BENCHMARK(BM_StreamTakeIntoCorpus)
    ->Arg(100)
    ->Arg(1000)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

void BM_LoadMarkersWindow(benchmark::State& state) {
  fs::path dir = BenchDir();
  const std::string path = (dir / "read.h5").string();
  {
    csw::CorpusTransaction tx(path);
    csw::CorpusTransaction::TakeWriter w = tx.BeginTake(Header("take"));
    w.AppendFrames(CaptureData().data(), kFrames);
    w.Finish();
    tx.Commit();
  }
  csw::Corpus corpus = csw::Corpus::Open(path);
  int64_t first = 0;
  for (auto _ : state) {
    csw::MarkerArray window = corpus.LoadMarkers("take", first, 1000);
    benchmark::DoNotOptimize(window.data().data());
    first = (first + 7919) % (kFrames - 1000);
  }
  state.SetBytesProcessed(static_cast<int64_t>(1000 * kMarkers * 3 * sizeof(float)) * state.iterations());
  fs::remove_all(dir);
}
BENCHMARK(BM_LoadMarkersWindow)->Unit(benchmark::kMicrosecond)->UseRealTime();

// ---------------------------------------------------------------------------
// Format version 2: commits cost what changed (lab corpora: bench/lab_corpus.h).
// One transaction that replaces one one-minute take, then commits.
void BM_OneTakeCommit(benchmark::State& state) {
  const std::string path = CachedLabCorpus(static_cast<int>(state.range(0)));
  const std::vector<float>& data = csw::bench::SmallTakeData();
  for (auto _ : state) {
    csw::CorpusTransaction tx(path);
    csw::CorpusTransaction::TakeWriter w =
        tx.BeginTake(LabHeader(csw::bench::kSmallTakeName), csw::IfTakeExists::kReplace);
    w.AppendFrames(data.data(), csw::bench::kSmallTakeFrames);
    w.Finish();
    tx.Commit();
  }
  state.counters["corpus_MB"] = static_cast<double>(FolderBytes(path)) / 1e6;
  state.counters["index_KB"] = static_cast<double>(fs::file_size(path)) / 1e3;
}
BENCHMARK(BM_OneTakeCommit)->Arg(1)->Arg(100)->ArgName("big_takes")->Unit(benchmark::kMillisecond)->UseRealTime();

// Autosave of a phone tier (6000 labels) on a 10-minute take (120 Hz × 600 s
// × 60 markers): a new tiers file and a new index, nothing else.
void BM_TierOnlyCommit(benchmark::State& state) {
  fs::path dir = BenchDir();
  const std::string path = (dir / "tiers.h5").string();
  constexpr int64_t kFrames10Min = 72000;
  {
    csw::CorpusTransaction tx(path);
    csw::CorpusTransaction::TakeWriter w = tx.BeginTake(LabHeader("session"));
    const std::vector<float> data = RandomWalk(kFrames10Min, 3);
    w.AppendFrames(data.data(), kFrames10Min);
    w.Finish();
    tx.Commit();
  }
  csw::LabelTier phones;
  phones.name = "phones";
  phones.end_s = 600.0;
  const char* symbols[] = {"a", "ʁ", "é", "ɔ̃", "s", "t", "m", "i", "u", "ɛ"};
  for (int i = 0; i < 6000; ++i) phones.labels.push_back({i * 0.1, (i + 1) * 0.1, symbols[i % 10]});
  int edit = 0;
  for (auto _ : state) {
    phones.labels[static_cast<size_t>(edit % 6000)].text = "e" + std::to_string(edit);
    ++edit;
    csw::CorpusTransaction tx(path);
    tx.WriteTiers("session", {phones});
    tx.Commit();
  }
  state.counters["take_MB"] = static_cast<double>(FolderBytes(path)) / 1e6;
  state.counters["index_KB"] = static_cast<double>(fs::file_size(path)) / 1e3;
  fs::remove_all(dir);
}
BENCHMARK(BM_TierOnlyCommit)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

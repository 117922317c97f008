#pragma once
// A lab-sized corpus for the storage benchmarks (bench_corpus, bench_gui):
// big takes of random-walk marker trajectories, which compress about as real
// captures do, built once and kept in the temporary folder for later runs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "io/corpus/corpus.h"

namespace csw::bench {

inline constexpr int64_t kLabMarkers = 60;
inline constexpr double kLabRate = 120.0;
// Frames of a big take: 100,000 frames × 60 markers (14 min at 120 Hz), a ~39 MB data file.
inline constexpr int64_t kBigTakeFrames = 100000;
// The small take every cached corpus holds besides its big ones: one minute.
inline constexpr int64_t kSmallTakeFrames = 7200;
inline constexpr const char* kSmallTakeName = "zz_edited";

// Random-walk trajectories (0.01 mm quantized steps of about 0.3 mm per frame,
// like slow facial markers) with 1 % missing samples.
inline std::vector<float> RandomWalk(int64_t frames, uint32_t seed) {
  std::vector<float> d(static_cast<size_t>(frames * kLabMarkers * 3));
  std::vector<double> pos(static_cast<size_t>(kLabMarkers * 3));
  uint32_t state = seed;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / 16777216.0;
  };
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = 1000.0 * next();
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < kLabMarkers; ++m) {
      float* p = &d[static_cast<size_t>((f * kLabMarkers + m) * 3)];
      const bool missing = next() < 0.01;
      for (int k = 0; k < 3; ++k) {
        double& x = pos[static_cast<size_t>(m * 3 + k)];
        x += (next() - 0.5) * 0.6;
        p[k] = missing ? std::nanf("") : static_cast<float>(std::round(x * 100.0) / 100.0);
      }
    }
  }
  return d;
}

inline Take LabHeader(const std::string& name) {
  Take t;
  t.name = name;
  t.rate_hz = kLabRate;
  for (int64_t m = 0; m < kLabMarkers; ++m) t.marker_names.push_back("M" + std::to_string(m));
  return t;
}

inline const std::vector<float>& SmallTakeData() {
  static const std::vector<float> d = RandomWalk(kSmallTakeFrames, 11);
  return d;
}

// Bytes of a corpus: the index and its folder of take files (format version 2).
inline uint64_t FolderBytes(const std::string& corpus) {
  uint64_t total = std::filesystem::file_size(corpus);
  for (const auto& e : std::filesystem::directory_iterator(CorpusTransaction::FolderPath(corpus)))
    total += e.file_size();
  return total;
}

// A corpus of `takes` big takes (~39 MB each: 30 takes ≈ 1.2 GB, 100 ≈ 3.9 GB)
// plus the one-minute take kSmallTakeName, built once and kept in the
// temporary folder (csw_bench_corpus_<takes>/corpus.h5).
inline std::string CachedLabCorpus(int takes) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("csw_bench_corpus_" + std::to_string(takes));
  const std::string path = (dir / "corpus.h5").string();
  std::error_code ec;
  if (fs::exists(path, ec)) {
    try {
      if (Corpus::Open(path).Takes().size() == static_cast<size_t>(takes) + 1) return path;
    } catch (const std::exception&) {
    }
  }
  fs::remove_all(dir, ec);
  fs::create_directories(dir);
  static const std::vector<float> big = RandomWalk(kBigTakeFrames, 7);
  CorpusTransaction tx(path);
  for (int i = 0; i < takes; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "take%03d", i);
    CorpusTransaction::TakeWriter w = tx.BeginTake(LabHeader(name));
    w.AppendFrames(big.data(), kBigTakeFrames);
    w.Finish();
  }
  CorpusTransaction::TakeWriter w = tx.BeginTake(LabHeader(kSmallTakeName));
  w.AppendFrames(SmallTakeData().data(), kSmallTakeFrames);
  w.Finish();
  tx.Commit();
  return path;
}

}  // namespace csw::bench

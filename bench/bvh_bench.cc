// BVH throughput: ParseBvh (text already in memory) and FormatBvh on a
// synthetic 31-joint body (the CMU/fairmotion layout: a 6-channel root, 30
// 3-channel joints in ZYX order, 7 end sites: 96 values per row) of 100,000
// frames (~60 MB of text), plus ReadBvh of one real 2,752-frame export when
// ../shared/data is present.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "io/formats/bvh.h"

namespace {

std::string SyntheticBvh(int64_t frames) {
  std::string h =
      "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation "
      "Yrotation Xrotation\n";
  int joint = 0;
  // 5 limbs of 6 joints each (legs, spine+head, arms), each ending in an end site,
  // plus 2 extra end sites on the last limb: 30 joints, 7 end sites.
  for (int limb = 0; limb < 5; ++limb) {
    for (int k = 0; k < 6; ++k, ++joint) {
      const std::string indent(static_cast<size_t>(k + 1), '\t');
      h += indent + "JOINT J" + std::to_string(joint) + "\n" + indent + "{\n" + indent + "\tOFFSET " +
           std::to_string(limb - 2) + " " + std::to_string(limb == 2 ? 9 : -8) + " 0.5\n" + indent +
           "\tCHANNELS 3 Zrotation Yrotation Xrotation\n";
    }
    const std::string indent(7, '\t');
    const int sites = limb == 4 ? 3 : 1;
    for (int s = 0; s < sites; ++s)
      h += indent + "End Site\n" + indent + "{\n" + indent + "\tOFFSET 0 -2 1\n" + indent + "}\n";
    for (int k = 5; k >= 0; --k) h += std::string(static_cast<size_t>(k + 1), '\t') + "}\n";
  }
  h += "}\nMOTION\nFrames: " + std::to_string(frames) + "\nFrame Time: .0083333\n";
  std::string text = h;
  text.reserve(h.size() + static_cast<size_t>(frames) * 96 * 10);
  char buf[32];
  for (int64_t f = 0; f < frames; ++f) {
    for (int c = 0; c < 96; ++c) {
      const double v = c < 3 ? 10.0 * std::sin(0.01 * static_cast<double>(f) + c)
                             : 60.0 * std::sin(0.003 * static_cast<double>(f) * (1 + c % 7) + c);
      const int n = std::snprintf(buf, sizeof(buf), c == 0 ? "%.6f" : " %.6f", v);
      text.append(buf, static_cast<size_t>(n));
    }
    text += '\n';
  }
  return text;
}

const std::string& Text() {
  static const std::string text = SyntheticBvh(100000);
  return text;
}

void BM_BvhRead(benchmark::State& state) {
  const std::string& text = Text();
  csw::BvhReadOptions options;
  options.units = "cm";
  int64_t frames = 0;
  for (auto _ : state) {
    csw::Take take = csw::ParseBvh(text, "synthetic.bvh", options);
    frames = take.frames();
    benchmark::DoNotOptimize(take.markers.data().data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(text.size()));
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(frames) * static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate);
  state.counters["MB"] = static_cast<double>(text.size()) / 1e6;
}
BENCHMARK(BM_BvhRead)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_BvhWrite(benchmark::State& state) {
  csw::BvhReadOptions options;
  options.units = "cm";
  const csw::Take take = csw::ParseBvh(Text(), "synthetic.bvh", options);
  size_t bytes = 0;
  for (auto _ : state) {
    std::string out = csw::FormatBvh(take);
    bytes = out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(bytes));
  state.counters["frames/s"] = benchmark::Counter(
      static_cast<double>(take.frames()) * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BvhWrite)->Unit(benchmark::kMillisecond)->Iterations(3);

// A real file from disk (fairmotion's CMU 01_01: 31 joints, 2,752 frames).
void BM_BvhReadFairmotion(benchmark::State& state) {
  const char* env = std::getenv("CSW_SHARED_DATA");
  const std::filesystem::path path =
      std::filesystem::path(env != nullptr ? env : "../shared/data") / "bvh/fairmotion/01_01.bvh";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("missing " + path.string()).c_str());
    return;
  }
  csw::BvhReadOptions options;
  options.units = "in";
  for (auto _ : state) {
    csw::Take take = csw::ReadBvh(path.string(), options);
    benchmark::DoNotOptimize(take.markers.data().data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(std::filesystem::file_size(path)));
}
BENCHMARK(BM_BvhReadFairmotion)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

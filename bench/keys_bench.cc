// Gestural score: posteriors of the 15 key Gaussians (9 shapes on the 7 hand
// distances, 6 placements on the 3D placement feature) per frame (issue 11:
// >= 1,000,000 frames/s on one core). Synthetic model and frames: classes with
// random means and covariances; 100,000 frames drawn around them.
//   BM_KeyPosteriorsComplete: every feature observed (the Cholesky fast path);
//   BM_KeyPosteriorsOneMissing: one of the 7 distances missing on every frame
//     (marginalised: sub-covariance factorised per frame);
//   BM_ScoreFrames: the whole ScoreFrames (shape posteriors, placement feature
//     chosen by the most probable shape, placement posteriors, closeness).
// End to end on the embedded demo corpus (datasets/demo/sentences: 20 cued
// sentences, 113 markers, imported once into a temporary corpus; the key model
// trained on its first 7 sentences' label tiers):
//   BM_KeysScoreDemo/dry: `csw keys score` on the 20 sentences, report only
//     (read takes, hand features, posteriors, decodings, accuracies);
//   BM_KeysScoreDemo/write: the same writing the tiers and the posterior
//     score sets into the corpus (one transaction per run).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "analysis/keys/key_model.h"
#include "core/build_paths.h"
#include "core/progress.h"
#include "io/corpus/corpus.h"
#include "workbench/jobs/import_job.h"
#include "workbench/jobs/keys_job.h"

namespace csw::keys {
namespace {

constexpr int64_t kFrames = 100000;

const KeyModel& Model() {
  static const KeyModel m = [] {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> n01;
    KeyTrainingSet set;
    set.shape_samples.resize(9 * 50, kNumDistances);
    set.placement_samples.resize(6 * 50, 3);
    for (int i = 0; i < 9 * 50; ++i) {
      for (int d = 0; d < kNumDistances; ++d) set.shape_samples(i, d) = 8.0 * ((i % 9) * (d + 1) % 7) + 3 * n01(rng);
      set.shape_labels.push_back(i % 9);
    }
    for (int i = 0; i < 6 * 50; ++i) {
      for (int d = 0; d < 3; ++d) set.placement_samples(i, d) = 25.0 * ((i % 6) * (d + 2) % 5) + 5 * n01(rng);
      set.placement_labels.push_back(i % 6);
    }
    HandLayout layout;
    layout.proximal = {"T1", "I1", "M1", "R1", "L1"};
    layout.distal = {"TT", "IT", "MT", "RT", "LT"};
    layout.palm = {"P1", "P2", "P3"};
    layout.head = {"H1", "H2", "H3"};
    return TrainKeyModel(set, layout, Eigen::Matrix3Xd::Zero(3, 3), {});
  }();
  return m;
}

HandFeatures Frames(bool one_missing) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  HandFeatures f;
  f.distances.resize(kFrames, kNumDistances);
  f.index_tip.resize(kFrames, 3);
  f.middle_tip.resize(kFrames, 3);
  for (int64_t t = 0; t < kFrames; ++t) {
    const int k = static_cast<int>(t % 9);
    for (int d = 0; d < kNumDistances; ++d) f.distances(t, d) = 8.0 * (k * (d + 1) % 7) + 3 * n01(rng);
    if (one_missing) f.distances(t, t % kNumDistances) = std::numeric_limits<double>::quiet_NaN();
    for (int d = 0; d < 3; ++d) {
      f.index_tip(t, d) = 25.0 * ((t % 6) * (d + 2) % 5) + 5 * n01(rng);
      f.middle_tip(t, d) = f.index_tip(t, d) + 1;
    }
  }
  return f;
}

void Posteriors(benchmark::State& state, bool one_missing) {
  const KeyModel& m = Model();
  const HandFeatures f = Frames(one_missing);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> x = f.distances, y = f.index_tip;
  std::vector<double> out(16);
  for (auto _ : state) {
    double sum = 0;
    for (int64_t t = 0; t < kFrames; ++t) {
      m.shape.Posterior(x.row(t).data(), out.data());
      m.placement.Posterior(y.row(t).data(), out.data() + kNumShapes);
      sum += out[0] + out[kNumShapes];
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * kFrames);
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kFrames), benchmark::Counter::kIsRate);
}

void BM_KeyPosteriorsComplete(benchmark::State& state) { Posteriors(state, false); }
void BM_KeyPosteriorsOneMissing(benchmark::State& state) { Posteriors(state, true); }

void BM_ScoreFrames(benchmark::State& state) {
  const KeyModel& m = Model();
  const HandFeatures f = Frames(false);
  for (auto _ : state) benchmark::DoNotOptimize(ScoreFrames(m, f));
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kFrames), benchmark::Counter::kIsRate);
}

// The demo sentences imported into a temporary corpus, and a key model.
struct Demo {
  std::filesystem::path dir;
  std::string corpus, keys;
  int64_t frames = 0;
  Demo() {
    dir = std::filesystem::temp_directory_path() / ("csw-keys-bench-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    corpus = (dir / "demo.h5").string();
    keys = (dir / "keys.h5").string();
    const std::filesystem::path src = std::filesystem::path(CSW_SOURCE_DIR) / "datasets/demo/sentences";
    Progress progress;
    jobs::ImportOptions io;
    for (const auto& e : std::filesystem::directory_iterator(src)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".c3d" || ext == ".TextGrid") io.files.push_back(e.path().string());
    }
    io.corpus = corpus;
    io.markerset = (src / "markerset.json").string();
    frames = jobs::Import(io, progress).frames;
    jobs::KeysTrainOptions t;
    t.corpus = corpus;
    t.takes = {"sentence_00[1-7]"};
    t.output = keys;
    jobs::KeysTrain(t, progress);
  }
  ~Demo() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

void BM_KeysScoreDemo(benchmark::State& state) {
  static const Demo demo;
  jobs::KeysScoreOptions o;
  o.corpus = demo.corpus;
  o.keys = demo.keys;
  o.dry_run = state.range(0) == 0;
  Progress progress;
  for (auto _ : state) benchmark::DoNotOptimize(jobs::KeysScore(o, progress));
  state.SetLabel(o.dry_run ? "dry-run" : "writes tiers and scores");
  state.counters["frames"] = static_cast<double>(demo.frames);
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * demo.frames), benchmark::Counter::kIsRate);
}

BENCHMARK(BM_KeyPosteriorsComplete)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KeyPosteriorsOneMissing)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScoreFrames)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KeysScoreDemo)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace csw::keys

BENCHMARK_MAIN();

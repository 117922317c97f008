// Synthesis speed (issue 15: >= 50x real time on one core for dictionaries
// built from the demo corpus, video rendering timed separately). Set-up, once:
// the embedded demo sentences (datasets/demo/sentences: 20 cued sentences,
// 113 markers) imported into a temporary corpus, face and hand models fitted
// on them, the dictionaries built from their labelled key tiers; the five
// first held-out sentences (datasets/unseen_sentences_fr.txt) phonetised by
// espeak-ng.
//   BM_Synthesize/0: phones -> keys -> timing plan -> dikeys and diphones
//     selected and concatenated -> every model marker, the five sentences per
//     iteration; counter "realtime" = seconds of speech per second of CPU.
//   BM_Synthesize/1: the same with the face from seed-003 fragments.
//   BM_Phonetise: espeak-ng's phones and audio for the same sentences (not
//     part of the 50x target: espeak-ng's own cost).
//   BM_PointLightVideo: the point-light MP4 of the first synthesised sentence
//     (25 fps, 640 x 720, silent); counter "realtime" as above.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>

#include "core/build_paths.h"
#include "core/progress.h"
#include "io/dictionary/dictionary_file.h"
#include "io/models/model_file.h"
#include "synth/synthesizer.h"
#include "workbench/jobs/dict_job.h"
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/import_job.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/video_job.h"

namespace csw {
namespace {

namespace fs = std::filesystem;

struct Demo {
  fs::path dir;
  ModelFile models;
  dict::Dictionary dictionary;
  std::vector<std::string> texts;
  std::vector<Utterance> utterances;
  double speech_s = 0;
  Demo() {
    dir = fs::temp_directory_path() / ("csw-synth-bench-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string corpus = (dir / "demo.h5").string(), model_file = (dir / "models.h5").string();
    const std::string dict_file = (dir / "dict.h5").string();
    const fs::path src = fs::path(CSW_SOURCE_DIR) / "datasets/demo/sentences";
    Progress progress;
    jobs::ImportOptions io;
    for (const auto& e : fs::directory_iterator(src)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".c3d" || ext == ".TextGrid") io.files.push_back(e.path().string());
    }
    io.corpus = corpus;
    io.markerset = (src / "markerset.json").string();
    jobs::Import(io, progress);
    for (const char* kind : {"face", "hand"}) {
      jobs::FitOptions fo;
      fo.corpus = corpus;
      fo.kind = kind;
      fo.output = model_file;
      jobs::Fit(fo, progress);
    }
    jobs::DictBuildOptions d;
    d.corpus = corpus;
    d.models = model_file;
    d.output = dict_file;
    d.tier = "keys";
    jobs::DictBuild(d, progress);
    models = LoadModelFile(model_file);
    dictionary = LoadDictionaryFile(dict_file);
    const std::vector<std::string> unseen =
        jobs::ReadSentences((fs::path(CSW_SOURCE_DIR) / "datasets/unseen_sentences_fr.txt").string());
    texts.assign(unseen.begin(), unseen.begin() + 5);
    for (const std::string& t : texts) {
      PhonetiseOptions po;
      po.rate_wpm = dict::MatchSpeakingRate(t, dict::MeanPhoneDuration(dictionary));
      utterances.push_back(Phonetise(t, po));
      speech_s += utterances.back().duration_s();
    }
  }
  ~Demo() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

const Demo& TheDemo() {
  static const Demo demo;
  return demo;
}

// Arg 0: the face from diphones (Viterbi); 1: from seed-003 fragments
// (greedy longest match, RBF resampling, blended overlaps).
void BM_Synthesize(benchmark::State& state) {
  const Demo& d = TheDemo();
  dict::SynthesisOptions options;
  options.face_fragments = state.range(0) == 1;
  int64_t frames = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < d.utterances.size(); ++i) {
      const dict::Synthesis s =
          dict::Synthesize(d.utterances[i], d.dictionary, *d.models.face, *d.models.hand, options, d.texts[i]);
      frames += s.take.frames();
      benchmark::DoNotOptimize(s.take.markers.data());
    }
  }
  state.counters["realtime"] =
      benchmark::Counter(d.speech_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Synthesize)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_Phonetise(benchmark::State& state) {
  const Demo& d = TheDemo();
  for (auto _ : state) {
    for (const std::string& t : d.texts) benchmark::DoNotOptimize(Phonetise(t).phones.data());
  }
  state.counters["realtime"] =
      benchmark::Counter(d.speech_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Phonetise)->Unit(benchmark::kMillisecond);

void BM_PointLightVideo(benchmark::State& state) {
  const Demo& d = TheDemo();
  const dict::Synthesis s =
      dict::Synthesize(d.utterances[0], d.dictionary, *d.models.face, *d.models.hand, {}, d.texts[0]);
  const std::string path = (d.dir / "video.mp4").string();
  PointLightOptions o;
  for (auto _ : state) benchmark::DoNotOptimize(jobs::WriteTakeVideo(s.take, nullptr, path, o, "", nullptr).frames);
  state.counters["realtime"] =
      benchmark::Counter(s.take.duration_s() * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PointLightVideo)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace csw

BENCHMARK_MAIN();

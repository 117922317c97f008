// Issue 15's acceptance run (left out of the sanitizer stage by its name):
// the 170 coverage sentences (datasets/coverage_sentences_fr.txt) simulated
// by the virtual cuer; face and hand models, a key recogniser and the
// dictionaries built from them; then the 30 held-out sentences
// (datasets/unseen_sentences_fr.txt) synthesised with per-dikey phasing and
// closed through the recogniser. Bars (the "done when"):
//   - the dictionary holds every placement and shape succession of the
//     corpus's own key tiers;
//   - key accuracy through the recogniser (free decoding aligned to the
//     intended keys) at least 95 % (the bar), and at least the
//     recogniser's own accuracy on the corpus's takes (85.8 %: it reads only
//     83 % of the corpus's placements at their labelled targets, the keys
//     the cuer only approached between fast syllables). Measured 96.6 %
//     (at the planned targets 97.3 %) with the key posture pull
//     (ConcatOptions::posture_radius 0.5: each key's hand moved toward its
//     code's exemplar) and trimmed units starting at their key's posture
//     (ConcatOptions::trim_keeps_key_posture); 89.4 % with neither, 92.8 %
//     with the second alone, 94.9 % with the first alone, 80.9 % before the
//     target cost (ConcatOptions::target_weight) that keeps units cut at
//     approached keys out of the selection;
//   - p99 of the frame-to-frame marker jumps <= 1.1 x the corpus's p99 and
//     the maximum <= the corpus's maximum (the bars; measured 16.9 mm
//     against 15.4 mm, and 34.0 mm against 34.0 mm: the synthesizer's speed
//     limit, synth/marker_synthesis.h LimitMarkerSpeed, spreads the movements
//     that a short slot made faster than the corpus's fastest; 43.6 mm = 1.28
//     x without it; 34.3 mm when the limit could not spread a stretch already
//     moving at one speed, before it widened its smoothing);
//   - CV placement and shape targets (kinematic, relative to A1) within 20 ms
//     of the corpus's means (per-dikey phasing; the bar; measured
//     17.4 and 16.0 ms off; 20.1 and 21.6 ms when too-short slots pushed
//     every later target instead of the least-squares spacing of
//     PlanOptions::least_squares_spacing).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/labels.h"
#include "core/markerset.h"
#include "datasets/virtual_cuer.h"
#include "io/corpus/corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/dict_job.h"
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/phasing_job.h"
#include "workbench/jobs/say_job.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

TEST(SayAcceptance, ThirtyUnseenSentencesFromTheCoverageCorpus) {
  const std::vector<std::string> coverage =
      ReadSentences((testing::SourceDir() / "datasets/coverage_sentences_fr.txt").string());
  const std::vector<std::string> unseen =
      ReadSentences((testing::SourceDir() / "datasets/unseen_sentences_fr.txt").string());
  ASSERT_GE(coverage.size(), 150u);
  ASSERT_EQ(unseen.size(), 30u);
  for (const std::string& u : unseen)
    ASSERT_EQ(std::count(coverage.begin(), coverage.end(), u), 0) << "'" << u << "' is in the corpus";

  testing::TempDir dir;
  const std::string corpus = (dir / "c.h5").string(), models = (dir / "models.h5").string();
  const std::string keys = (dir / "keys.h5").string(), dictionary = (dir / "dict.h5").string();
  SimulateOptions so;
  so.audio = false;
  so.occlusions = false;
  const VirtualCuer cuer(so);
  const std::string set = MarkerSetToJson(cuer.MakeMarkerSet());
  // The corpus's own successions, from the key tiers the simulator wrote.
  std::set<std::pair<int, int>> placements, shapes;
  {
    CorpusTransaction tx(corpus);
    for (size_t i = 0; i < coverage.size(); ++i) {
      SimulationResult r = cuer.SimulateSentence("s" + std::to_string(i), coverage[i]);
      r.take.markerset_json = set;
      for (const LabelTier& t : r.take.tiers) {
        if (t.name != "keys") continue;
        const std::vector<KeyMark> marks = ReadKeyTier(t, r.take.name);
        for (size_t k = 0; k + 1 < marks.size(); ++k) {
          if (marks[k].code.placement != marks[k + 1].code.placement)
            placements.insert({marks[k].code.placement, marks[k + 1].code.placement});
          if (marks[k].code.shape != marks[k + 1].code.shape)
            shapes.insert({marks[k].code.shape, marks[k + 1].code.shape});
        }
      }
      tx.WriteTake(r.take);
    }
    tx.Commit();
  }
  Progress progress;
  for (const char* kind : {"face", "hand"}) {
    FitOptions fo;
    fo.corpus = corpus;
    fo.kind = kind;
    fo.output = models;
    Fit(fo, progress);
  }
  KeysTrainOptions kt;
  kt.corpus = corpus;
  kt.takes = {"s*"};
  kt.output = keys;
  KeysTrain(kt, progress);
  DictBuildOptions db;
  db.corpus = corpus;
  db.models = models;
  db.keys = keys;
  db.output = dictionary;
  db.tier = "keys";
  const json built = DictBuild(db, progress);
  // Every succession of the corpus is in the dictionary.
  const json& counts_p = built["coverage"]["dictionary"]["placement"]["counts"];
  const json& counts_s = built["coverage"]["dictionary"]["shape"]["counts"];
  for (const auto& [a, b] : placements) EXPECT_GT(counts_p[a][b].get<int>(), 0) << "placement " << a << "->" << b;
  for (const auto& [a, b] : shapes) EXPECT_GT(counts_s[a][b].get<int>(), 0) << "shape " << a << "->" << b;
  EXPECT_GE(placements.size(), 30u);
  EXPECT_GE(shapes.size(), 70u);

  // The corpus's phasing, as csw phasing measures it.
  PhasingOptions po;
  po.corpus = corpus;
  po.keys = keys;
  const json corpus_phasing = Phasing(po, progress);
  // The recogniser on the corpus's own takes (the first 40), read as csw say
  // reads the synthesised ones: free decoding against the cued keys.
  KeysScoreOptions ks;
  ks.corpus = corpus;
  ks.keys = keys;
  for (int i = 0; i < 40; ++i) ks.takes.push_back("s" + std::to_string(i));
  ks.dry_run = true;
  const json scored = KeysScore(ks, progress);
  const double corpus_accuracy = scored["sequence"]["free"]["keys_correct"].get<double>() /
                                 scored["sequence"]["free"]["keys_expected"].get<double>();
  const std::string phasing_file = (dir / "corpus_phasing.json").string();
  std::ofstream(phasing_file) << corpus_phasing.dump();

  SayOptions say;
  say.texts = unseen;
  say.dict = dictionary;
  say.models = models;
  say.keys = keys;
  say.check = true;
  say.video = false;
  say.corpus_phasing = phasing_file;
  say.output = (dir / "say").string();
  const json r = Say(say, progress);
  const json& check = r["check"];
  std::cout << "fallback: " << r["fallback"].dump() << "\ncheck: " << check.dump(1) << "\n";
  std::cout << "recogniser on the corpus: " << corpus_accuracy << "\n";
  EXPECT_GE(check["keys"]["accuracy"].get<double>(), corpus_accuracy);
  EXPECT_GE(check["keys"]["accuracy"].get<double>(), 0.95);
  EXPECT_GE(check["keys"]["at_targets"]["accuracy"].get<double>(), 0.95);
  const json& c = check["continuity"];
  EXPECT_LE(c["p99_jump_mm"].get<double>(), 1.1 * c["corpus_p99_jump_mm"].get<double>());
  EXPECT_LE(c["max_jump_mm"].get<double>(), c["corpus_max_jump_mm"].get<double>());
  // Every key was synthesised from whole dikeys or the seed's fallback.
  EXPECT_EQ(r["fallback"]["interpolated"], 0);
  // Gesture targets within 20 ms of the corpus's, for every key type (lone
  // vowels: 15 keys, their phasing pooled with lone vowels' only).
  for (const char* type : {"CV", "V", "C"}) {
    const json& t = check["timing"][type];
    for (const char* landmark : {"placement_target_ms", "shape_target_ms"}) {
      ASSERT_TRUE(t[landmark].is_number()) << type << " " << landmark;
      ASSERT_TRUE(t[std::string("corpus_") + landmark].is_number()) << type << " " << landmark;
      EXPECT_NEAR(t[landmark].get<double>(), t[std::string("corpus_") + landmark].get<double>(), 20.0)
          << type << " " << landmark;
    }
  }
}

}  // namespace
}  // namespace csw::jobs

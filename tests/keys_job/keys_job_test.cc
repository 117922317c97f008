#include "workbench/jobs/keys_job.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "analysis/keys/hand_features.h"
#include "core/build_paths.h"
#include "core/error.h"
#include "core/markerset.h"
#include "datasets/virtual_cuer.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "tests/keys_job/cuer_corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

TEST(KeysOptionsCheck, RequiredOptionsAndReasons) {
  KeysTrainOptions t;
  EXPECT_EQ(t.Check(), "no corpus given");
  t.corpus = "c.h5";
  EXPECT_EQ(t.Check(), "--takes: name the training takes");
  t.takes = {"a"};
  EXPECT_EQ(t.Check(), "-o: no output model file");
  t.output = "k.h5";
  EXPECT_EQ(t.Check(), "");
  t.model.shape.min_variance = 0;
  EXPECT_EQ(t.Check(), "shape model: min_variance must be > 0");
  KeysScoreOptions s;
  s.corpus = "c.h5";
  EXPECT_EQ(s.Check(), "--keys: no key model file");
  s.keys = "k.h5";
  EXPECT_EQ(s.Check(), "");
  s.decode.min_key_ms = -1;
  EXPECT_EQ(s.Check(), "min_key_ms must be > 0");
  s.decode.min_key_ms = 80;
  s.decode.aligned_floor = 0;  // --aligned-floor 0
  EXPECT_EQ(s.Check(), "aligned_floor must be in (0, 1)");
  s.decode.aligned_floor = 3e-3;
  s.fit_sd_factor = -0.5;  // --fit-sd-factor -0.5
  EXPECT_EQ(s.Check(), "--fit-sd-factor must be >= 0");
  s.fit_sd_factor = 0;  // off
  EXPECT_EQ(s.Check(), "");
}

TEST(KeysText, RendersTheScoreReport) {
  const json r = {
      {"takes",
       {{{"take", "s1"},
         {"frames", 500},
         {"decoded_keys", 12},
         {"shape_accuracy", 0.9},
         {"placement_accuracy", 0.8},
         {"free_keys_correct", 9},
         {"aligned_keys_correct", 7},
         {"keys_expected", 10}}}},
      {"shape", {{"accuracy", 0.9}, {"count", 10}}},
      {"placement", {{"accuracy", 0.8}, {"count", 10}}},
      {"sequence",
       {{"free",
         {{"keys_correct", 9}, {"keys_expected", 10}, {"insertions", 2}, {"deletions", 0}, {"substitutions", 1}}},
        {"aligned",
         {{"keys_correct", 7}, {"keys_expected", 10}, {"target_error_ms", {{"mean", 31.25}, {"sd", 12.5}}}}}}}};
  EXPECT_EQ(KeysScoreText(r),
            "take s1: 500 frames, 12 keys decoded; shape 90.0 %, placement 80.0 %, free 9/10, aligned 7/10\n"
            "shape accuracy 90.0 % of 10 labelled frames; placement 80.0 % of 10\n"
            "free decoding: 9 of 10 keys, 2 insertions, 0 deletions, 1 substitutions\n"
            "aligned decoding: 7 of 10 keys within 40 ms; target error 31.2 ms (sd 12.5)\n");
  // With the decoding options the job reports (csw keys score --json).
  json with = r;
  with["decoding"] = {
      {"min_key_ms", 80.0}, {"aligned_floor", 0.003}, {"anchor_nearest", false}, {"fit_sd_factor", 4.0}};
  EXPECT_EQ(KeysScoreText(with).substr(KeysScoreText(r).size()),
            "decoding options: shortest free key 80 ms, aligned floor 0.003, targets nearer a neighbour's A1 + lag "
            "kept, fit sd factor 4\n");
  with["decoding"]["keep_in_class"] = false;
  EXPECT_EQ(KeysScoreText(with).substr(KeysScoreText(r).size()),
            "decoding options: shortest free key 80 ms, aligned floor 0.003, targets nearer a neighbour's A1 + lag "
            "kept, fit sd factor 4, fits in the key's class not kept\n");
}

// Six virtual-cuer sentences (no occlusions, so every feature is observed):
// four to train on, two to score.
struct Fixture : testing::CuerCorpus {
  Fixture() : CuerCorpus(6) {}
};

TEST(KeysJob, TrainsScoresAndWritesTheDecodedTiers) {
  Fixture fx;
  Progress progress;
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s[0-3]"};
  t.output = fx.keys;
  const json tr = KeysTrain(t, progress);
  ASSERT_EQ(tr["takes"].size(), 4u);
  const Take s0 = Corpus::Open(fx.corpus).LoadTake("s0");
  size_t labels = 0;
  for (const auto& tier : s0.tiers)
    if (tier.name == "keys") labels = tier.labels.size();
  EXPECT_EQ(tr["takes"][0]["shape_targets"].get<size_t>(), labels);
  EXPECT_EQ(tr["takes"][0]["placement_tier"], "placement_targets");
  ASSERT_TRUE(LoadModelFile(fx.keys).keys.has_value());
  EXPECT_EQ(LoadModelFile(fx.keys).keys->info.training_takes.size(), 4u);

  KeysScoreOptions s;
  s.corpus = fx.corpus;
  s.keys = fx.keys;
  s.takes = {"s4,s5"};
#ifdef CSW_FIGURES_MODULE_FILE
  ::setenv("CSW_FIGURES_MODULE", CSW_FIGURES_MODULE_FILE, 1);
  s.figures = (fx.dir / "figures").string();
#endif
  const json sr = KeysScore(s, progress);
  ASSERT_EQ(sr["takes"].size(), 2u);
  EXPECT_EQ(sr["takes"][0]["scores_written"], "keys");
  // The simulated phones give the labelled keys their A1 (speech anchors).
  EXPECT_EQ(sr["takes"][0]["speech_anchors"], true);
  EXPECT_EQ(sr["takes"][1]["speech_anchors"], true);
  const Corpus c = Corpus::Open(fx.corpus);
  int64_t expected = 0;
  for (const char* name : {"s4", "s5"}) {
    const Take take = c.LoadTake(name);
    std::map<std::string, const LabelTier*> tiers;
    for (const auto& tier : take.tiers) tiers[tier.name] = &tier;
    // The simulator's tiers are kept, ours added.
    for (const char* n : {"words", "phones", "keys", "placement_targets", "keys_decoded", "keys_decoded_targets",
                          "shape_extents", "placement_extents", "keys_aligned", "placement_aligned"})
      EXPECT_EQ(tiers.count(n), 1u) << name << " " << n;
    expected += static_cast<int64_t>(tiers["keys"]->labels.size());
    EXPECT_EQ(tiers["keys_aligned"]->labels.size(), tiers["keys"]->labels.size());
    // One placement target per placement change: at most one per key, and at
    // most as many as the placement_targets tier's marks.
    EXPECT_GT(tiers["placement_aligned"]->labels.size(), 0u);
    EXPECT_LE(tiers["placement_aligned"]->labels.size(), tiers["placement_targets"]->labels.size());
    EXPECT_GT(tiers["keys_decoded"]->labels.size(), 0u);
  }
  // The decoding options used, the defaults here.
  EXPECT_EQ(sr["decoding"]["min_key_ms"], 80.0);
  EXPECT_EQ(sr["decoding"]["aligned_floor"], 3e-3);
  EXPECT_EQ(sr["decoding"]["anchor_nearest"], true);
  EXPECT_EQ(sr["decoding"]["fit_sd_factor"], 4.0);
  EXPECT_EQ(sr["decoding"]["keep_in_class"], true);
  EXPECT_EQ(sr["shape"]["count"].get<int64_t>(), expected);
  EXPECT_EQ(sr["sequence"]["free"]["keys_expected"].get<int64_t>(), expected);
  EXPECT_EQ(sr["sequence"]["aligned"]["keys_expected"].get<int64_t>(), expected);
  // Accuracy = trace / total of the confusion matrix.
  int64_t trace = 0, total = 0;
  const json& conf = sr["shape"]["confusion"];
  for (size_t i = 0; i < conf.size(); ++i)
    for (size_t j = 0; j < conf[i].size(); ++j) {
      total += conf[i][j].get<int64_t>();
      if (i == j) trace += conf[i][j].get<int64_t>();
    }
  EXPECT_EQ(total, expected);
  EXPECT_DOUBLE_EQ(sr["shape"]["accuracy"].get<double>(), static_cast<double>(trace) / total);
  // The rest keys (00, first and last of each take) are always recognised.
  EXPECT_GE(conf[0][0].get<int64_t>(), 4);
  // Four training sentences, no occlusions: most labelled frames are right.
  EXPECT_GE(sr["shape"]["accuracy"].get<double>(), 0.6);
  EXPECT_GE(sr["placement"]["accuracy"].get<double>(), 0.6);
  {
    // --aligned-floor 1e-6 --no-anchor-nearest --fit-sd-factor 0 --dry-run: reported, the same
    // keys aligned, and the frames' accuracies (not decoding) unchanged.
    KeysScoreOptions o = s;
    o.figures.clear();
    o.dry_run = true;
    o.decode.aligned_floor = 1e-6;
    o.anchor_nearest = false;
    o.fit_sd_factor = 0;
    o.keep_in_class = false;
    const json r2 = KeysScore(o, progress);
    EXPECT_EQ(r2["decoding"]["aligned_floor"], 1e-6);
    EXPECT_EQ(r2["decoding"]["anchor_nearest"], false);
    EXPECT_EQ(r2["decoding"]["fit_sd_factor"], 0.0);
    EXPECT_EQ(r2["decoding"]["keep_in_class"], false);
    EXPECT_EQ(r2["sequence"]["aligned"]["keys_expected"], sr["sequence"]["aligned"]["keys_expected"]);
    EXPECT_EQ(r2["shape"]["accuracy"], sr["shape"]["accuracy"]);
  }

  // The posteriors stored in the corpus are those of the model on the take's
  // features, bit for bit (score set "keys", row-major frames × classes).
  const keys::KeyModel model = *LoadModelFile(fx.keys).keys;
  for (const char* name : {"s4", "s5"}) {
    const Take take = c.LoadTake(name);
    const MarkerBinding b = BindMarkerSet(ParseMarkerSet(c.TakeMarkerSet(name), name), take.marker_names, false, name);
    const keys::KeyPosteriors want =
        keys::ScoreFrames(model, keys::ComputeHandFeatures(take.markers, b, model.layout, model.head_reference));
    const std::optional<TakeScores> got = c.LoadScores(name, "keys");
    ASSERT_TRUE(got.has_value()) << name;
    EXPECT_EQ(got->rate_hz, take.rate_hz);
    EXPECT_EQ(got->start_s, 0.0);
    EXPECT_EQ(got->source, fx.keys);
    ASSERT_EQ(got->matrices.size(), 2u);
    for (const ScoreMatrix& m : got->matrices) {  // name order: placement, shape
      const Eigen::MatrixXd& p = m.name == "shape" ? want.shape : want.placement;
      ASSERT_EQ(m.rows, take.frames()) << name << " " << m.name;
      ASSERT_EQ(m.cols, m.name == "shape" ? 9 : 6) << m.name;
      ASSERT_EQ(m.column_names.back(), m.name == "shape" ? "8" : "5");
      int64_t differ = 0;
      for (int64_t t = 0; t < m.rows; ++t)
        for (int64_t k = 0; k < m.cols; ++k)
          if (m.values[static_cast<size_t>(t * m.cols + k)] != p(t, k)) ++differ;
      EXPECT_EQ(differ, 0) << name << " " << m.name;
    }
  }
#ifdef CSW_FIGURES_MODULE_FILE
  // The two confusion matrices, as PNG files of a real size (a labelled 9 × 9
  // grid with counts: tens of kB; an empty canvas compresses to a few kB).
  ASSERT_EQ(sr["figures"].size(), 2u);
  for (const char* f : {"shape_confusion.png", "placement_confusion.png"}) {
    const std::filesystem::path png = fx.dir / "figures" / f;
    ASSERT_TRUE(std::filesystem::exists(png)) << png;
    std::ifstream in(png, std::ios::binary);
    unsigned char h[24] = {};
    in.read(reinterpret_cast<char*>(h), 24);
    EXPECT_EQ(std::string(reinterpret_cast<char*>(h) + 1, 3), "PNG") << f;
    const int width = (h[16] << 24) | (h[17] << 16) | (h[18] << 8) | h[19];
    const int height = (h[20] << 24) | (h[21] << 16) | (h[22] << 8) | h[23];
    EXPECT_GE(width, 300) << f;
    EXPECT_GE(height, 300) << f;
    EXPECT_GT(std::filesystem::file_size(png), 8000u) << f;
  }
  EXPECT_NE(KeysScoreText(sr).find("figure: "), std::string::npos);
  ::unsetenv("CSW_FIGURES_MODULE");
#endif
}

TEST(KeysJob, BadLabelCodesAndMissingKeyModelGiveClearErrors) {
  Fixture fx;
  Progress progress;
  {
    Take t = Corpus::Open(fx.corpus).LoadTake("s0");
    for (auto& tier : t.tiers)
      if (tier.name == "keys") tier.labels[1].text = "9x";
    CorpusTransaction tx(fx.corpus);
    tx.WriteTiers("s0", t.tiers);
    tx.Commit();
  }
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s0"};
  t.output = fx.keys;
  try {
    KeysTrain(t, progress);
    FAIL() << "bad code accepted";
  } catch (const InvalidInput& e) {
    // One error naming the corpus, the take, the tier, the label and the code (core/labels.h).
    EXPECT_NE(std::string(e.what()).find(fx.corpus + ": take 's0': tier 'keys': label 2 at "), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("bad key code '9x'"), std::string::npos) << e.what();
  }
  // A model file without /keys.
  SaveModelFile(fx.keys, ModelFile{});
  KeysScoreOptions s;
  s.corpus = fx.corpus;
  s.keys = fx.keys;
  try {
    KeysScore(s, progress);
    FAIL() << "scored without a key model";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("no key model"), std::string::npos) << e.what();
  }
}

TEST(KeysJob, ExplicitLayoutSectionNamesTheMarkers) {
  Fixture fx;
  Progress progress;
  // The layout derived from the roles, written as a hand_layout section without
  // "head" (the marker set's head cluster is the default).
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s0"};
  t.output = fx.keys;
  KeysTrain(t, progress);
  const keys::HandLayout derived = LoadModelFile(fx.keys).keys->layout;
  json section = keys::HandLayoutToJson(derived);
  section.erase("head");
  section["thumb_palm"] = derived.palm[0];  // a different palm point than the derived one
  const std::string layout_path = (fx.dir / "layout.json").string();
  std::ofstream(layout_path) << json{{"hand_layout", section}}.dump();
  t.layout = layout_path;
  const std::string other = (fx.dir / "keys2.h5").string();
  t.output = other;
  KeysTrain(t, progress);
  const keys::HandLayout explicit_layout = LoadModelFile(other).keys->layout;
  EXPECT_EQ(explicit_layout.proximal, derived.proximal);
  EXPECT_EQ(explicit_layout.distal, derived.distal);
  EXPECT_EQ(explicit_layout.head, derived.head);
  EXPECT_EQ(explicit_layout.thumb_palm, derived.palm[0]);
  // A misspelt key is an error naming the file.
  std::ofstream(layout_path) << R"({"hand_layout": {"fingerz": {}}})";
  try {
    KeysTrain(t, progress);
    FAIL() << "bad layout accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("layout.json: hand_layout: unknown key \"fingerz\""), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace csw::jobs

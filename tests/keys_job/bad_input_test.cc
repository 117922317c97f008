// Damaged input files of the key and phasing jobs give one clear error naming
// the file and where in it: the --truth files of csw phasing, the --layout
// file of csw keys train, and a label tier with a bad code met by csw keys
// score. (Damaged key-model HDF5 files: tests/io/models and tests/keys.)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "tests/keys_job/cuer_corpus.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/phasing_job.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;

// The message of the exception of type E that f throws ("" when none or another).
template <typename E>
std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

// Two sentences; a key model trained on the first.
struct Fixture : testing::CuerCorpus {
  Progress progress;
  Fixture() : CuerCorpus(2) {
    KeysTrainOptions t;
    t.corpus = corpus;
    t.takes = {"s0"};
    t.output = keys;
    KeysTrain(t, progress);
  }
};

TEST(BadInput, DamagedTruthFilesNameTheFileAndThePlace) {
  Fixture fx;
  PhasingOptions o;
  o.corpus = fx.corpus;
  o.keys = fx.keys;
  o.takes = {"s1"};
  o.truth = fx.truth;
  const std::string file = (fs::path(fx.truth) / "s1.truth.json").string();
  // Cut short: not JSON, at line 2.
  std::ofstream(file) << "{\"take\": \"s1\",\n \"keys\": [{\"code\": \"00\"";
  std::string m = ErrorOf<ParseError>([&] { Phasing(o, fx.progress); });
  EXPECT_NE(m.find(file + ": not JSON"), std::string::npos) << m;
  EXPECT_NE(m.find("line 2"), std::string::npos) << m;
  // JSON without the keys array.
  std::ofstream(file) << "{\"take\": \"s1\"}";
  m = ErrorOf<ParseError>([&] { Phasing(o, fx.progress); });
  EXPECT_NE(m.find(file + ": no \"keys\" array"), std::string::npos) << m;
  // The true truth with one key's time replaced by text: the key is named.
  nlohmann::json truth = nlohmann::json::parse(TruthToJson(fx.sims[1]));
  ASSERT_GT(truth["keys"].size(), 3u);
  truth["keys"][2]["shape_target_s"] = "soon";
  std::ofstream(file) << truth.dump();
  m = ErrorOf<ParseError>([&] { Phasing(o, fx.progress); });
  EXPECT_NE(m.find(file + ": key 2: "), std::string::npos) << m;
}

TEST(BadInput, DamagedLayoutFileNamesTheFileAndThePlace) {
  Fixture fx;
  KeysTrainOptions t;
  t.corpus = fx.corpus;
  t.takes = {"s0"};
  t.output = (fx.dir / "k2.h5").string();
  t.layout = (fx.dir / "layout.json").string();
  // Not JSON: the line of the error.
  std::ofstream(t.layout) << "{\n  \"hand_layout\": {\n    \"palm\": [\"P1\", \"P2\",\n";
  std::string m = ErrorOf<ParseError>([&] { KeysTrain(t, fx.progress); });
  EXPECT_NE(m.find(t.layout + ": line 4: invalid JSON"), std::string::npos) << m;
  // A number too large for a double (found by fuzz/hand_layout_fuzz.cc):
  // the same one error, with the line.
  std::ofstream(t.layout) << "{\"hand_layout\": {\n  \"palm\": [1e999]}}";
  m = ErrorOf<ParseError>([&] { KeysTrain(t, fx.progress); });
  EXPECT_NE(m.find(t.layout + ": line 2: invalid JSON: number overflow"), std::string::npos) << m;
  // JSON without the section.
  std::ofstream(t.layout) << "{\"layout\": {}}";
  m = ErrorOf<UsageError>([&] { KeysTrain(t, fx.progress); });
  EXPECT_NE(m.find(t.layout + ": no \"hand_layout\" section"), std::string::npos) << m;
  // A value of the wrong type: the file, the section and the key.
  std::ofstream(t.layout) << R"({"hand_layout": {"palm": "P1"}})";
  m = ErrorOf<InvalidInput>([&] { KeysTrain(t, fx.progress); });
  EXPECT_NE(m.find(t.layout + ": hand_layout: "), std::string::npos) << m;
  EXPECT_NE(m.find("palm"), std::string::npos) << m;
  EXPECT_FALSE(fs::exists(t.output));  // nothing written
}

TEST(BadInput, BadKeyCodeInTheLabelTierStopsScoringWithOneError) {
  Fixture fx;
  {
    Take t = Corpus::Open(fx.corpus).LoadTake("s1");
    for (auto& tier : t.tiers)
      if (tier.name == "placement_targets") tier.labels[3].text = "72";  // placement 7 does not exist
    CorpusTransaction tx(fx.corpus);
    tx.WriteTiers("s1", t.tiers);
    tx.Commit();
  }
  const std::vector<std::string> tiers_before = Corpus::Open(fx.corpus).Summary("s1").tier_names;
  KeysScoreOptions s;
  s.corpus = fx.corpus;
  s.keys = fx.keys;
  const std::string m = ErrorOf<InvalidInput>([&] { KeysScore(s, fx.progress); });
  EXPECT_NE(m.find(fx.corpus + ": take 's1': tier 'placement_targets': label 4 at "), std::string::npos) << m;
  EXPECT_NE(m.find("bad key code '72'"), std::string::npos) << m;
  // Nothing written: neither tiers nor scores.
  const Corpus c = Corpus::Open(fx.corpus);
  EXPECT_EQ(c.Summary("s1").tier_names, tiers_before);
  EXPECT_TRUE(c.ScoreNames("s0").empty());
}

}  // namespace
}  // namespace csw::jobs

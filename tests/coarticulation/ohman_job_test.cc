// csw coartic fit (workbench/jobs/ohman_job.h): option checks, the text report of a
// hand-written result, the fit file's parsing (round trip and errors), and
// the job end to end on virtual-cuer VCV takes in a test corpus with a face
// model fitted by csw fit.
#include "workbench/jobs/ohman_job.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/build_paths.h"
#include "core/error.h"
#include "core/file_util.h"
#include "core/markerset.h"
#include "io/corpus/corpus.h"
#include "tests/coarticulation/vcv_takes.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

TEST(OhmanJobOptions, CheckGivesTheReason) {
  OhmanJobOptions o;
  EXPECT_EQ(o.Check(), "no corpus given");
  o.corpus = "c.h5";
  EXPECT_EQ(o.Check(), "no model file given (--models)");
  o.models = "m.h5";
  EXPECT_EQ(o.Check(), "");
  o.phones = "";
  EXPECT_EQ(o.Check(), "--phones must name a tier");
  o.phones = "phones";
  o.fit.vowels = {"a", ""};
  EXPECT_EQ(o.Check(), "a vowel context cannot be a pause label");
  o.fit.vowels = {"a", "i"};
  o.fit.min_w = 1.5;
  EXPECT_EQ(o.Check(), "min_w must be in (0, 1)");
  o.fit.min_w = 0.1;
  o.fit.min_vowel_spread = -1;
  EXPECT_EQ(o.Check(), "min_vowel_spread must be in [0, 1)");
  o.fit.min_vowel_spread = 0.05;
  o.inversion.max_iterations = 0;
  EXPECT_EQ(o.Check(), "--max-iterations must be >= 1");
  Progress p;
  o.inversion.max_iterations = 30;
  o.corpus = "";
  EXPECT_THROW(Ohman(o, p), UsageError);
}

// A result with one parameter, one consonant in two contexts; NaN (null)
// where c is not identifiable.
json SmallResult() {
  json fit = {{"format", "csw-ohman"},
              {"version", 1},
              {"parameters", {"jaw"}},
              {"vowels",
               {{{"vowel", "a"}, {"source", "isolated"}, {"occurrences", 2}, {"target", {1.5}}},
                {{"vowel", "i"}, {"source", "vcv"}, {"occurrences", 4}, {"target", {-0.25}}}}},
              {"rest", {0.0}},
              {"range", {3.0}},
              {"consonants",
               {{{"consonant", "p"},
                 {"contexts", {"a", "i"}},
                 {"tokens", 2},
                 {"w", {0.05}},
                 {"intercept", {0.01}},
                 {"c", {nullptr}},
                 {"residual", {0.0}},
                 {"identifiable", {false}},
                 {"effect", {{"a", {-0.065}}, {"i", {0.0225}}}},
                 {"measured_effect", {{"a", {-0.065}}, {"i", {0.0225}}}},
                 {"realisation", {{"a", {1.435}}, {"i", {-0.2275}}}},
                 {"k_style",
                  {{"left_inset_s", 0.01},
                   {"left_ramp_s", 0.07},
                   {"right_inset_s", 0.012},
                   {"right_ramp_s", 0.065},
                   {"rms", 0.05},
                   {"samples", 20}}},
                 {"mean_k", {{"times_s", {-0.01, 0.0}}, {"k", {0.9, 1.0}}}}}}},
              {"tokens", json::array()},
              {"warnings", {"vowel 'i' never occurs alone"}}};
  return {{"corpus", "c.h5"},
          {"models", "m.h5"},
          {"takes",
           {{{"take", "vcv"},
             {"frames", 100},
             {"solved_frames", 98},
             {"tokens", 2},
             {"generation", {{"correlation", {0.9876}}, {"rms", {0.1}}, {"unknown_phones", {"j"}}}}}}},
          {"skipped", {{{"take", "other"}, {"reason", "no interval tier 'phones' (tiers: none)"}}}},
          {"fit", fit},
          {"summary", {{"tokens", 2}, {"consonants", 1}, {"parameters", 1}, {"identifiable", 0}}},
          {"figures", {"f/ohman_k_p.png"}},
          {"output", "o.json"}};
}

TEST(OhmanText, RendersTheReport) {
  EXPECT_EQ(OhmanText(SmallResult()),
            "Öhman coarticulation model: 2 VCV tokens, 1 consonants, 1 parameters (face model m.h5)\n"
            "  take vcv: 2 tokens, 98/100 frames solved; generated vs inverted r: 0.988 (left out: j)\n"
            "  skipped other: no interval tier 'phones' (tiers: none)\n"
            "Vowel references:\n"
            "  a (isolated, 2): 1.500\n"
            "  i (vcv, 4): -0.250\n"
            "[p] 2 tokens; k: plateau from start + 10 ms to end - 12 ms, ramps 70 / 65 ms, rms 0.050\n"
            "  parameter        w        c   residual  effect per context\n"
            "  jaw             0.050        -    0.000   a -0.065  i 0.022\n"
            "warning: vowel 'i' never occurs alone\n"
            "figure: f/ohman_k_p.png\n"
            "fit written to o.json\n");
}

TEST(OhmanFitJson, RoundTripAndErrors) {
  const json j = SmallResult()["fit"];
  std::vector<std::string> names;
  const coarticulation::OhmanFit fit = OhmanFitFromJson(j, "o.json", &names);
  EXPECT_EQ(names, std::vector<std::string>{"jaw"});
  ASSERT_EQ(fit.consonants.size(), 1u);
  EXPECT_TRUE(std::isnan(fit.consonants[0].c[0]));
  EXPECT_DOUBLE_EQ(fit.consonants[0].w[0], 0.05);
  EXPECT_DOUBLE_EQ(fit.vowel_targets(1, 0), -0.25);
  EXPECT_EQ(OhmanFitToJson(fit, names, {}), j);  // written back identically
  // Generation from the file: at the centre of a lone [apa]'s consonant the
  // carrier is v_a = 1.5 and k = 1, so p = v + (a − w v) = 1.5 + 0.01 − 0.075.
  const std::vector<Label> phones = {{0.0, 0.3, ""}, {0.3, 0.4, "a"}, {0.4, 0.5, "p"}, {0.5, 0.6, "a"}, {0.6, 0.9, ""}};
  const Eigen::MatrixXd p = coarticulation::GenerateOhman(fit, phones, {0.45});
  EXPECT_NEAR(p(0, 0), 1.5 + 0.01 - 0.05 * 1.5, 1e-12);

  auto error_of = [](json bad) {
    try {
      OhmanFitFromJson(bad, "o.json");
    } catch (const ParseError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  json bad = j;
  bad.erase("format");
  EXPECT_EQ(error_of(bad), "o.json: Öhman fit: missing 'format'");
  bad = j;
  bad["version"] = 2;
  EXPECT_EQ(error_of(bad), "o.json: Öhman fit: version 2 is not supported (1 is)");
  bad = j;
  bad["consonants"][0]["w"] = {0.1, 0.2};
  EXPECT_EQ(error_of(bad), "o.json: Öhman fit: 'consonants[0].w' must be an array of 1 numbers");
  bad = j;
  bad["consonants"][0]["effect"].erase("i");
  EXPECT_EQ(error_of(bad), "o.json: Öhman fit: missing 'consonants[0].effect.i'");
  bad = j;
  bad["consonants"][0]["k_style"]["left_ramp_s"] = -1;
  EXPECT_EQ(error_of(bad), "o.json: Öhman fit: 'consonants[0].k_style.' ramps must be >= 0");
}

TEST(OhmanJob, FitsVirtualCuerTakesAndWritesTheFitFile) {
  testing::TempDir dir;
  const std::vector<std::string> consonants = {"p", "s", "ʃ"};
  const std::vector<SimulationResult> sims = testing::SimulateVcvTakes(3, consonants);
  SimulateOptions so;
  so.kind = CorpusKind::kVisemes;
  const VirtualCuer cuer(so);
  const std::string set_json = MarkerSetToJson(cuer.MakeMarkerSet(CorpusKind::kVisemes));
  const std::string set_file = (dir / "markerset.json").string();
  std::ofstream(set_file) << set_json;
  const std::string corpus = (dir / "c.h5").string();
  {
    CorpusTransaction tx(corpus);
    for (const SimulationResult& r : sims) {
      Take t = r.take;
      t.markerset_json = set_json;
      tx.WriteTake(t);
    }
    Take no_phones = sims[1].take;
    no_phones.name = "no_phones";
    no_phones.tiers.clear();
    no_phones.markerset_json = set_json;
    tx.WriteTake(no_phones);
    tx.Commit();
  }
  Progress progress;
  FitOptions fo;
  fo.corpus = corpus;
  fo.kind = "face";
  fo.markerset = set_file;
  fo.output = (dir / "models.h5").string();
  Fit(fo, progress);

  OhmanJobOptions o;
  o.corpus = corpus;
  o.models = fo.output;
  o.output = (dir / "ohman.json").string();
#ifdef CSW_FIGURES_MODULE_FILE
  ::setenv("CSW_FIGURES_MODULE", CSW_FIGURES_MODULE_FILE, 1);
  o.figures = (dir / "figures").string();
#endif
  const json r = Ohman(o, progress);
  // 3 consonants × 3 contexts; the take without phones is skipped.
  EXPECT_EQ(r["summary"]["tokens"], 9);
  EXPECT_EQ(r["summary"]["consonants"], 3);
  ASSERT_EQ(r["skipped"].size(), 1u);
  EXPECT_EQ(r["skipped"][0]["take"], "no_phones");
  std::map<std::string, int> tokens;
  for (const json& t : r["takes"]) tokens[t["take"].get<std::string>()] = t["tokens"].get<int>();
  EXPECT_EQ(tokens, (std::map<std::string, int>{{"vowels", 0}, {"vcv_a", 3}, {"vcv_i", 3}, {"vcv_u", 3}}));
  const json& fit = r["fit"];
  std::vector<std::string> got;
  for (const json& c : fit["consonants"]) got.push_back(c["consonant"]);
  EXPECT_EQ(got, consonants);
  for (const json& v : fit["vowels"]) {
    EXPECT_EQ(v["source"], "isolated");
    EXPECT_EQ(v["occurrences"], 1);
  }
  // Measured effect = mean realisation − vowel reference, per context.
  for (const json& c : fit["consonants"])
    for (const json& v : c["contexts"]) {
      const std::string vowel = v;
      const json& target = fit["vowels"][vowel == "a" ? 0 : vowel == "i" ? 1 : 2]["target"];
      for (size_t x = 0; x < 6; ++x) {
        EXPECT_NEAR(c["measured_effect"][vowel][x].get<double>(),
                    c["realisation"][vowel][x].get<double>() - target[x].get<double>(), 1e-9);
      }
    }
  // Every token's pooled k: one value per frame between its vowel centres;
  // over the tokens, the median k is about 1 at the consonant centre and
  // about 0 at the vowel centres (the simulator's consonant window is a
  // plateau over the consonant with 70 ms ramps starting 60 ms before it:
  // ≤ 0.02 at a vowel centre 50-70 ms away).
  ASSERT_EQ(fit["tokens"].size(), 9u);
  std::vector<double> at_centre, at_vowels;
  for (const json& t : fit["tokens"]) {
    ASSERT_EQ(t["k"].size(), t["k_times_s"].size());
    const double rate = 120.0;  // the simulator's default capture rate
    const double span = t["v2_centre_s"].get<double>() - t["v1_centre_s"].get<double>();
    EXPECT_NEAR(static_cast<double>(t["k"].size()), span * rate, 1.5);
    const double centre = 0.5 * (t["c_start_s"].get<double>() + t["c_end_s"].get<double>());
    size_t nearest = 0;
    for (size_t i = 0; i < t["k"].size(); ++i)
      if (std::abs(t["k_times_s"][i].get<double>() - centre) < std::abs(t["k_times_s"][nearest].get<double>() - centre))
        nearest = i;
    at_centre.push_back(t["k"][nearest].get<double>());
    at_vowels.push_back(t["k"].front().get<double>());
    at_vowels.push_back(t["k"].back().get<double>());
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  EXPECT_NEAR(median(at_centre), 1.0, 0.15);
  EXPECT_NEAR(median(at_vowels), 0.0, 0.15);
  // Trajectories regenerated from the fit follow the inverted ones: the first
  // parameter (most of the variance) correlates >= 0.95 in every VCV take.
  for (const json& t : r["takes"]) {
    ASSERT_TRUE(t.contains("generation")) << t;
    EXPECT_TRUE(t["generation"]["unknown_phones"].empty()) << t;
    if (t["take"] != "vowels") {
      EXPECT_GE(t["generation"]["correlation"][0].get<double>(), 0.95) << t;
    }
  }
  // The file holds the result's fit, and reads back.
  EXPECT_EQ(json::parse(ReadTextFile(o.output)), fit);
  EXPECT_EQ(OhmanFitFromJson(fit, o.output).consonants.size(), 3u);
  const std::string text = OhmanText(r);
  EXPECT_NE(text.find("Öhman coarticulation model: 9 VCV tokens, 3 consonants, 6 parameters"), std::string::npos)
      << text;
  EXPECT_NE(text.find("[ʃ] 3 tokens"), std::string::npos) << text;
#ifdef CSW_FIGURES_MODULE_FILE
  ASSERT_EQ(r["figures"].size(), 3u + 3u);  // k(t) per consonant, trajectories per VCV take
  for (const json& f : r["figures"]) {
    std::ifstream in(f.get<std::string>(), std::ios::binary);
    char h[4] = {};
    in.read(h, 4);
    EXPECT_EQ(std::string(h + 1, 3), "PNG") << f;
    EXPECT_GT(std::filesystem::file_size(f.get<std::string>()), 10000u) << f;  // curves, not an empty canvas
  }
#endif
  // Only takes without the phone tier: a clear error.
  o.takes = {"no_phones"};
  o.figures.clear();
  try {
    Ohman(o, progress);
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("no selected take has the phone tier 'phones'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace csw::jobs

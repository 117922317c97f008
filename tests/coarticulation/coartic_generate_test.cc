// csw coartic generate (workbench/jobs/coartic_generate_job.h): the phone
// string's parsing, option checks, and trajectories from a hand-written fit
// file against hand-derived values, as CSV, text and JSON.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/error.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/coartic_generate_job.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

// One parameter "jaw"; vowel a at 1.5, i at −0.25, u at 0 (rest 0); consonant
// p with w = 0.05 and a = w c = 0.01 (c = 0.2), k style: full between the
// consonant's edges, 40 ms ramps outside them.
json Fit() {
  return json::parse(R"({"format": "csw-ohman", "version": 1, "parameters": ["jaw"],
    "vowels": [{"vowel": "a", "source": "isolated", "occurrences": 1, "target": [1.5]},
               {"vowel": "i", "source": "isolated", "occurrences": 1, "target": [-0.25]},
               {"vowel": "u", "source": "isolated", "occurrences": 1, "target": [0.0]}],
    "rest": [0.0], "range": [2.0],
    "consonants": [{"consonant": "p", "contexts": ["a"], "tokens": 1, "w": [0.05], "intercept": [0.01],
      "c": [0.2], "residual": [0.0], "effect": {"a": [-0.065]}, "measured_effect": {"a": [-0.065]},
      "realisation": {"a": [1.435]},
      "k_style": {"left_inset_s": 0.0, "left_ramp_s": 0.04, "right_inset_s": 0.0, "right_ramp_s": 0.04,
                  "rms": 0.0, "samples": 10},
      "mean_k": {"times_s": [], "k": []}}],
    "tokens": [], "warnings": []})");
}

TEST(CoarticGenerate, ParsesPhoneStrings) {
  CoarticGenerateOptions o;
  const std::vector<Label> l = ParsePhoneString("_:300 a p:80 a #", {"a", "i", "u"}, o);
  ASSERT_EQ(l.size(), 5u);
  EXPECT_EQ(l[0].text, "");  // a pause
  EXPECT_NEAR(l[0].end_s, 0.3, 1e-12);
  EXPECT_EQ(l[1].text, "a");
  EXPECT_NEAR(l[1].end_s - l[1].start_s, 0.150, 1e-12);  // the vowel default
  EXPECT_NEAR(l[2].end_s - l[2].start_s, 0.080, 1e-12);
  EXPECT_NEAR(l[4].end_s - l[4].start_s, 0.200, 1e-12);  // the pause default
  EXPECT_NEAR(l[4].end_s, 0.3 + 0.15 + 0.08 + 0.15 + 0.2, 1e-12);
  EXPECT_THROW(ParsePhoneString("a:abc", {"a"}, o), InvalidInput);
  EXPECT_THROW(ParsePhoneString("a:-5", {"a"}, o), InvalidInput);
  EXPECT_THROW(ParsePhoneString("   ", {"a"}, o), InvalidInput);
  CoarticGenerateOptions c;
  EXPECT_NE(c.Check().find("fit file"), std::string::npos);
  c.fit = "f.json";
  EXPECT_NE(c.Check().find("either"), std::string::npos);
  c.phones = "a";
  EXPECT_EQ(c.Check(), "");
  c.textgrid = "x.TextGrid";
  EXPECT_NE(c.Check().find("either"), std::string::npos);
  c.textgrid.clear();
  c.rate_hz = 0;
  EXPECT_NE(c.Check().find("--rate"), std::string::npos);
}

TEST(CoarticGenerate, TrajectoriesFromAFitFile) {
  testing::TempDir dir;
  const std::string fit = (dir / "fit.json").string();
  std::ofstream(fit) << Fit().dump(1);
  CoarticGenerateOptions o;
  o.fit = fit;
  o.phones = "_:300 a:100 p:100 a:100 _:300";
  o.rate_hz = 100;
  o.output = (dir / "p.csv").string();
  Progress progress;
  const json r = CoarticGenerate(o, progress);
  EXPECT_EQ(r["samples"], 91);  // 0 .. 0.9 s
  EXPECT_EQ(r["parameters"], json::array({"jaw"}));
  ASSERT_EQ(r["phones"].size(), 5u);
  // Read the CSV back: at 0.45 s, the centre of [p] in a lone [apa], the
  // carrier is v_a = 1.5 and k = 1, so jaw = v + (a − w v) = 1.5 + 0.01 − 0.075.
  std::ifstream in(o.output);
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header, "time_s,jaw");
  std::vector<std::pair<double, double>> rows;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    double t = 0, v = 0;
    char comma = 0;
    ls >> t >> comma >> v;
    rows.emplace_back(t, v);
  }
  ASSERT_EQ(rows.size(), 91u);
  EXPECT_NEAR(rows[45].first, 0.45, 1e-9);
  EXPECT_NEAR(rows[45].second, 1.5 + 0.01 - 0.05 * 1.5, 1e-7);
  // In the middle of the opening pause the carrier is at rest and p is absent.
  EXPECT_NEAR(rows[5].second, 0.0, 1e-7);
  const std::string text = CoarticGenerateText(r);
  EXPECT_NE(text.find("phones: _ a p a _"), std::string::npos) << text;
  EXPECT_NE(text.find("trajectories: " + o.output), std::string::npos) << text;
  // A phone the fit does not know: named, unless skipped.
  o.phones = "a t a";
  try {
    CoarticGenerate(o, progress);
    FAIL() << "an unknown phone was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("'t'"), std::string::npos) << e.what();
  }
  o.skip_unknown = true;
  EXPECT_EQ(CoarticGenerate(o, progress)["phones"].size(), 3u);
}

}  // namespace
}  // namespace csw::jobs

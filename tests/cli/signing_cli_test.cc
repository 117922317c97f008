// The sign-language commands end to end through the csw binary: simulate
// signs, segment, transitions --json (the duration models the done-when of
// issue 14 asks the CLI to report), sign-sequence, export as BVH and import
// back.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "tests/cli/cli_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::Csw;
using testing::Q;
using testing::RunResult;

json Json(const std::string& args, const fs::path& dir) {
  const RunResult r = Csw(args + " --json", dir);
  EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
  return r.code == 0 ? json::parse(r.out) : json();
}

TEST(SigningCli, SimulateSegmentTransitionsSequenceAndBvhRoundTrip) {
  testing::TempDir dir;
  const std::string count = "16";  // also under the sanitizers: 6 takes leave the plane too loosely fitted
  ASSERT_EQ(
      Csw("-q simulate signs --count " + count + " --seed 9 --hand-offset 0 -o " + Q(dir / "sim"), dir.path()).code, 0);
  const std::string corpus = Q(dir / "sim" / "signs.h5");
  // Durations follow the seed's SURFACE plane in G and E over every joint at
  // the nominal boundaries: the CLI's JSON reports it as the best model, with
  // the plane's coefficients within 5 %.
  const json t = Json("-q transitions " + corpus + " --tiers signs --joints all -o " + Q(dir / "d.json"), dir.path());
  ASSERT_TRUE(t.is_object());
  EXPECT_GE(t["transitions"].get<int>(), 35);
  EXPECT_EQ(t["best"], "surface");
  const double seed_theta[3] = {0.148777, 0.663958, 0.275229};
  for (const json& m : t["models"]) {
    if (m["model"] != "surface") continue;
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(m["fit"]["theta"][static_cast<size_t>(i)].get<double>(), seed_theta[i], 0.05 * seed_theta[i]);
    }
  }
  EXPECT_TRUE(fs::exists(dir / "d.json"));
  // csw segment moves the jittered manual tags; its tiers feed transitions.
  const json s = Json("-q segment " + corpus + " --tier manual", dir.path());
  ASSERT_TRUE(s.is_object());
  const json per_hand = Json("-q transitions " + corpus + " --tiers manual_right,manual_left", dir.path());
  EXPECT_GT(per_hand["transitions"].get<int>(), 0);
  // A new utterance with the fitted durations, as BVH; imported back.
  const json q = Json("-q sign-sequence " + corpus + " --glosses HELLO,OPEN --durations " + Q(dir / "d.json") + " -o " +
                          Q(dir / "seq" / "hello_open.bvh"),
                      dir.path());
  ASSERT_TRUE(q.is_object());
  EXPECT_EQ(q["signs"].size(), 2u);
  const RunResult imp =
      Csw("-q import " + Q(dir / "seq" / "hello_open.bvh") + " --units mm -o " + Q(dir / "seq.h5"), dir.path());
  ASSERT_EQ(imp.code, 0) << imp.err;
  const json info = Json("info " + Q(dir / "seq.h5"), dir.path());
  ASSERT_TRUE(info.is_object());
  EXPECT_EQ(info.dump().find("hello_open") != std::string::npos, true) << info.dump();
  // An unknown gloss is a data error (exit 2) naming it.
  const RunResult bad = Csw("sign-sequence " + corpus + " --glosses BANANA -o " + Q(dir / "x.bvh"), dir.path());
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("BANANA"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace csw

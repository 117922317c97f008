// End-to-end tests of `csw fit` and `csw invert` (issue 4): the acceptance run
// on a virtual-cuer corpus (simulated truth), the real Facial-Sing capture of
// c3d.org (hidden samples), gap filling as a new take, and clear errors.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "core/sha256.h"
#include "io/corpus/corpus.h"
#include "tests/cli/cli_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::Csw;
using testing::Q;
using testing::RunResult;

json RunJson(const std::string& args, const fs::path& dir) {
  const RunResult r = Csw(args + " --json", dir);
  EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
  if (r.code != 0) return json();
  return json::parse(r.out);
}

double Mean(const json& stats) { return stats.at("mean_mm").get<double>(); }

// The virtual cuer with simulated truth: 18 sentences, the first third (6)
// for training, the rest held out. Targets of issue 4: visible face ≤ 1 mm,
// hand ≤ 2 mm, held-out ≤ 25 % above training, poses within 0.5° / 0.5 mm,
// occluded markers ≤ 3 mm. The hand model keeps 20 angle components: the
// simulated hand varies its 22 joints independently from key to key (3° sd),
// more freedom than the seed's 12 components capture. Occluded hand markers
// (mostly folded fingers behind the palm) are filled by the hand model's
// Gaussian gap filler, trained by EM on incomplete frames (docs/models.md).
TEST(CliModels, VirtualCuerAcceptance) {
  testing::TempDir dir;
  const fs::path sim = dir / "sim";
  ASSERT_EQ(Csw("simulate sentences --count 18 --clean --seed 7 -o " + Q(sim), dir.path()).code, 0);
  std::string files;
  for (int i = 1; i <= 18; ++i) {
    const std::string base = (sim / ((i < 10 ? "sentence_00" : "sentence_0") + std::to_string(i))).string();
    files += " '" + base + ".c3d' '" + base + ".wav' '" + base + ".TextGrid'";
  }
  const fs::path corpus = dir / "corpus.h5", models = dir / "models.h5";
  ASSERT_EQ(Csw("import" + files + " --markerset " + Q(sim / "markerset.json") + " -o " + Q(corpus), dir.path()).code,
            0);
  // Throat weights are fitted, not read from the simulator's marker set.
  {
    std::ifstream in(sim / "markerset.json");
    json set = json::parse(in);
    json names = json::array();
    for (const auto& t : set["throat"]) names.push_back(t["marker"]);
    set["throat"] = names;
    std::ofstream(dir / "set.json") << set.dump(2);
  }
  std::ofstream(dir / "config.json") << R"({"format": "csw-model-config", "version": 1, "markerset": "set.json",
                                          "hand": {"angle_components": 20}})";
  const std::string train =
      " --train sentence_001,sentence_002,sentence_003,sentence_004,sentence_005,sentence_006"
      " --config " +
      Q(dir / "config.json") + " -o " + Q(models);
  const json rigid = RunJson("fit rigid " + Q(corpus) + train, dir.path());
  ASSERT_EQ(rigid["rigid"].size(), 2u);
  const json face = RunJson("fit face " + Q(corpus) + train, dir.path());
  ASSERT_TRUE(face.contains("face"));
  EXPECT_EQ(face["face"]["parameters"].size(), 6u);  // the simulator's face has 6 articulatory parameters
  // Fitted throat weights near the simulator's (0.22 … 0.85).
  std::ifstream in(sim / "markerset.json");
  const json truth_set = json::parse(in);
  double weight_error = 0;
  for (size_t i = 0; i < truth_set["throat"].size(); ++i) {
    weight_error = std::max(weight_error, std::abs(face["face"]["throat"][i]["head_weight"].get<double>() -
                                                   truth_set["throat"][i]["head_weight"].get<double>()));
  }
  EXPECT_LT(weight_error, 0.1);
  const json hand = RunJson("fit hand " + Q(corpus) + train, dir.path());
  ASSERT_TRUE(hand.contains("hand"));
  // The gap filler also learns from the frames where some hand marker is
  // hidden: more of them than the shape model's complete frames.
  ASSERT_TRUE(hand["hand"].contains("gaussian_fill"));
  EXPECT_GT(hand["hand"]["gaussian_fill"]["frames"].get<int64_t>(), 2 * hand["hand"]["training_frames"].get<int64_t>());

  const json inv = RunJson("invert " + Q(corpus) + " --models " + Q(models) + " --truth " + Q(sim), dir.path());
  ASSERT_TRUE(inv.contains("face") && inv.contains("hand"));
  for (const char* kind : {"face", "hand"}) {
    SCOPED_TRACE(kind);
    const json& m = inv[kind];
    const double target = m["target_mm"].get<double>();
    EXPECT_EQ(m["takes"].size(), 18u);
    const double train_err = Mean(m["training"]["visible"]), held_err = Mean(m["held_out"]["visible"]);
    EXPECT_LE(train_err, target);
    EXPECT_LE(held_err, target);
    EXPECT_LE(held_err, 1.25 * train_err);
    EXPECT_GT(m["overall"]["occluded"]["count"].get<int64_t>(), 0);
    EXPECT_LE(Mean(m["overall"]["occluded"]), 3.0);
    // The gap-edge correction costs the face, already at the noise floor, at
    // most a few hundredths of a mm; the hand's Gaussian fill is left as is.
    EXPECT_LE(Mean(m["overall"]["occluded"]), Mean(m["overall"]["occluded_model"]) + 0.02);
    std::printf("%s: training %.3f mm, held-out %.3f mm, occluded %.3f mm (model alone %.3f), pose %.3f deg %.3f mm\n",
                kind, train_err, held_err, Mean(m["overall"]["occluded"]), Mean(m["overall"]["occluded_model"]),
                m["overall"]["pose"]["rotation_deg"]["mean_deg"].get<double>(),
                Mean(m["overall"]["pose"]["translation_mm"]));
    EXPECT_LE(m["overall"]["pose"]["rotation_deg"]["mean_deg"].get<double>(), 0.5);
    EXPECT_LE(Mean(m["overall"]["pose"]["translation_mm"]), 0.5);
    for (const auto& t : m["takes"]) EXPECT_EQ(t["solved_frames"], t["frames"]) << t["take"];
    // The per-marker breakdown pools the same samples: shape markers' counts
    // add up to the totals, and their count-weighted means to the overall mean.
    int64_t visible_count = 0, occluded_count = 0;
    double occluded_sum = 0;
    for (const auto& e : m["markers"]) {
      if (e["role"] != "shape") continue;
      visible_count += e["visible"]["count"].get<int64_t>();
      const int64_t n = e["occluded"]["count"].get<int64_t>();
      occluded_count += n;
      if (n > 0) occluded_sum += static_cast<double>(n) * Mean(e["occluded"]);
    }
    EXPECT_EQ(visible_count, m["overall"]["visible"]["count"].get<int64_t>());
    EXPECT_EQ(occluded_count, m["overall"]["occluded"]["count"].get<int64_t>());
    EXPECT_NEAR(occluded_sum / static_cast<double>(occluded_count), Mean(m["overall"]["occluded"]), 1e-6);
  }

  // Ctrl-C during a filling inversion: exit 130, the corpus byte-identical.
  const std::string before = Sha256OfFile(corpus.string());
  const fs::path err = dir / "cancel.err";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 2);
    execl(CSW_BINARY, CSW_BINARY, "invert", corpus.c_str(), "--models", models.c_str(), "--fill", "--threads", "1",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  bool inverting = false;
  for (int i = 0; i < 4000 && !inverting; ++i) {
    std::ifstream in(err);
    std::stringstream text;
    text << in.rdbuf();
    inverting = text.str().find("inverting: 10%") != std::string::npos;
    if (!inverting) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(inverting) << "the inversion never reported progress";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_EQ(Sha256OfFile(corpus.string()), before);
}

// Real data the project did not make: remove head motion, fit ≤ 10 face
// parameters on the first half, reconstruct 10 % hidden samples of the second
// half within 2 mm, and fill the real gaps into a new take.
TEST(CliModels, FacialSingHiddenSamplesAndRealGaps) {
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_29/Facial-Sing.c3d");
  testing::TempDir dir;
  const fs::path c3d = testing::SharedData("c3d/c3d.org/sample_29/Facial-Sing.c3d");
  const fs::path set = testing::SourceDir() / "datasets/markersets/c3d-org-facial-sing.json";
  const fs::path corpus = dir / "fs.h5", models = dir / "face.h5";
  ASSERT_EQ(Csw("import " + Q(c3d) + " --markerset " + Q(set) + " -o " + Q(corpus), dir.path()).code, 0);
  std::ofstream(dir / "config.json") << R"({"format": "csw-model-config", "version": 1, "face": {"components": 8}})";
  const json fit = RunJson("fit face " + Q(corpus) + " --train 'Facial-Sing@:50%' --markerset " + Q(set) +
                               " --config " + Q(dir / "config.json") + " -o " + Q(models),
                           dir.path());
  ASSERT_TRUE(fit.contains("face"));
  EXPECT_LE(fit["face"]["parameters"].size(), 10u);
  EXPECT_GT(fit["face"]["selected_frames"].get<int64_t>(), 100);

  const json inv =
      RunJson("invert " + Q(corpus) + " --models " + Q(models) + " --takes 'Facial-Sing@50%:' --hide 0.1", dir.path());
  ASSERT_TRUE(inv.contains("face"));
  const json& take = inv["face"]["takes"][0];
  EXPECT_EQ(take["role"], "held_out");
  EXPECT_EQ(take["frames"].get<int64_t>(), 1500);
  const int64_t hidden = take["hidden"]["count"].get<int64_t>();
  const int64_t visible = take["visible"]["count"].get<int64_t>();
  EXPECT_NEAR(static_cast<double>(hidden) / static_cast<double>(hidden + visible), 0.1, 0.002);
  EXPECT_LE(Mean(take["hidden"]), 2.0);

  // Fill the whole take: a new take "Facial-Sing.filled"; the original is untouched.
  const Take before = Corpus::Open(corpus.string()).LoadTake("Facial-Sing");
  const json fill = RunJson("invert " + Q(corpus) + " --models " + Q(models) + " --fill", dir.path());
  ASSERT_EQ(fill["filled"].size(), 1u);
  EXPECT_EQ(fill["filled"][0]["filled_take"], "Facial-Sing.filled");
  const Corpus c = Corpus::Open(corpus.string());
  const Take original = c.LoadTake("Facial-Sing");
  const Take filled = c.LoadTake("Facial-Sing.filled");
  EXPECT_EQ(original.markers.data().size(), before.markers.data().size());
  EXPECT_TRUE(std::equal(original.markers.data().begin(), original.markers.data().end(), before.markers.data().begin(),
                         [](float a, float b) { return (std::isnan(a) && std::isnan(b)) || a == b; }));
  // The real gaps of ../shared/data/README.md: filled in every frame where the head was seen.
  int64_t filled_samples = 0;
  for (const char* name : {"section3-1", "section4-1", "section4-2", "section5-1", "section6-1", "section13-2"}) {
    const int64_t m = original.MarkerIndex(name);
    ASSERT_GE(m, 0) << name;
    int64_t gaps = 0, still_missing = 0;
    for (int64_t f = 0; f < original.frames(); ++f) {
      if (original.markers.Visible(f, m)) {
        // Visible samples are copied unchanged.
        EXPECT_EQ(original.markers.at(f, m)[0], filled.markers.at(f, m)[0]);
        continue;
      }
      ++gaps;
      if (!filled.markers.Visible(f, m)) ++still_missing;
    }
    EXPECT_GT(gaps, 0) << name;
    EXPECT_EQ(still_missing, 0) << name;
    filled_samples += gaps;
  }
  EXPECT_GE(fill["filled"][0]["samples_filled"].get<int64_t>(), filled_samples);
  // A second fill makes another version and keeps the first.
  const json again =
      RunJson("invert " + Q(corpus) + " --models " + Q(models) + " --takes Facial-Sing --fill", dir.path());
  EXPECT_EQ(again["filled"][0]["filled_take"], "Facial-Sing.filled-2");
  EXPECT_TRUE(Corpus::Open(corpus.string()).HasTake("Facial-Sing.filled"));
}

TEST(CliModels, ClearErrors) {
  testing::TempDir dir;
  const fs::path sim = dir / "sim";
  ASSERT_EQ(Csw("simulate shapes -o " + Q(sim), dir.path()).code, 0);
  const fs::path corpus = dir / "c.h5";
  ASSERT_EQ(Csw("import " + Q(sim / "shapes_01.c3d") + " -o " + Q(corpus), dir.path()).code, 0);
  // No marker set: usage-level data error naming what to give.
  RunResult r = Csw("fit face " + Q(corpus) + " -o " + Q(dir / "m.h5"), dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--markerset"), std::string::npos) << r.err;
  // Unknown kind: usage error.
  EXPECT_EQ(Csw("fit tongue " + Q(corpus) + " -o " + Q(dir / "m.h5"), dir.path()).code, 1);
  // A bad take range names itself.
  r = Csw("fit face " + Q(corpus) + " --train 'shapes_01@9:3' --markerset " + Q(sim / "markerset.json") + " -o " +
              Q(dir / "m.h5"),
          dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("shapes_01@9:3"), std::string::npos) << r.err;
  // A marker set naming markers the take lacks: the take and the markers are named.
  std::ofstream(dir / "bad.json") << R"({"format": "csw-markerset", "version": 1, "name": "x",
    "head_cluster": ["NOPE1", "NOPE2", "NOPE3"], "face": ["ULM"]})";
  r = Csw("fit face " + Q(corpus) + " --markerset " + Q(dir / "bad.json") + " -o " + Q(dir / "m.h5"), dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("NOPE1, NOPE2, NOPE3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("shapes"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "m.h5"));
  // A corpus given as the model file: one line naming it.
  r = Csw("invert " + Q(corpus) + " --models " + Q(corpus), dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(corpus.string()), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // A config with an unknown key names the file and the key.
  std::ofstream(dir / "cfg.json") << R"({"face": {"componets": 3}})";
  r = Csw("fit face " + Q(corpus) + " --markerset " + Q(sim / "markerset.json") + " --config " + Q(dir / "cfg.json") +
              " -o " + Q(dir / "m.h5"),
          dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("cfg.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("componets"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace csw

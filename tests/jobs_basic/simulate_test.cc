// Simulate's output: the take names it returns and what lands in the output
// folder (written into a hidden partial folder, then moved into place).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "synth/phasing.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/jobs.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;

std::set<std::string> Names(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.insert(e.path().filename().string());
  return out;
}

TEST(SimulateJob, ShapesIntoANewFolderGiveTheKnownFiles) {
  testing::TempDir dir;
  SimulateJobOptions o;
  o.corpus = "shapes";
  o.output = (dir / "new" / "shapes").string();  // parent folders are created
  Progress progress;
  const std::vector<std::string> takes = Simulate(o, progress);
  EXPECT_EQ(takes, std::vector<std::string>{"shapes_01"});
  EXPECT_EQ(Names(dir / "new" / "shapes"),
            (std::set<std::string>{"markerset.json", "shapes_01.c3d", "shapes_01.TextGrid", "shapes_01.truth.json"}));
  EXPECT_EQ(Names(dir / "new"), std::set<std::string>{"shapes"});  // no partial folder left
}

TEST(SimulateJob, IntoAnExistingFolderKeepsItsOtherFiles) {
  testing::TempDir dir;
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "notes.txt") << "mine";
  std::ofstream(dir / "out" / "shapes_01.c3d") << "old";  // replaced by the new take
  SimulateJobOptions o;
  o.corpus = "shapes";
  o.output = (dir / "out").string() + "/";  // a trailing slash names the same folder
  Progress progress;
  Simulate(o, progress);
  EXPECT_EQ(Names(dir / "out"), (std::set<std::string>{"markerset.json", "notes.txt", "shapes_01.c3d",
                                                       "shapes_01.TextGrid", "shapes_01.truth.json"}));
  std::ifstream notes(dir / "out" / "notes.txt");
  std::string text;
  notes >> text;
  EXPECT_EQ(text, "mine");
  EXPECT_GT(fs::file_size(dir / "out" / "shapes_01.c3d"), 1000u);
  EXPECT_EQ(Names(dir.path()), std::set<std::string>{"out"});
}

TEST(SimulateJob, CancelledRunChangesNothing) {
  testing::TempDir dir;
  SimulateJobOptions o;
  o.corpus = "shapes";
  o.output = (dir / "out").string();
  Progress progress;
  progress.Cancel();
  EXPECT_THROW(Simulate(o, progress), Cancelled);
  EXPECT_TRUE(Names(dir.path()).empty());
}

nlohmann::json ReadJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// A bad phasing file is refused before anything is written, with one error
// that names it.
TEST(SimulateJob, BadPhasingFileGivesOneErrorNamingIt) {
  testing::TempDir dir;
  const fs::path bad = dir / "timing.json";
  SimulateJobOptions o;
  o.corpus = "sentences";
  o.texts = {"bonjour"};
  o.output = (dir / "out").string();
  o.phasing_file = bad.string();
  Progress progress;
  for (const std::string& text :
       {std::string("{\"placement_cv\": {"), std::string(R"({"placement_cv": {"start_mean_ms": "early"}})"),
        std::string(R"({"shape_cv": {"start_mean_ms": -100, "start_sd_ms": -5, "target_mean_ms": 0,
                        "target_sd_ms": 10}})")}) {
    std::ofstream(bad) << text;
    try {
      Simulate(o, progress);
      ADD_FAILURE() << "accepted " << text;
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
    }
    EXPECT_EQ(Names(dir.path()), std::set<std::string>{"timing.json"});
  }
}

// Every mean shifted by +70 ms: with the same seed each key's true start and
// target times move by 70 ms relative to its A1 (the draws are the same, the
// peak-speed lengthening depends on durations and distances). Two espeak-ng
// runs in one process may place the phones up to a few samples apart, so A1 and
// the times relative to it are compared within 1 ms.
TEST(SimulateJob, ShiftedPhasingFileMovesTheTruthTimes) {
  testing::TempDir dir;
  PhasingModel shifted;
  const double shift_s = 0.070;
  for (MovementTiming* m : {&shifted.placement_cv, &shifted.shape_cv, &shifted.placement_v, &shifted.shape_v,
                            &shifted.placement_c, &shifted.shape_c, &shifted.rest}) {
    m->start_mean_s += shift_s;
    m->target_mean_s += shift_s;
  }
  SavePhasingModel(shifted, (dir / "shifted.json").string());
  SimulateJobOptions o;
  o.corpus = "sentences";
  o.texts = {"Le petit chat boit du lait."};
  o.occlusions = false;
  o.dropouts_per_s = 0;
  Progress progress;
  o.output = (dir / "default").string();
  Simulate(o, progress);
  o.output = (dir / "shifted").string();
  o.phasing_file = (dir / "shifted.json").string();
  const std::vector<std::string> takes = Simulate(o, progress);
  ASSERT_EQ(takes.size(), 1u);
  const nlohmann::json a = ReadJson(dir / "default" / (takes[0] + ".truth.json"));
  const nlohmann::json b = ReadJson(dir / "shifted" / (takes[0] + ".truth.json"));
  EXPECT_DOUBLE_EQ(b["phasing"]["placement_cv"]["start_mean_ms"].get<double>(), -239.0 + 70.0);
  EXPECT_DOUBLE_EQ(a["phasing"]["placement_cv"]["start_mean_ms"].get<double>(), -239.0);
  ASSERT_EQ(a["keys"].size(), b["keys"].size());
  ASSERT_GE(a["keys"].size(), 6u);
  for (size_t k = 0; k < a["keys"].size(); ++k) {
    const nlohmann::json &ka = a["keys"][k], &kb = b["keys"][k];
    EXPECT_EQ(ka["code"], kb["code"]);
    const double a1a = ka["a1_s"].get<double>(), a1b = kb["a1_s"].get<double>();
    EXPECT_NEAR(a1b, a1a, 1e-3);
    for (const char* t : {"placement_start_s", "placement_target_s", "shape_start_s", "shape_target_s"})
      EXPECT_NEAR((kb[t].get<double>() - a1b) - (ka[t].get<double>() - a1a), shift_s, 1e-3) << "key " << k << " " << t;
    if (ka["type"] == "cv") {  // the vowel phone follows the consonant phone
      EXPECT_EQ(ka["vowel_phone"].get<int>(), ka["consonant_phone"].get<int>() + 1);
    }
  }
}

}  // namespace
}  // namespace csw::jobs

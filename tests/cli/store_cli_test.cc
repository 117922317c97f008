// The corpus store seen from the command line: the marker set remembered with
// each take (so fit needs no --markerset), csw pack and csw upgrade, and the
// error for a corpus whose folder of take files is missing.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

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

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Simulates the shapes take once per test and imports it (with or without a
// marker set) into dir/c.h5.
void SimulateAndImport(const testing::TempDir& dir, bool with_markerset) {
  ASSERT_EQ(Csw("-q simulate shapes -o " + Q(dir / "s"), dir.path()).code, 0);
  const std::string set = with_markerset ? " --markerset " + Q(dir / "s" / "markerset.json") : "";
  RunResult r = Csw("-q import " + Q(dir / "s" / "shapes_01.c3d") + set + " -o " + Q(dir / "c.h5"), dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
}

TEST(CliStore, CorpusRemembersTheMarkerSetSoFitNeedsNone) {
  testing::TempDir dir;
  SimulateAndImport(dir, true);
  RunResult info = Csw("info --json " + Q(dir / "c.h5"), dir.path());
  ASSERT_EQ(info.code, 0) << info.err;
  const json j = json::parse(info.out);
  EXPECT_EQ(j["format_version"].get<int>(), 2);
  EXPECT_TRUE(j["takes"][0]["markerset"].get<bool>()) << info.out;

  RunResult fit = Csw("-q fit rigid " + Q(dir / "c.h5") + " -o " + Q(dir / "m.h5"), dir.path());
  ASSERT_EQ(fit.code, 0) << fit.err;
  // The model's clusters have the sizes of the marker set given at import.
  const json set = json::parse(Slurp(dir / "s" / "markerset.json"));
  RunResult inspect = Csw("inspect --json " + Q(dir / "m.h5"), dir.path());
  ASSERT_EQ(inspect.code, 0) << inspect.err;
  const json m = json::parse(inspect.out);
  EXPECT_EQ(m["models"]["head_motion"]["markers"].get<size_t>(), set["head_cluster"].size());
  EXPECT_EQ(m["models"]["forearm_motion"]["markers"].get<size_t>(), set["forearm_cluster"].size());
}

TEST(CliStore, FitWithoutAnyMarkerSetIsAUsageErrorNamingTheTake) {
  testing::TempDir dir;
  SimulateAndImport(dir, false);
  RunResult fit = Csw("-q fit rigid " + Q(dir / "c.h5") + " -o " + Q(dir / "m.h5"), dir.path());
  EXPECT_EQ(fit.code, 1) << fit.err;
  EXPECT_NE(fit.err.find("take 'shapes_01'"), std::string::npos) << fit.err;
  EXPECT_NE(fit.err.find("--markerset"), std::string::npos) << fit.err;
  EXPECT_FALSE(fs::exists(dir / "m.h5"));
}

TEST(CliStore, PackGivesOneFileWithIdenticalTakesAndUpgradeSplitsIt) {
  testing::TempDir dir;
  SimulateAndImport(dir, true);
  ASSERT_TRUE(fs::is_directory(dir / "c.h5.d"));
  RunResult pack = Csw("pack " + Q(dir / "c.h5") + " -o " + Q(dir / "one.h5"), dir.path());
  ASSERT_EQ(pack.code, 0) << pack.err;
  EXPECT_NE(pack.out.find("packed 1 take(s)"), std::string::npos) << pack.out;
  EXPECT_FALSE(fs::exists(dir / "one.h5.d"));

  // The packed file moved elsewhere, alone, still reads: same CSV export.
  fs::create_directories(dir / "elsewhere");
  fs::rename(dir / "one.h5", dir / "elsewhere" / "one.h5");
  ASSERT_EQ(Csw("export " + Q(dir / "c.h5") + " --take shapes_01 --format csv -o " + Q(dir / "a.csv"), dir.path()).code,
            0);
  ASSERT_EQ(Csw("export " + Q(dir / "elsewhere" / "one.h5") + " --take shapes_01 --format csv -o " + Q(dir / "b.csv"),
                dir.path())
                .code,
            0);
  const std::string a = Slurp(dir / "a.csv");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, Slurp(dir / "b.csv"));
  EXPECT_EQ(Corpus::Open((dir / "elsewhere" / "one.h5").string()).TakeMarkerSet("shapes_01"),
            Corpus::Open((dir / "c.h5").string()).TakeMarkerSet("shapes_01"));

  // Packing over an existing file is refused and leaves it alone.
  const std::string before = Slurp(dir / "a.csv");
  RunResult again = Csw("pack " + Q(dir / "c.h5") + " -o " + Q(dir / "a.csv"), dir.path());
  EXPECT_EQ(again.code, 1) << again.err;
  EXPECT_EQ(Slurp(dir / "a.csv"), before);

  // Upgrade splits the packed file into index + folder, once.
  RunResult up = Csw("upgrade --json " + Q(dir / "elsewhere" / "one.h5"), dir.path());
  ASSERT_EQ(up.code, 0) << up.err;
  EXPECT_TRUE(json::parse(up.out)["upgraded"].get<bool>()) << up.out;
  EXPECT_TRUE(fs::is_directory(dir / "elsewhere" / "one.h5.d"));
  ASSERT_EQ(Csw("export " + Q(dir / "elsewhere" / "one.h5") + " --take shapes_01 --format csv -o " + Q(dir / "c.csv"),
                dir.path())
                .code,
            0);
  EXPECT_EQ(a, Slurp(dir / "c.csv"));
  RunResult twice = Csw("upgrade " + Q(dir / "elsewhere" / "one.h5"), dir.path());
  ASSERT_EQ(twice.code, 0) << twice.err;
  EXPECT_NE(twice.out.find("nothing to do"), std::string::npos) << twice.out;
}

TEST(CliStore, MissingTakeFolderGivesOneClearError) {
  testing::TempDir dir;
  SimulateAndImport(dir, true);
  fs::rename(dir / "c.h5.d", dir / "moved.d");
  RunResult info = Csw("info " + Q(dir / "c.h5"), dir.path());
  EXPECT_EQ(info.code, 2) << info.err;
  EXPECT_NE(info.err.find("c.h5"), std::string::npos) << info.err;
  EXPECT_NE(info.err.find("shapes_01"), std::string::npos) << info.err;
  EXPECT_NE(info.err.find("missing"), std::string::npos) << info.err;
}

}  // namespace
}  // namespace csw

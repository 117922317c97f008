// End-to-end tests of the `csw` command line: exit codes, inspect against the
// reference values of ../shared/data/c3d/REFERENCE.tsv, import/info/export round
// trips, atomic imports and a real kill in the middle of an import.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "core/sha256.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/formats/textgrid.h"
#include "io/formats/trc.h"
#include "io/formats/wav.h"
#include "tests/cli/cli_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using testing::Csw;
using testing::Q;
using testing::RunResult;

Take SmallTake(const std::string& name, int64_t frames, int64_t markers) {
  Take t;
  t.name = name;
  t.rate_hz = 120.0;
  for (int64_t m = 0; m < markers; ++m) t.marker_names.push_back("M" + std::to_string(m));
  t.markers.Resize(frames, markers);
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < markers; ++m) {
      float* p = t.markers.at(f, m);
      p[0] = static_cast<float>(100.0 * std::sin(0.01 * f + m));
      p[1] = static_cast<float>(m * 10.0 + 0.5 * f);
      p[2] = static_cast<float>(1000.0 + m);
    }
  }
  if (frames > 5 && markers > 1) t.markers.SetMissing(3, 1);
  return t;
}

TEST(Cli, ExitCodesAndOneLineErrors) {
  testing::TempDir dir;
  EXPECT_EQ(Csw("", dir.path()).code, 1);
  EXPECT_EQ(Csw("--help", dir.path()).code, 0);
  EXPECT_EQ(Csw("frobnicate", dir.path()).code, 1);
  RunResult missing = Csw("inspect " + Q(dir / "nope.c3d"), dir.path());
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("nope.c3d: no such file"), std::string::npos) << missing.err;
  // A garbage C3D: one line naming the file and an offset.
  std::ofstream(dir / "junk.c3d") << std::string(700, 'x');
  RunResult junk = Csw("inspect " + Q(dir / "junk.c3d"), dir.path());
  EXPECT_EQ(junk.code, 2);
  EXPECT_NE(junk.err.find("junk.c3d: offset "), std::string::npos) << junk.err;
  EXPECT_EQ(std::count(junk.err.begin(), junk.err.end(), '\n'), 1) << junk.err;
  EXPECT_EQ(Csw("export " + Q(dir / "x.h5") + " --take a --format xyz -o " + Q(dir / "o"), dir.path()).code, 1);
}

struct RefRow {
  std::string file, status;
  int64_t points = 0, first_frame = 0, frames = 0, analog_channels = 0, subframes = 0, valid = 0;
  double rate = 0, sum = 0;
};

std::vector<RefRow> ReadReference() {
  std::vector<RefRow> rows;
  fs::path tsv = testing::SharedData("c3d/REFERENCE.tsv");
  if (tsv.empty()) return rows;
  std::ifstream in(tsv);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    RefRow r;
    std::getline(ss, r.file, '\t');
    std::getline(ss, r.status, '\t');
    if (r.status == "ok") {
      ss >> r.points >> r.first_frame >> r.frames >> r.rate >> r.analog_channels >> r.subframes >> r.valid >> r.sum;
    }
    rows.push_back(r);
  }
  return rows;
}

TEST(Cli, InspectMatchesReferenceForEveryOkFile) {
  CSW_REQUIRE_SHARED_DATA("c3d/REFERENCE.tsv");
  testing::TempDir dir;
  int checked = 0;
  for (const RefRow& r : ReadReference()) {
    if (r.status != "ok") continue;
    SCOPED_TRACE(r.file);
    RunResult res = Csw("inspect --json " + Q(testing::SharedData("c3d/" + r.file)), dir.path());
    ASSERT_EQ(res.code, 0) << res.err;
    json j = json::parse(res.out);
    // Four files where the reference reader ignores the header's layout; csw reads
    // the layout that fills the file (io/c3d/README.md, tests io.C3dPeerDivergence.*).
    static const std::set<std::string> kDivergent = {"c3d.org/sample_11/evart.c3d",
                                                     "c3d.org/sample_20/phasespace_sample.c3d",
                                                     "c3d.org/sample_28/type1.C3D", "ezc3d/Kistler.c3d"};
    if (kDivergent.count(r.file)) {
      EXPECT_GT(j["frames"].get<int64_t>(), 0);
      continue;
    }
    EXPECT_EQ(j["points"].get<int64_t>(), r.points);
    EXPECT_EQ(j["first_frame"].get<int64_t>(), r.first_frame);
    EXPECT_EQ(j["frames"].get<int64_t>(), r.frames);
    EXPECT_NEAR(j["point_rate_hz"].get<double>(), r.rate, 1e-3 * std::max(1.0, r.rate));
    EXPECT_EQ(j["analog_channels"].get<int64_t>(), r.analog_channels);
    EXPECT_EQ(j["valid_point_samples"].get<int64_t>(), r.valid);
    EXPECT_NEAR(j["sum_xyz_valid"].get<double>(), r.sum, 1e-6 * std::max(1.0, std::abs(r.sum)));
    ++checked;
  }
  EXPECT_GE(checked, 60);
}

TEST(Cli, MipsFilesGiveTheValuesOfTheirIntelTwins) {
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_01/Eb015si.c3d");
  testing::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> twins = {{"sample_01/Eb015si.c3d", "sample_01/Eb015pi.c3d"},
                                                                  {"sample_01/Eb015sr.c3d", "sample_01/Eb015pr.c3d"},
                                                                  {"sample_02/sgi_int.c3d", "sample_02/pc_int.c3d"},
                                                                  {"sample_02/sgi_real.c3d", "sample_02/pc_real.c3d"}};
  for (const auto& [mips, intel] : twins) {
    SCOPED_TRACE(mips);
    RunResult a = Csw("inspect --json " + Q(testing::SharedData("c3d/c3d.org/" + mips)), dir.path());
    RunResult b = Csw("inspect --json " + Q(testing::SharedData("c3d/c3d.org/" + intel)), dir.path());
    ASSERT_EQ(a.code, 0) << a.err;
    ASSERT_EQ(b.code, 0) << b.err;
    json ja = json::parse(a.out), jb = json::parse(b.out);
    EXPECT_EQ(ja["processor"], "mips");
    EXPECT_EQ(jb["processor"], "intel");
    for (const char* k : {"points", "frames", "first_frame", "valid_point_samples", "analog_channels", "labels"})
      EXPECT_EQ(ja[k], jb[k]) << k;
    EXPECT_EQ(ja["sum_xyz_valid"].get<double>(), jb["sum_xyz_valid"].get<double>());
  }
}

TEST(Cli, PeerErrorFilesGiveDataWithWarningsOrOneClearError) {
  CSW_REQUIRE_SHARED_DATA("c3d/REFERENCE.tsv");
  testing::TempDir dir;
  int checked = 0;
  for (const RefRow& r : ReadReference()) {
    if (r.status == "ok") continue;
    SCOPED_TRACE(r.file);
    RunResult res = Csw("inspect --json " + Q(testing::SharedData("c3d/" + r.file)), dir.path());
    ASSERT_TRUE(res.code == 0 || res.code == 2) << "exit " << res.code << ": " << res.err;
    if (res.code == 2) {
      EXPECT_NE(res.err.find(fs::path(r.file).filename().string() + ": offset "), std::string::npos) << res.err;
      EXPECT_EQ(std::count(res.err.begin(), res.err.end(), '\n'), 1) << res.err;
    } else {
      json j = json::parse(res.out);
      EXPECT_GT(j["frames"].get<int64_t>(), 0);
      // MIPS files and Facial-Sing (no ANALOG group) are valid files the peer reader rejects.
      bool valid_file = j["processor"] == "mips" || r.file.find("Facial-Sing") != std::string::npos;
      if (!valid_file) {
        EXPECT_FALSE(j["warnings"].empty()) << "a peer-error file read silently";
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(Cli, ImportInfoExportRoundTrip) {
  testing::TempDir dir;
  Take take = SmallTake("take01", 240, 5);
  take.events.push_back({"RIC", "Right", 0.5, ""});
  WriteC3d((dir / "take01.c3d").string(), take);
  LabelTier phones{"phones", LabelTier::Kind::kInterval, 0.0, 2.0, {{0.0, 0.7, "b"}, {0.7, 2.0, "ɔ̃"}}};
  WriteTextGrid((dir / "take01.TextGrid").string(), {phones}, 0.0, 2.0);
  Audio audio;
  audio.rate_hz = 16000;
  audio.samples.resize(32000);
  for (size_t i = 0; i < audio.samples.size(); ++i) audio.samples[i] = 0.5f * std::sin(0.05f * static_cast<float>(i));
  WriteWav((dir / "take01.wav").string(), audio);
  WriteC3d((dir / "take02.c3d").string(), SmallTake("take02", 60, 3));

  fs::path corpus = dir / "corpus.h5";
  RunResult imp = Csw("import " + Q(dir / "take01.c3d") + " " + Q(dir / "take01.TextGrid") + " " +
                          Q(dir / "take01.wav") + " " + Q(dir / "take02.c3d") + " -o " + Q(corpus),
                      dir.path());
  ASSERT_EQ(imp.code, 0) << imp.err;
  RunResult info = Csw("info --json " + Q(corpus), dir.path());
  ASSERT_EQ(info.code, 0) << info.err;
  json j = json::parse(info.out);
  ASSERT_EQ(j["take_count"].get<int>(), 2);
  json t1 = j["takes"][0];
  EXPECT_EQ(t1["name"], "take01");
  EXPECT_EQ(t1["frames"].get<int64_t>(), 240);
  EXPECT_EQ(t1["markers"].get<int64_t>(), 5);
  EXPECT_EQ(t1["gaps"].get<int64_t>(), 1);
  EXPECT_EQ(t1["tiers"], json::array({"phones"}));
  EXPECT_TRUE(t1["audio"].get<bool>());
  EXPECT_FALSE(j["takes"][1]["audio"].get<bool>());

  for (const char* fmt : {"c3d", "trc"}) {
    fs::path out = dir / (std::string("back.") + fmt);
    RunResult ex = Csw("export " + Q(corpus) + " --take take01 --format " + fmt + " -o " + Q(out), dir.path());
    ASSERT_EQ(ex.code, 0) << ex.err;
    // Both files hold the take's float samples exactly (C3D as float32, TRC with
    // the shortest decimal that reads back to the same float): tolerance 0.
    const bool c3d = std::string(fmt) == "c3d";
    Take back = c3d ? ReadC3d(out.string()) : ReadTrc(out.string());
    SCOPED_TRACE(fmt);
    ASSERT_EQ(back.frames(), take.frames());
    ASSERT_EQ(back.marker_names, take.marker_names);
    EXPECT_EQ(back.rate_hz, take.rate_hz);
    ASSERT_EQ(back.markers.data().size(), take.markers.data().size());
    for (size_t i = 0; i < take.markers.data().size(); ++i) {
      float a = take.markers.data()[i], b = back.markers.data()[i];
      if (std::isnan(a)) {
        EXPECT_TRUE(std::isnan(b)) << i;
      } else {
        ASSERT_EQ(a, b) << i;
      }
    }
    if (c3d) {
      ASSERT_EQ(back.events.size(), 1u);
      EXPECT_NEAR(back.events[0].time_s, 0.5, 1e-6);
    }
  }
  fs::path csv = dir / "back.csv";
  ASSERT_EQ(Csw("export " + Q(corpus) + " --take take02 --format csv -o " + Q(csv), dir.path()).code, 0);
  std::ifstream in(csv);
  std::string header, first;
  std::getline(in, header);
  std::getline(in, first);
  EXPECT_EQ(header.rfind("frame,time_s,M0_x,M0_y,M0_z", 0), 0u) << header;
  EXPECT_EQ(first.rfind("1,0.000000,", 0), 0u) << first;
  // Only the two exported files plus inputs: no temporary left behind.
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".csw-export"), std::string::npos) << e.path();
}

TEST(Cli, FailedImportLeavesTheCorpusUnchanged) {
  testing::TempDir dir;
  WriteC3d((dir / "a.c3d").string(), SmallTake("a", 50, 3));
  fs::path corpus = dir / "corpus.h5";
  ASSERT_EQ(Csw("import " + Q(dir / "a.c3d") + " -o " + Q(corpus), dir.path()).code, 0);
  std::string before = Sha256OfFile(corpus.string());
  WriteC3d((dir / "b.c3d").string(), SmallTake("b", 50, 3));
  std::ofstream(dir / "c.c3d") << std::string(2000, '\x01');  // damaged
  RunResult r = Csw("import " + Q(dir / "b.c3d") + " " + Q(dir / "c.c3d") + " -o " + Q(corpus), dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("c.c3d"), std::string::npos) << r.err;
  EXPECT_EQ(Sha256OfFile(corpus.string()), before);
  // A take that exists already: refused with a hint, corpus unchanged; --replace works.
  RunResult again = Csw("import " + Q(dir / "a.c3d") + " -o " + Q(corpus), dir.path());
  EXPECT_EQ(again.code, 2);
  EXPECT_NE(again.err.find("--replace"), std::string::npos) << again.err;
  EXPECT_EQ(Sha256OfFile(corpus.string()), before);
  EXPECT_EQ(Csw("import --replace " + Q(dir / "a.c3d") + " -o " + Q(corpus), dir.path()).code, 0);
  EXPECT_EQ(Corpus::Open(corpus.string()).Takes().size(), 1u);
}

TEST(Cli, MarkerSetMismatchNamesTheMissingMarkers) {
  testing::TempDir dir;
  WriteC3d((dir / "a.c3d").string(), SmallTake("a", 20, 4));
  std::ofstream(dir / "set.json") << R"({"name": "s", "head_cluster": ["M0", "M1", "M2"], "face": ["LipU"]})";
  fs::path corpus = dir / "corpus.h5";
  RunResult r =
      Csw("import " + Q(dir / "a.c3d") + " -o " + Q(corpus) + " --markerset " + Q(dir / "set.json"), dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("LipU"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(corpus));
  std::ofstream(dir / "ok.json") << R"({"name": "s", "head_cluster": ["M0", "M1", "m2"]})";
  EXPECT_EQ(
      Csw("import " + Q(dir / "a.c3d") + " -o " + Q(corpus) + " --markerset " + Q(dir / "ok.json"), dir.path()).code,
      0);
}

// A real SIGKILL in the middle of `csw import`: the previous corpus stays intact.
TEST(Cli, KilledImportLeavesThePreviousCorpusIntact) {
  testing::TempDir dir;
  WriteC3d((dir / "small.c3d").string(), SmallTake("small", 30, 3));
  fs::path corpus = dir / "corpus.h5";
  ASSERT_EQ(Csw("import " + Q(dir / "small.c3d") + " -o " + Q(corpus), dir.path()).code, 0);
  std::string before = Sha256OfFile(corpus.string());
  WriteC3d((dir / "big.c3d").string(), SmallTake("big", 40000, 60));
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl(CSW_BINARY, CSW_BINARY, "-q", "import", (dir / "big.c3d").c_str(), "-o", corpus.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until the import's temporary corpus exists and has grown, then kill.
  bool seen = false;
  for (int i = 0; i < 2000 && !seen; ++i) {
    for (const auto& e : fs::directory_iterator(dir.path())) {
      std::string n = e.path().filename().string();
      std::error_code ec;
      if (n != "corpus.h5" && n.find("corpus.h5") != std::string::npos && fs::file_size(e.path(), ec) > 200000)
        seen = true;
    }
    if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(seen) << "the import finished or never started writing before the kill";
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(Sha256OfFile(corpus.string()), before);
  Corpus c = Corpus::Open(corpus.string());
  ASSERT_EQ(c.Takes().size(), 1u);
  EXPECT_EQ(c.Takes()[0].name, "small");
  // The next import still works (a stale temporary file does not block it).
  EXPECT_EQ(Csw("import " + Q(dir / "big.c3d") + " -o " + Q(corpus), dir.path()).code, 0);
  EXPECT_EQ(Corpus::Open(corpus.string()).Takes().size(), 2u);
}

}  // namespace
}  // namespace csw

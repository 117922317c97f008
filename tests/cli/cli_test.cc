// End-to-end tests of the `csw` command line: exit codes, inspect against the
// reference values of ../shared/data/c3d/REFERENCE.tsv, import/info/export round
// trips, atomic imports and a real kill in the middle of an import.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
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

#include "core/build_paths.h"
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

// `fit --help` sends the reader to the page that describes the configuration (docs/models.md), not to
// the model file format.
TEST(Cli, FitHelpPointsToTheConfigurationDocs) {
  testing::TempDir dir;
  const RunResult help = Csw("fit --help", dir.path());
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("Model configuration JSON (docs/models.md, \"Configuration file\")"), std::string::npos)
      << help.out;
  EXPECT_EQ(help.out.find("model-format.md"), std::string::npos) << help.out;
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
// Waits (up to 10 s) until an import writing into a corpus has a take file
// of more than 200 kB in the corpus folder; false when it never had.
bool WaitForTakeFileToGrow(const fs::path& folder) {
  for (int i = 0; i < 2000; ++i) {
    std::error_code ec;
    for (const auto& e : fs::recursive_directory_iterator(folder, ec)) {
      if (e.is_regular_file(ec) && fs::file_size(e.path(), ec) > 200000) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

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
  const bool seen = WaitForTakeFileToGrow(dir / "corpus.h5.d");
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

// Usage errors exit 1 (was 2 for a --markerset file that does not exist), bad data 2.
TEST(Cli, ExitCodeUsageErrorIsOneBadDataIsTwo) {
  testing::TempDir dir;
  WriteC3d((dir / "a.c3d").string(), SmallTake("a", 20, 3));
  RunResult r =
      Csw("import " + Q(dir / "a.c3d") + " -o " + Q(dir / "c.h5") + " --markerset " + Q(dir / "no.json"), dir.path());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("--markerset"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "c.h5"));
  RunResult text = Csw("simulate shapes --text bonjour -o " + Q(dir / "s"), dir.path());
  EXPECT_EQ(text.code, 1) << text.err;
  EXPECT_NE(text.err.find("--text"), std::string::npos) << text.err;
  std::ofstream(dir / "bad.c3d") << std::string(700, 'x');
  EXPECT_EQ(Csw("import " + Q(dir / "bad.c3d") + " -o " + Q(dir / "c.h5"), dir.path()).code, 2);
}

// --phasing: a missing file is a usage error, a damaged one bad data; both name
// the file and write nothing.
TEST(Cli, SimulatePhasingFileErrorsNameTheFile) {
  testing::TempDir dir;
  RunResult missing =
      Csw("simulate sentences --text bonjour --phasing " + Q(dir / "no.json") + " -o " + Q(dir / "s"), dir.path());
  EXPECT_EQ(missing.code, 1) << missing.err;
  EXPECT_NE(missing.err.find("--phasing " + (dir / "no.json").string()), std::string::npos) << missing.err;
  std::ofstream(dir / "p.json") << R"({"placement_cv": {"start_mean_ms": "early"}})";
  RunResult bad =
      Csw("simulate sentences --text bonjour --phasing " + Q(dir / "p.json") + " -o " + Q(dir / "s"), dir.path());
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find((dir / "p.json").string()), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("start_mean_ms"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "s"));
}

// Point rate and count of valid samples of a C3D written by csw simulate.
struct C3dFacts {
  double rate_hz = 0;
  int64_t samples = 0, valid = 0;
};
C3dFacts FactsOf(const fs::path& c3d) {
  C3dReader reader(c3d.string());
  C3dFacts f;
  f.rate_hz = reader.info().point_rate_hz;
  f.samples = reader.info().points * reader.info().frames;
  double sum = 0;
  reader.ValidPointStats(&f.valid, &sum);
  return f;
}

// `csw simulate demo` ignored --rate, --noise, --no-occlusions, ... (demo always 120 Hz with gaps).
TEST(Cli, SimulateDemoHonoursRateAndNoOcclusions) {
  testing::TempDir dir;
  fs::path out = dir / "demo";
  RunResult r = Csw("-q simulate demo --count 1 --rate 100 --no-occlusions --dropouts 0 -o " + Q(out), dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  int takes = 0;
  for (const char* sub : {"shapes", "visemes", "sentences"}) {
    for (const auto& e : fs::directory_iterator(out / sub)) {
      if (e.path().extension() != ".c3d") continue;
      SCOPED_TRACE(e.path().string());
      C3dFacts f = FactsOf(e.path());
      EXPECT_EQ(f.rate_hz, 100.0);
      EXPECT_GT(f.samples, 0);
      EXPECT_EQ(f.valid, f.samples) << "a gap without occlusions or dropouts";
      ++takes;
    }
  }
  EXPECT_EQ(takes, 6);  // 1 shapes take, 4 viseme items, 1 sentence
  // The defaults (120 Hz, occlusions) still give gaps: the options above made the difference.
  fs::path def = dir / "default";
  ASSERT_EQ(Csw("-q simulate demo --count 1 -o " + Q(def), dir.path()).code, 0);
  C3dFacts f = FactsOf(def / "sentences" / "sentence_001.c3d");
  EXPECT_EQ(f.rate_hz, 120.0);
  EXPECT_LT(f.valid, f.samples);
  // --clean applies to demo too.
  fs::path clean = dir / "clean";
  ASSERT_EQ(Csw("-q simulate demo --count 1 --clean -o " + Q(clean), dir.path()).code, 0);
  EXPECT_TRUE(fs::exists(clean / "sentences" / "sentence_001.clean.c3d"));
  // --text replaces the 20 shipped sentences of demo: two texts give two sentence takes.
  fs::path text = dir / "text";
  RunResult t = Csw("-q simulate demo --text bonjour --text merci -o " + Q(text), dir.path());
  ASSERT_EQ(t.code, 0) << t.err;
  int sentences = 0;
  for (const auto& e : fs::directory_iterator(text / "sentences"))
    if (e.path().extension() == ".c3d") ++sentences;
  EXPECT_EQ(sentences, 2);
}

// Starts csw with `args` in its own process; returns the pid.
pid_t Spawn(const std::vector<std::string>& args) {
  pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(CSW_BINARY));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, STDOUT_FILENO);
    execv(CSW_BINARY, argv.data());
    _exit(127);
  }
  return pid;
}

// True once a file ending in `suffix` exists anywhere under `dir`.
bool AnyFileUnder(const fs::path& dir, const std::string& suffix) {
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    const std::string n = it->path().filename().string();
    if (n.size() >= suffix.size() && n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0) return true;
  }
  return false;
}

// Starts `csw simulate sentences` (40 takes), sends `sig` once a take has been
// written, and checks the exit code and that nothing is left behind.
void SignalDuringSimulateLeavesNothingBehind(int sig, int expected_code, const std::string& expected_message) {
  testing::TempDir dir;
  fs::path out = dir / "sim";
  fs::path err = dir / "err.txt";
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    int fd = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, STDERR_FILENO);
    int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, STDOUT_FILENO);
    execl(CSW_BINARY, CSW_BINARY, "-q", "simulate", "sentences", "--count", "40", "-o", out.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until at least one take has been written (somewhere under dir), then signal.
  bool seen = false;
  for (int i = 0; i < 6000 && !seen; ++i) {
    seen = AnyFileUnder(dir.path(), ".c3d");
    if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, sig);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(seen) << "simulate never wrote a take";
  ASSERT_TRUE(WIFEXITED(status)) << "ended by the signal instead of exiting";
  EXPECT_EQ(WEXITSTATUS(status), expected_code);
  std::ifstream in(err);
  std::string message((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(message.find(expected_message), std::string::npos) << message;
  // And it is true: no output folder, no partial folder, no take anywhere.
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(AnyFileUnder(dir.path(), ".c3d"));
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find("csw-partial"), std::string::npos) << e.path();
}

// Ctrl-C during simulate printed "nothing was changed" while the takes written so far stayed on disk.
TEST(Cli, CtrlCDuringSimulateLeavesNothingBehind) {
  SignalDuringSimulateLeavesNothingBehind(SIGINT, 130, "csw: cancelled; nothing was changed");
}

TEST(Cli, SigtermDuringSimulateExits143AndLeavesNothingBehind) {
  SignalDuringSimulateLeavesNothingBehind(SIGTERM, 143, "csw: terminated; nothing was changed");
}

// SIGTERM used to end csw with the signal's default action; now it cancels like Ctrl-C and exits 143.
TEST(Cli, SigtermDuringImportExits143AndKeepsTheCorpus) {
  testing::TempDir dir;
  WriteC3d((dir / "small.c3d").string(), SmallTake("small", 30, 3));
  fs::path corpus = dir / "corpus.h5";
  ASSERT_EQ(Csw("import " + Q(dir / "small.c3d") + " -o " + Q(corpus), dir.path()).code, 0);
  const std::string before = Sha256OfFile(corpus.string());
  WriteC3d((dir / "big.c3d").string(), SmallTake("big", 40000, 60));
  pid_t pid = Spawn({"-q", "import", (dir / "big.c3d").string(), "-o", corpus.string()});
  ASSERT_GE(pid, 0);
  const bool seen = WaitForTakeFileToGrow(dir / "corpus.h5.d");
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(seen) << "the import finished or never started writing before SIGTERM";
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of exiting";
  EXPECT_EQ(WEXITSTATUS(status), 143);
  EXPECT_EQ(Sha256OfFile(corpus.string()), before);
  const Corpus c = Corpus::Open(corpus.string());
  ASSERT_EQ(c.Takes().size(), 1u);
  EXPECT_EQ(c.Takes()[0].name, "small");
}

// `csw inspect models.h5` failed: every .h5 was opened as a corpus.
TEST(Cli, InspectModelsH5DescribesTheModelFile) {
  testing::TempDir dir;
  std::ofstream(dir / "fake.h5") << "not hdf5";
  RunResult fake = Csw("inspect " + Q(dir / "fake.h5"), dir.path());
  EXPECT_EQ(fake.code, 2);
  EXPECT_NE(fake.err.find("fake.h5: not an HDF5 file"), std::string::npos) << fake.err;
  // A corpus is still a corpus.
  WriteC3d((dir / "a.c3d").string(), SmallTake("a", 20, 3));
  ASSERT_EQ(Csw("import " + Q(dir / "a.c3d") + " -o " + Q(dir / "c.h5"), dir.path()).code, 0);
  RunResult c = Csw("inspect --json " + Q(dir / "c.h5"), dir.path());
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_EQ(json::parse(c.out)["format"], "corpus");
  EXPECT_EQ(json::parse(c.out)["take_count"].get<int>(), 1);
}

// The same for a model file written by `csw fit`: described, not taken for a corpus.
TEST(Cli, InspectModelsH5FromCswFitListsItsModels) {
  testing::TempDir dir;
  ASSERT_EQ(Csw("-q simulate shapes -o " + Q(dir / "s"), dir.path()).code, 0);
  ASSERT_EQ(Csw("-q import " + Q(dir / "s" / "shapes_01.c3d") + " -o " + Q(dir / "c.h5"), dir.path()).code, 0);
  RunResult fit = Csw("-q fit rigid " + Q(dir / "c.h5") + " --markerset " + Q(dir / "s" / "markerset.json") + " -o " +
                          Q(dir / "models.h5"),
                      dir.path());
  ASSERT_EQ(fit.code, 0) << fit.err;
  // Known from the inputs: the cluster sizes of the marker set, the frames of the take.
  std::ifstream ms(dir / "s" / "markerset.json");
  const json set = json::parse(ms);
  const int64_t frames = Corpus::Open((dir / "c.h5").string()).Summary("shapes_01").frames;
  RunResult r = Csw("inspect --json " + Q(dir / "models.h5"), dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["format"], "models");
  EXPECT_EQ(j["model_count"].get<int>(), 2);
  const std::pair<const char*, const char*> models[] = {{"head_motion", "head_cluster"},
                                                        {"forearm_motion", "forearm_cluster"}};
  for (const auto& [model, cluster] : models) {
    SCOPED_TRACE(model);
    ASSERT_TRUE(j["models"].contains(model)) << j.dump();
    const json& m = j["models"][model];
    EXPECT_EQ(m["markers"].get<size_t>(), set[cluster].size());
    EXPECT_EQ(m["training_takes"], json::array({"shapes_01"}));
    EXPECT_EQ(m["training_frames"].get<int64_t>(), frames);
    EXPECT_EQ(m["created_utc"].get<std::string>().size(), 20u);  // 2026-01-02T03:04:05Z
  }
  RunResult text = Csw("inspect " + Q(dir / "models.h5"), dir.path());
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("  head_motion: " + std::to_string(set["head_cluster"].size()) + " markers, "),
            std::string::npos)
      << text.out;
}

// C3D samples with NaN coordinates and a residual >= 0 (Vicon/pyCGM2): inspect
// counted them as valid (and gave sum_xyz_valid null) while import dropped them.
TEST(Cli, C3dNanWithResidualIsMissingInInspectAndImport) {
  testing::TempDir dir;
  const int64_t frames = 50, markers = 4;
  Take t = SmallTake("nan", frames, markers);  // one missing sample: frame 3, marker 1
  const fs::path c3d = dir / "nan.c3d";
  WriteC3d(c3d.string(), t);
  // Patch samples (frame, marker) to NaN coordinates with residual 0.0 (float storage, 16 bytes a sample).
  const std::vector<std::pair<int64_t, int64_t>> patched = {{0, 0}, {10, 2}, {49, 3}};
  {
    std::fstream f(c3d, std::ios::in | std::ios::out | std::ios::binary);
    unsigned char header[512];
    f.read(reinterpret_cast<char*>(header), 512);
    const int64_t data_block = header[16] | (header[17] << 8);  // word 9: first block of the data (1-based)
    const int64_t analog_words = header[4] | (header[5] << 8);  // word 3: analog values per frame
    ASSERT_EQ(header[2] | (header[3] << 8), markers);
    const int64_t frame_bytes = markers * 16 + analog_words * 4;
    const float nan = std::nanf(""), zero = 0.0f;
    for (const auto& [fr, m] : patched) {
      f.seekp((data_block - 1) * 512 + fr * frame_bytes + m * 16);
      f.write(reinterpret_cast<const char*>(&nan), 4);
      f.seekp((data_block - 1) * 512 + fr * frame_bytes + m * 16 + 12);
      f.write(reinterpret_cast<const char*>(&zero), 4);
    }
  }
  // The known answer, from the take the test wrote (file units are mm, POINT:SCALE -0.1 for float storage).
  int64_t valid = 0;
  double sum = 0;
  for (int64_t fr = 0; fr < frames; ++fr) {
    for (int64_t m = 0; m < markers; ++m) {
      if (!t.markers.Visible(fr, m)) continue;
      if (std::find(patched.begin(), patched.end(), std::make_pair(fr, m)) != patched.end()) continue;
      const float* p = t.markers.at(fr, m);
      sum += static_cast<double>(p[0]) + static_cast<double>(p[1]) + static_cast<double>(p[2]);
      ++valid;
    }
  }
  ASSERT_EQ(valid, frames * markers - 1 - 3);
  RunResult r = Csw("inspect --json " + Q(c3d), dir.path());
  ASSERT_EQ(r.code, 0) << r.err;
  json j = json::parse(r.out);
  EXPECT_EQ(j["valid_point_samples"].get<int64_t>(), valid);
  ASSERT_TRUE(j["sum_xyz_valid"].is_number()) << j["sum_xyz_valid"].dump();
  EXPECT_NEAR(j["sum_xyz_valid"].get<double>(), sum, 1e-9 * std::abs(sum));
  // Import stores the same samples.
  ASSERT_EQ(Csw("import " + Q(c3d) + " -o " + Q(dir / "c.h5"), dir.path()).code, 0);
  Take back = Corpus::Open((dir / "c.h5").string()).LoadTake("nan");
  EXPECT_EQ(back.markers.CountVisible(), valid);
  for (const auto& [fr, m] : patched) EXPECT_FALSE(back.markers.Visible(fr, m)) << fr << "," << m;
}

// csw cue on a lone TextGrid: usage errors exit 1, a missing phone tier exits 2
// with one line naming the tiers present, and a good request writes the copy.
TEST(Cli, CueTextGridExitCodesAndOutput) {
  testing::TempDir dir;
  // "bonjour" in SPPAS symbols, 0.1 s a phone: bo~ 34, Zu 41, R alone 13.
  LabelTier phones{"PhonAlign", LabelTier::Kind::kInterval, 0.0, 0.5, {}};
  const char* symbols[] = {"b", "o~", "Z", "u", "R"};
  for (int i = 0; i < 5; ++i) phones.labels.push_back({0.1 * i, 0.1 * (i + 1), symbols[i]});
  WriteTextGrid((dir / "a.TextGrid").string(), {phones}, 0.0, 0.5);
  EXPECT_EQ(Csw("cue " + Q(dir / "a.TextGrid"), dir.path()).code, 1);
  EXPECT_EQ(
      Csw("cue " + Q(dir / "a.TextGrid") + " -o " + Q(dir / "b.TextGrid") + " --symbols arpabet", dir.path()).code, 1);
  const RunResult missing = Csw("-q cue " + Q(dir / "a.TextGrid") + " -o " + Q(dir / "b.TextGrid"), dir.path());
  EXPECT_EQ(missing.code, 2);
  EXPECT_EQ(missing.err,
            (dir / "a.TextGrid").string() + ": no phone tier 'phones' (tiers: 'PhonAlign'); name it with --phones\n");
  EXPECT_FALSE(fs::exists(dir / "b.TextGrid"));
  const RunResult ok = Csw(
      "-q cue --json " + Q(dir / "a.TextGrid") + " -o " + Q(dir / "b.TextGrid") + " --phones PhonAlign", dir.path());
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(json::parse(ok.out)["takes"][0]["sequence"], "00 34 41 13 00");
  const std::vector<LabelTier> tiers = ReadTextGrid((dir / "b.TextGrid").string());
  ASSERT_EQ(tiers.size(), 2u);
  EXPECT_EQ(tiers[1].name, "expected_keys");
  ASSERT_EQ(tiers[1].labels.size(), 3u);
  EXPECT_EQ(tiers[1].labels[0].text, "34");
  EXPECT_EQ(tiers[1].labels[2].text, "13");
}

}  // namespace
}  // namespace csw

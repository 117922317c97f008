// Format version 2: index file + folder of immutable per-take files joined by
// HDF5 external links. Commits cost what changed; version-1 and packed files
// still open and are upgraded by the first transaction; garbage collection
// respects readers in this and other processes.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/progress.h"
#include "io/corpus/corpus.h"
#include "io/corpus/corpus_tools.h"
#include "tests/io/corpus/corpus_test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
using testing::ExpectSameTake;
using testing::MakeFullTake;
using testing::TempDir;

void WriteCorpus(const std::string& path, const std::vector<Take>& takes) {
  CorpusTransaction tx(path);
  for (const Take& t : takes) tx.WriteTake(t);
  tx.Commit();
}

std::vector<std::string> FolderFiles(const std::string& corpus) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(CorpusTransaction::FolderPath(corpus), ec)) {
    out.push_back(e.path().filename().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The file an external link /takes/<take>/<member> of the index names
// ("" when the member is not an external link), read with the raw HDF5 API.
std::string LinkedFile(const std::string& corpus, const std::string& take, const std::string& member) {
  hid_t f = H5Fopen(corpus.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return "";
  const std::string link = "/takes/" + take + "/" + member;
  std::string out;
  H5L_info_t info;
  if (H5Lget_info(f, link.c_str(), &info, H5P_DEFAULT) >= 0 && info.type == H5L_TYPE_EXTERNAL) {
    std::vector<char> buf(info.u.val_size);
    const char* file = nullptr;
    const char* obj = nullptr;
    unsigned flags = 0;
    if (H5Lget_val(f, link.c_str(), buf.data(), buf.size(), H5P_DEFAULT) >= 0 &&
        H5Lunpack_elink_val(buf.data(), buf.size(), &flags, &file, &obj) >= 0) {
      out = file;
    }
  }
  H5Fclose(f);
  return out;
}

std::string Bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void SetIntAttr(hid_t obj, const char* name, int64_t v) {
  if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
  hid_t s = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(obj, name, H5T_STD_I64LE, s, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(a, H5T_NATIVE_INT64, &v);
  H5Aclose(a);
  H5Sclose(s);
}

// A corpus in the version-1 layout (one self-contained file, format_version
// 1, no cached summary or markerset attributes), as csw before version 2
// wrote it: the takes are written by csw and packed (every member then lives
// in the one file, exactly at its version-1 path), and the version-2
// additions are removed with the raw HDF5 API.
void WriteVersion1Corpus(const std::string& path, const std::vector<Take>& takes) {
  TempDir scratch;
  const std::string v2 = (scratch / "v2.h5").string();
  WriteCorpus(v2, takes);
  Progress progress;
  PackCorpus(v2, path, progress);
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  SetIntAttr(f, "format_version", 1);
  H5Adelete(f, "layout");
  for (const Take& t : takes) {
    hid_t g = H5Gopen2(f, ("/takes/" + t.name).c_str(), H5P_DEFAULT);
    ASSERT_GE(g, 0);
    for (const char* a :
         {"frame_count", "marker_count", "gap_count", "has_audio", "analog_channels", "tier_names", "markerset"}) {
      EXPECT_GE(H5Adelete(g, a), 0) << a;
    }
    H5Gclose(g);
  }
  H5Fclose(f);
}

int64_t TotalGaps(const MarkerArray& a) {
  int64_t n = 0;
  for (int64_t m = 0; m < a.markers(); ++m) n += CountGaps(a, m);
  return n;
}

int64_t Version(const std::string& path) {
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  int64_t v = -1;
  hid_t a = H5Aopen(f, "format_version", H5P_DEFAULT);
  H5Aread(a, H5T_NATIVE_INT64, &v);
  H5Aclose(a);
  H5Fclose(f);
  return v;
}

TEST(CorpusV2, IndexLinksEveryMemberIntoPerTakeFiles) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("t", 300, 4)});
  EXPECT_EQ(Version(path), 2);
  const std::string data = LinkedFile(path, "t", "markers");
  EXPECT_EQ(data.rfind("c.h5.d/t-", 0), 0u) << data;
  for (const char* member : {"marker_names", "analog", "events", "provenance"}) {
    EXPECT_EQ(LinkedFile(path, "t", member), data) << member;
  }
  const std::string tiers = LinkedFile(path, "t", "tiers");
  const std::string audio = LinkedFile(path, "t", "audio");
  EXPECT_NE(tiers, data);
  EXPECT_NE(audio, data);
  EXPECT_NE(tiers, audio);
  EXPECT_EQ(FolderFiles(path).size(), 3u);
  EXPECT_EQ(Corpus::Open(path).format_version(), 2);
}

TEST(CorpusV2, TierOnlyCommitsNeverTouchTheMarkersFileAndTheIndexStaysSmall) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take t = MakeFullTake("t", 6000, 20);
  WriteCorpus(path, {t});
  const std::string data = (dir / LinkedFile(path, "t", "markers")).string();
  struct stat before {};
  ASSERT_EQ(stat(data.c_str(), &before), 0);
  const std::string bytes_before = Bytes(data);
  const auto index_first = fs::file_size(path);
  LabelTier tier = t.tiers[0];
  for (int i = 0; i < 200; ++i) {
    tier.labels[0].text = "edit " + std::to_string(i % 10);
    CorpusTransaction tx(path);
    tx.WriteTiers("t", {tier, t.tiers[1]});
    tx.Commit();
  }
  struct stat after {};
  ASSERT_EQ(stat(data.c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_EQ(after.st_mtim.tv_sec, before.st_mtim.tv_sec);
  EXPECT_EQ(after.st_mtim.tv_nsec, before.st_mtim.tv_nsec);
  EXPECT_EQ(Bytes(data), bytes_before);
  EXPECT_EQ((dir / LinkedFile(path, "t", "markers")).string(), data);
  // A fresh index per commit: exactly as large as the first one (same names,
  // same-length texts live in the tiers file, not in the index), and small.
  EXPECT_EQ(fs::file_size(path), index_first);
  EXPECT_LT(fs::file_size(path), 64u * 1024);
  // The superseded tiers files were collected: data, tiers, audio.
  EXPECT_EQ(FolderFiles(path).size(), 3u);
  // Audio changes and removing or adding another take leave it alone too.
  {
    Audio mono;
    mono.rate_hz = 8000;
    mono.samples = {0.5f, -0.5f};
    CorpusTransaction tx(path);
    tx.WriteAudio("t", mono, "new.wav");
    tx.WriteTake(MakeFullTake("other", 10, 2));
    tx.Commit();
  }
  {
    CorpusTransaction tx(path);
    tx.RemoveTake("other");
    tx.Commit();
  }
  ASSERT_EQ(stat(data.c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_EQ(after.st_mtim.tv_nsec, before.st_mtim.tv_nsec);
  EXPECT_EQ(Bytes(data), bytes_before);
  EXPECT_EQ(Corpus::Open(path).LoadTake("t").audio.samples, (std::vector<float>{0.5f, -0.5f}));
  t.audio.rate_hz = 8000;
  t.audio.channels = 1;
  t.audio.samples = {0.5f, -0.5f};
  t.audio_path = "new.wav";
  Take back = Corpus::Open(path).LoadTake("t");
  Take expected = t;
  expected.tiers = {tier, t.tiers[1]};
  ExpectSameTake(expected, back);
}

TEST(CorpusV2, ReadsWorkWhateverTheCurrentDirectory) {
  TempDir dir;
  TempDir elsewhere;
  const std::string path = (dir / "c.h5").string();
  Take t = MakeFullTake("t", 500, 5);
  WriteCorpus(path, {t});
  const fs::path cwd = fs::current_path();
  fs::current_path(elsewhere.path());
  {
    // Absolute path, cwd without the folder: HDF5 resolves the relative link
    // names against the index file's folder.
    ExpectSameTake(t, Corpus::Open(path).LoadTake("t"));
    // A relative path to the corpus from another directory.
    const std::string rel = fs::relative(path, elsewhere.path()).string();
    ASSERT_NE(rel.find(".."), std::string::npos) << rel;
    ExpectSameTake(t, Corpus::Open(rel).LoadTake("t"));
    // The raw API: one open call, then /takes/t/markers.
    hid_t f = H5Fopen(rel.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    hid_t d = H5Dopen2(f, "/takes/t/markers", H5P_DEFAULT);
    EXPECT_GE(d, 0);
    if (d >= 0) H5Dclose(d);
    H5Fclose(f);
  }
  fs::current_path(dir.path());
  ExpectSameTake(t, Corpus::Open("c.h5").LoadTake("t"));  // relative, from its own folder
  fs::current_path(cwd);
}

TEST(CorpusV2, Version1FileOpensReadsAndIsUpgradedByTheFirstTransaction) {
  TempDir dir;
  const std::string path = (dir / "old.h5").string();
  Take a = MakeFullTake("a", 700, 6);
  Take b = MakeFullTake("b", 250, 3);
  WriteVersion1Corpus(path, {a, b});
  ASSERT_EQ(Version(path), 1);
  EXPECT_EQ(LinkedFile(path, "a", "markers"), "");  // really one file
  {
    Corpus v1 = Corpus::Open(path);
    EXPECT_EQ(v1.format_version(), 1);
    std::vector<TakeSummary> s = v1.Takes();
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0].frames, 700);
    EXPECT_EQ(s[0].markers, 6);
    EXPECT_TRUE(s[0].has_audio);
    EXPECT_EQ(s[0].analog_channels, 2);
    EXPECT_EQ(s[0].tier_names, (std::vector<std::string>{"phones", "keys/targets"}));
    ExpectSameTake(a, v1.LoadTake("a"));
    ExpectSameTake(b, v1.LoadTake("b"));
  }
  LabelTier words;
  words.name = "mots";
  words.end_s = 1.0;
  words.labels = {{0.0, 1.0, "bonjour"}};
  {
    CorpusTransaction tx(path);
    tx.WriteTiers("b", {words});
    tx.Commit();
  }
  EXPECT_EQ(Version(path), 2);
  EXPECT_FALSE(LinkedFile(path, "a", "markers").empty());
  EXPECT_FALSE(LinkedFile(path, "b", "markers").empty());
  EXPECT_EQ(FolderFiles(path).size(), 6u);
  Corpus v2 = Corpus::Open(path);
  ExpectSameTake(a, v2.LoadTake("a"));
  b.tiers = {words};
  ExpectSameTake(b, v2.LoadTake("b"));
  // The gap count the version-1 file did not cache is counted at the upgrade.
  EXPECT_EQ(v2.Summary("a").gaps, TotalGaps(a.markers));
  EXPECT_GT(TotalGaps(a.markers), 0);
}

TEST(CorpusV2, UpgradeCorpusSplitsAVersion1FileOnceAndKeepsEveryTake) {
  TempDir dir;
  const std::string path = (dir / "old.h5").string();
  Take a = MakeFullTake("a", 400, 4);
  Take b = MakeFullTake("b", 100, 2);
  WriteVersion1Corpus(path, {a, b});
  std::vector<std::string> stages;
  Progress progress([&](const std::string& stage, double) { stages.push_back(stage); });
  EXPECT_TRUE(UpgradeCorpus(path, progress));
  EXPECT_FALSE(stages.empty());
  EXPECT_EQ(Version(path), 2);
  EXPECT_EQ(FolderFiles(path).size(), 6u);
  Corpus corpus = Corpus::Open(path);
  ExpectSameTake(a, corpus.LoadTake("a"));
  ExpectSameTake(b, corpus.LoadTake("b"));
  EXPECT_EQ(corpus.Summary("a").gaps, TotalGaps(a.markers));
  const std::string index = Bytes(path);
  EXPECT_FALSE(UpgradeCorpus(path, progress));  // already version 2: nothing written
  EXPECT_EQ(Bytes(path), index);
}

TEST(CorpusV2, PackedFileIsSelfContainedOpensWithIdenticalTakesAndUpgrades) {
  TempDir dir;
  TempDir other;
  const std::string path = (dir / "c.h5").string();
  Take a = MakeFullTake("a", 800, 5);
  Take b = MakeFullTake("b", 60, 2);
  b.markerset_json = R"({"name": "LPC", "markers": ["Lèvre_sup", "M1"]})";
  Take empty;
  empty.name = "empty";
  empty.rate_hz = 120;
  empty.provenance.imported_utc = "2026-01-01T00:00:00Z";
  empty.provenance.csw_version = "x";
  WriteCorpus(path, {a, b, empty});
  const std::string packed = (other / "send.h5").string();
  Progress progress;
  PackCorpus(path, packed, progress);
  EXPECT_THROW(PackCorpus(path, packed, progress), IoError);  // never replaces a file
  EXPECT_THROW(PackCorpus(path, path, progress), IoError);
  // Self-contained: no external link, and it opens with the original's folder gone.
  EXPECT_EQ(LinkedFile(packed, "a", "markers"), "");
  EXPECT_EQ(LinkedFile(packed, "a", "tiers"), "");
  EXPECT_FALSE(fs::exists(CorpusTransaction::FolderPath(packed)));
  fs::rename(CorpusTransaction::FolderPath(path), (dir / "moved.d").string());
  {
    Corpus c = Corpus::Open(packed);
    std::vector<TakeSummary> s = c.Takes();
    ASSERT_EQ(s.size(), 3u);
    ExpectSameTake(a, c.LoadTake("a"));
    ExpectSameTake(b, c.LoadTake("b"));
    ExpectSameTake(empty, c.LoadTake("empty"));
    EXPECT_EQ(c.TakeMarkerSet("b"), b.markerset_json);
    EXPECT_TRUE(c.Summary("b").has_markerset);
  }
  // A transaction on the packed file splits it again.
  {
    CorpusTransaction tx(packed);
    tx.RemoveTake("empty");
    tx.Commit();
  }
  EXPECT_FALSE(LinkedFile(packed, "a", "markers").empty());
  Corpus c = Corpus::Open(packed);
  ASSERT_EQ(c.Takes().size(), 2u);
  ExpectSameTake(a, c.LoadTake("a"));
  ExpectSameTake(b, c.LoadTake("b"));
  EXPECT_EQ(c.TakeMarkerSet("b"), b.markerset_json);
}

TEST(CorpusV2, MissingTakeFileGivesOneClearErrorNamingCorpusTakeAndFile) {
  TempDir dir;
  const std::string path = (dir / "corpus.h5").string();
  WriteCorpus(path, {MakeFullTake("take01", 50, 2), MakeFullTake("take03", 50, 2)});
  const std::string rel = LinkedFile(path, "take03", "markers");
  ASSERT_FALSE(rel.empty());
  fs::remove(dir / rel);
  try {
    Corpus::Open(path);
    FAIL() << "no error";
  } catch (const IoError& e) {
    const std::string expected = path + ": take 'take03': its file " + rel +
                                 " is missing; the folder corpus.h5.d must stay beside corpus.h5 (use csw pack to "
                                 "send one file)";
    EXPECT_EQ(std::string(e.what()), expected);
  }
  // The whole folder gone (index copied alone): the first take is named.
  fs::remove_all(CorpusTransaction::FolderPath(path));
  try {
    Corpus::Open(path);
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("take 'take01': its file corpus.h5.d/take01-"), std::string::npos) << e.what();
  }
}

TEST(CorpusV2, GarbageIsCollectedOnlyWhenNoReaderMayNeedIt) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take first = MakeFullTake("t", 200, 3);
  WriteCorpus(path, {first});
  Take second = MakeFullTake("t", 300, 3);
  second.rate_hz = 250;
  Take third = MakeFullTake("t", 100, 3);
  third.rate_hz = 60;

  // No reader: replacing the take deletes its old files at commit.
  std::string old_data = LinkedFile(path, "t", "markers");
  {
    CorpusTransaction tx(path);
    tx.WriteTake(second, IfTakeExists::kReplace);
    tx.Commit();
  }
  EXPECT_FALSE(fs::exists(dir / old_data));
  EXPECT_EQ(FolderFiles(path).size(), 3u);

  // A live Corpus of this process keeps the files of its generation.
  old_data = LinkedFile(path, "t", "markers");
  {
    Corpus reader = Corpus::Open(path);
    {
      CorpusTransaction tx(path);
      tx.WriteTake(third, IfTakeExists::kReplace);
      tx.Commit();
    }
    EXPECT_TRUE(fs::exists(dir / old_data));
    ExpectSameTake(second, reader.LoadTake("t"));  // still the state it opened
    ExpectSameTake(third, Corpus::Open(path).LoadTake("t"));
  }
  {
    CorpusTransaction tx(path);  // the reader is gone: the next transaction collects
    tx.Commit();
  }
  EXPECT_FALSE(fs::exists(dir / old_data));
  EXPECT_EQ(FolderFiles(path).size(), 3u);

  // A reader in another process: nothing is deleted while it holds the corpus open.
  old_data = LinkedFile(path, "t", "markers");
  int ready[2];
  int go[2];
  ASSERT_EQ(pipe(ready), 0);
  ASSERT_EQ(pipe(go), 0);
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    int code = 0;
    try {
      Corpus reader = Corpus::Open(path);
      char c = 'r';
      if (write(ready[1], &c, 1) != 1) _exit(5);
      if (read(go[0], &c, 1) != 1) _exit(6);
      // After the parent's commit: the generation this reader opened still reads.
      Take t = reader.LoadTake("t");
      code =
          (t.rate_hz == 60 && t.frames() == 100 && testing::SameFloats(t.markers.data(), third.markers.data())) ? 0 : 7;
    } catch (...) {
      code = 8;
    }
    _exit(code);
  }
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);
  {
    CorpusTransaction tx(path);
    tx.WriteTake(first, IfTakeExists::kReplace);
    tx.Commit();
  }
  EXPECT_TRUE(fs::exists(dir / old_data));
  EXPECT_EQ(FolderFiles(path).size(), 6u);
  ASSERT_EQ(write(go[1], "g", 1), 1);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child status " << status;
  for (int fd : {ready[0], ready[1], go[0], go[1]}) close(fd);
  {
    CorpusTransaction tx(path);  // the other process has exited
    tx.Commit();
  }
  EXPECT_FALSE(fs::exists(dir / old_data));
  EXPECT_EQ(FolderFiles(path).size(), 3u);
  ExpectSameTake(first, Corpus::Open(path).LoadTake("t"));
}

TEST(CorpusV2, MarkerSetJsonRoundTrips) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take with = MakeFullTake("with", 30, 2);
  with.markerset_json = "{\"name\": \"virtual cuer\", \"note\": \"é → ʁ\", \"pad\": \"" + std::string(100000, 'x') +
                        "\"}";  // larger than HDF5's 64 KiB compact attribute limit
  Take without = MakeFullTake("without", 30, 2);
  WriteCorpus(path, {with, without});
  Corpus corpus = Corpus::Open(path);
  EXPECT_EQ(corpus.LoadTake("with").markerset_json, with.markerset_json);
  EXPECT_EQ(corpus.LoadTake("without").markerset_json, "");
  EXPECT_EQ(corpus.TakeMarkerSet("with"), with.markerset_json);
  EXPECT_EQ(corpus.TakeMarkerSet("without"), "");
  EXPECT_TRUE(corpus.Summary("with").has_markerset);
  EXPECT_FALSE(corpus.Summary("without").has_markerset);
  EXPECT_THROW(corpus.TakeMarkerSet("nope"), InvalidInput);
  // Kept by a commit that does not touch the take.
  {
    CorpusTransaction tx(path);
    tx.WriteTiers("without", {});
    tx.Commit();
  }
  EXPECT_EQ(Corpus::Open(path).TakeMarkerSet("with"), with.markerset_json);
}

TEST(CorpusV2, H5pyReadsMarkersAndTiersThroughTheIndexWithOneOpenCall) {
  // The first python3 on PATH with h5py, else Debian's (a pyenv python3 may shadow it).
  std::string python;
  for (const char* candidate : {"python3", "/usr/bin/python3"}) {
    if (std::system((std::string(candidate) + " -c 'import h5py' > /dev/null 2>&1").c_str()) == 0) {
      python = candidate;
      break;
    }
  }
  if (python.empty()) GTEST_SKIP() << "python3 h5py not installed (Debian package python3-h5py)";
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("take01", 120, 4)});
  const std::string script = (dir / "read.py").string();
  const std::string out = (dir / "out.txt").string();
  std::ofstream(script) << "import sys, h5py\n"
                           "f = h5py.File(sys.argv[1], 'r')\n"
                           "m = f['takes/take01/markers']\n"
                           "t = f['takes/take01/tiers/000_phones/text'].asstr()[()]\n"
                           "n = f['takes/take01/marker_names'].asstr()[()]\n"
                           "open(sys.argv[2], 'w', encoding='utf-8').write('%s|%s|%s|%d|%s' % (m.shape, t[0], t[1], "
                           "f.attrs['format_version'], n[0]))\n";
  // From another directory, so that the links resolve against the index's folder.
  const std::string cmd = "cd / && " + python + " '" + script + "' '" + path + "' '" + out + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  EXPECT_EQ(Bytes(out), "(120, 4, 3)|ʁ|é|2|Lèvre_sup");
}

TEST(CorpusV2, H5dumpReadsMarkersThroughTheIndexFromAnotherDirectory) {
  if (std::system("command -v h5dump > /dev/null 2>&1") != 0) GTEST_SKIP() << "h5dump not installed (hdf5-tools)";
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take t = MakeFullTake("t", 3, 2);
  WriteCorpus(path, {t});
  const std::string out = (dir / "dump.txt").string();
  const std::string cmd = "cd / && h5dump -d /takes/t/markers -s 1,1,0 -c 1,1,3 '" + path + "' > '" + out + "' 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << Bytes(out);
  const std::string dump = Bytes(out);
  char expected[128];
  const float* p = t.markers.at(1, 1);
  std::snprintf(expected, sizeof expected, "(1,1,0): %g, %g, %g", p[0], p[1], p[2]);
  EXPECT_NE(dump.find(expected), std::string::npos) << dump << "\nexpected " << expected;
}

}  // namespace
}  // namespace csw

#include "io/corpus/corpus.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/progress.h"
#include "tests/io/corpus/corpus_test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
using testing::ExpectSameMarkers;
using testing::ExpectSameTake;
using testing::MakeFullTake;
using testing::SmoothMarkers;
using testing::TempDir;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

void WriteCorpus(const std::string& path, const std::vector<Take>& takes) {
  CorpusTransaction tx(path);
  for (const Take& t : takes) tx.WriteTake(t);
  tx.Commit();
}

int64_t TotalGaps(const MarkerArray& a) {
  int64_t n = 0;
  for (int64_t m = 0; m < a.markers(); ++m) n += CountGaps(a, m);
  return n;
}

TEST(Corpus, RoundTripOfEverything) {
  TempDir dir;
  const std::string path = (dir / "corpus.h5").string();
  Take take = MakeFullTake("take01");
  WriteCorpus(path, {take});

  Corpus corpus = Corpus::Open(path);
  EXPECT_EQ(corpus.path(), path);
  EXPECT_TRUE(corpus.HasTake("take01"));
  EXPECT_FALSE(corpus.HasTake("take02"));
  Take back = corpus.LoadTake("take01");
  ExpectSameTake(take, back);

  // Known answers for the summary: 4 markers, gaps where (f / 7 + m) % 11 == 0
  // over 120 frames: marker 0 misses frames 0-6 and 77-83 (2 gaps), marker 1
  // 70-76, marker 2 63-69, marker 3 56-62 (1 gap each).
  std::vector<TakeSummary> takes = corpus.Takes();
  ASSERT_EQ(takes.size(), 1u);
  const TakeSummary& s = takes[0];
  EXPECT_EQ(s.name, "take01");
  EXPECT_EQ(s.rate_hz, 100.0);
  EXPECT_EQ(s.frames, 120);
  EXPECT_EQ(s.markers, 4);
  EXPECT_EQ(s.gaps, 5);
  EXPECT_EQ(s.gaps, TotalGaps(take.markers));
  EXPECT_DOUBLE_EQ(s.duration_s, 1.2);
  EXPECT_EQ(s.tier_names, (std::vector<std::string>{"phones", "keys/targets"}));
  EXPECT_TRUE(s.has_audio);
  EXPECT_EQ(s.analog_channels, 2);
}

TEST(Corpus, RootAttributesAndReservedGroups) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {});
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  for (const char* g : {"takes", "models", "dictionaries"}) EXPECT_GT(H5Lexists(f, g, H5P_DEFAULT), 0) << g;
  hid_t a = H5Aopen(f, "format_version", H5P_DEFAULT);
  ASSERT_GE(a, 0);
  int64_t version = 0;
  EXPECT_GE(H5Aread(a, H5T_NATIVE_INT64, &version), 0);
  EXPECT_EQ(version, kCorpusFormatVersion);
  H5Aclose(a);
  H5Fclose(f);
  EXPECT_TRUE(Corpus::Open(path).Takes().empty());
}

TEST(Corpus, ManyTakesListedInNameOrder) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("b", 10, 2), MakeFullTake("a", 20, 3), MakeFullTake("c", 5, 1)});
  std::vector<TakeSummary> takes = Corpus::Open(path).Takes();
  ASSERT_EQ(takes.size(), 3u);
  EXPECT_EQ(takes[0].name, "a");
  EXPECT_EQ(takes[0].frames, 20);
  EXPECT_EQ(takes[0].markers, 3);
  EXPECT_EQ(takes[1].name, "b");
  EXPECT_EQ(takes[1].frames, 10);
  EXPECT_EQ(takes[2].name, "c");
  EXPECT_EQ(takes[2].markers, 1);
}

TEST(Corpus, StreamingInUnevenChunksEqualsOneShot) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take take = MakeFullTake("oneshot", 1500, 7);
  Take streamed_header = take;
  streamed_header.name = "streamed";
  streamed_header.markers = MarkerArray();
  // Analog: the first 100 samples in the header, the rest appended in pieces.
  streamed_header.analog.samples = 100;
  streamed_header.analog.data.resize(100 * 2);
  {
    CorpusTransaction tx(path);
    tx.WriteTake(take);
    CorpusTransaction::TakeWriter w = tx.BeginTake(streamed_header);
    const int64_t row = 7 * 3;
    int64_t f = 0;
    const int64_t pieces[] = {1, 17, 300, 0, 256, 255, 171, 3, 600};
    for (int64_t n : pieces) {
      n = std::min(n, take.frames() - f);
      w.AppendFrames(take.markers.data().data() + f * row, n);
      f += n;
      EXPECT_EQ(w.frames_written(), f);
    }
    w.AppendFrames(take.markers.data().data() + f * row, take.frames() - f);
    int64_t s = 100;
    for (int64_t n : {1, 999, 4000}) {
      n = std::min(n, take.analog.samples - s);
      w.AppendAnalog(take.analog.data.data() + s * 2, n);
      s += n;
    }
    w.AppendAnalog(take.analog.data.data() + s * 2, take.analog.samples - s);
    w.Finish();
    EXPECT_THROW(w.AppendFrames(take.markers.data().data(), 1), Error);
    tx.Commit();
  }
  Corpus corpus = Corpus::Open(path);
  Take one = corpus.LoadTake("oneshot");
  Take streamed = corpus.LoadTake("streamed");
  ExpectSameTake(take, one);
  streamed.name = "oneshot";
  ExpectSameTake(one, streamed);
  EXPECT_EQ(corpus.Summary("streamed").gaps, TotalGaps(take.markers));
  EXPECT_EQ(corpus.Summary("oneshot").gaps, corpus.Summary("streamed").gaps);
}

TEST(Corpus, LoadMarkersReadsAFrameWindow) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take take = MakeFullTake("t", 1000, 5);
  WriteCorpus(path, {take});
  Corpus corpus = Corpus::Open(path);
  MarkerArray window = corpus.LoadMarkers("t", 250, 300);  // crosses chunk boundaries
  ASSERT_EQ(window.frames(), 300);
  ASSERT_EQ(window.markers(), 5);
  for (int64_t f = 0; f < 300; ++f) {
    for (int64_t m = 0; m < 5; ++m) {
      for (int k = 0; k < 3; ++k) {
        float expected = take.markers.at(250 + f, m)[k];
        float got = window.at(f, m)[k];
        if (std::isnan(expected)) {
          EXPECT_TRUE(std::isnan(got));
        } else {
          EXPECT_EQ(expected, got);
        }
      }
    }
  }
  EXPECT_EQ(corpus.LoadMarkers("t", 1000, 0).frames(), 0);
  EXPECT_THROW(corpus.LoadMarkers("t", 900, 101), InvalidInput);
  EXPECT_THROW(corpus.LoadMarkers("t", -1, 5), InvalidInput);
  EXPECT_THROW(corpus.LoadMarkers("nope", 0, 5), InvalidInput);
  EXPECT_THROW(corpus.LoadTake("nope"), InvalidInput);
}

TEST(Corpus, ChunkingShuffleAndDeflateAreSet) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take take = MakeFullTake("t", 2000, 20);
  WriteCorpus(path, {take});
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  hid_t d = H5Dopen2(f, "/takes/t/markers", H5P_DEFAULT);
  ASSERT_GE(d, 0);
  hid_t dcpl = H5Dget_create_plist(d);
  EXPECT_EQ(H5Pget_layout(dcpl), H5D_CHUNKED);
  hsize_t chunk[3] = {0, 0, 0};
  EXPECT_EQ(H5Pget_chunk(dcpl, 3, chunk), 3);
  EXPECT_EQ(chunk[0], static_cast<hsize_t>(kCorpusChunkFrames));
  EXPECT_EQ(chunk[1], 20u);
  EXPECT_EQ(chunk[2], 3u);
  ASSERT_EQ(H5Pget_nfilters(dcpl), 2);
  unsigned flags = 0;
  size_t nelmts = 4;
  unsigned cd[4] = {0, 0, 0, 0};
  EXPECT_EQ(H5Pget_filter2(dcpl, 0, &flags, &nelmts, cd, 0, nullptr, nullptr), H5Z_FILTER_SHUFFLE);
  nelmts = 4;
  EXPECT_EQ(H5Pget_filter2(dcpl, 1, &flags, &nelmts, cd, 0, nullptr, nullptr), H5Z_FILTER_DEFLATE);
  ASSERT_GE(nelmts, 1u);
  EXPECT_EQ(cd[0], static_cast<unsigned>(kCorpusDeflateLevel));
  // The filters really ran: smooth trajectories shrink well below raw size.
  hsize_t stored = H5Dget_storage_size(d);
  const hsize_t raw = 2000 * 20 * 3 * sizeof(float);
  EXPECT_GT(stored, 0u);
  EXPECT_LT(stored, raw * 3 / 4);
  // Units are declared on the dataset.
  hid_t a = H5Aopen(d, "units", H5P_DEFAULT);
  EXPECT_GE(a, 0);
  H5Aclose(a);
  H5Pclose(dcpl);
  H5Dclose(d);
  H5Fclose(f);
}

// Runs a command and returns its standard output.
std::string RunCommand(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  pclose(p);
  return out;
}

// The numbers h5dump prints in the DATA block of one dataset, in order.
std::vector<std::string> H5dumpValues(const std::string& dump) {
  std::vector<std::string> values;
  size_t data = dump.find("DATA {");
  if (data == std::string::npos) return values;
  std::istringstream in(dump.substr(data));
  std::string line;
  std::getline(in, line);  // "DATA {"
  while (std::getline(in, line)) {
    if (line.find('}') != std::string::npos) break;  // end of the DATA block
    size_t idx = line.find("):");
    if (idx == std::string::npos) continue;
    std::string rest = line.substr(idx + 2);
    std::istringstream fields(rest);
    std::string v;
    while (std::getline(fields, v, ',')) {
      size_t b = v.find_first_not_of(" \t");
      size_t e = v.find_last_not_of(" \t");
      if (b != std::string::npos) values.push_back(v.substr(b, e - b + 1));
    }
  }
  return values;
}

TEST(Corpus, H5dumpReadsTheMarkerValues) {
  if (std::system("command -v h5dump > /dev/null 2>&1") != 0) GTEST_SKIP() << "h5dump not installed (hdf5-tools)";
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take take;
  take.name = "t";
  take.rate_hz = 50;
  take.marker_names = {"A", "B"};
  take.markers = MarkerArray(2, 2);
  const float values[] = {1.5f, -2.25f, 1234.5f, 0.125f, 7.0f, -8.5f, 3.0f, 4.0f, 5.0f};
  std::copy(values, values + 9, take.markers.data().begin());  // frame 1 marker 1 stays NaN
  WriteCorpus(path, {take});
  std::string dump = RunCommand("h5dump -d /takes/t/markers '" + path + "' 2>&1");
  ASSERT_NE(dump.find("H5T_IEEE_F32LE"), std::string::npos) << dump;
  std::vector<std::string> got = H5dumpValues(dump);
  ASSERT_EQ(got.size(), 12u) << dump;
  for (int i = 0; i < 9; ++i) EXPECT_EQ(std::strtod(got[i].c_str(), nullptr), values[i]) << got[i];
  for (int i = 9; i < 12; ++i) EXPECT_TRUE(std::isnan(std::strtod(got[i].c_str(), nullptr))) << got[i];
  // The marker names come out as UTF-8 strings.
  std::string names = RunCommand("h5dump -d /takes/t/marker_names '" + path + "' 2>&1");
  EXPECT_NE(names.find("\"A\", \"B\""), std::string::npos) << names;
  EXPECT_NE(names.find("H5T_CSET_UTF8"), std::string::npos) << names;
}

TEST(Corpus, ExistingTakeIsRefusedUnlessReplaced) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("t", 3000, 10)});
  const auto size_before = fs::file_size(path);
  Take replacement = MakeFullTake("t", 3000, 10);
  replacement.rate_hz = 250.0;
  {
    CorpusTransaction tx(path);
    EXPECT_THROW(tx.WriteTake(replacement), InvalidInput);
    tx.WriteTake(replacement, IfTakeExists::kReplace);
    tx.Commit();
  }
  Corpus corpus = Corpus::Open(path);
  ExpectSameTake(replacement, corpus.LoadTake("t"));
  // Replacing compacts the file: the old take's space is not carried along.
  EXPECT_LT(fs::file_size(path), size_before * 11 / 10);
}

TEST(Corpus, RemoveTakeAndReplaceTiersAndAudio) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("a"), MakeFullTake("b")});
  LabelTier words;
  words.name = "mots";
  words.kind = LabelTier::Kind::kInterval;
  words.start_s = 0;
  words.end_s = 1;
  words.labels = {{0.0, 0.5, "bonjour"}, {0.5, 1.0, "ça"}};
  Audio mono;
  mono.rate_hz = 8000;
  mono.channels = 1;
  mono.samples = {0.0f, 0.5f, -0.5f, 0.25f};
  {
    CorpusTransaction tx(path);
    tx.RemoveTake("a");
    EXPECT_THROW(tx.RemoveTake("a"), InvalidInput);
    tx.WriteTiers("b", {words});
    tx.WriteAudio("b", mono, "new.wav");
    EXPECT_EQ(tx.TakeNames(), (std::vector<std::string>{"b"}));
    tx.Commit();
  }
  Corpus corpus = Corpus::Open(path);
  EXPECT_FALSE(corpus.HasTake("a"));
  Take b = corpus.LoadTake("b");
  Take expected = MakeFullTake("b");
  expected.tiers = {words};
  expected.audio = mono;
  expected.audio_path = "new.wav";
  ExpectSameTake(expected, b);
  // Empty audio with no path removes the audio group.
  {
    CorpusTransaction tx(path);
    tx.WriteAudio("b", Audio(), "");
    tx.Commit();
  }
  EXPECT_FALSE(Corpus::Open(path).Summary("b").has_audio);
  EXPECT_EQ(Corpus::Open(path).LoadTake("b").audio_path, "");
}

TEST(Corpus, LoadTiersReadsTheTiersAloneAsWritten) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("a")});
  LabelTier keys{"keys", LabelTier::Kind::kPoint, 0.0, 2.0, {{0.25, 0.25, "13"}, {1.5, 1.5, "00"}}};
  LabelTier words{"mots", LabelTier::Kind::kInterval, 0.0, 1.0, {{0.0, 0.5, "bonjour"}, {0.5, 1.0, "ça"}}};
  {
    CorpusTransaction tx(path);
    tx.WriteTiers("a", {words, keys});
    tx.Commit();
  }
  const std::vector<LabelTier> tiers = Corpus::Open(path).LoadTiers("a");
  ASSERT_EQ(tiers.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const LabelTier& want = i == 0 ? words : keys;
    EXPECT_EQ(tiers[i].name, want.name);
    EXPECT_EQ(tiers[i].kind, want.kind);
    EXPECT_EQ(tiers[i].start_s, want.start_s);
    EXPECT_EQ(tiers[i].end_s, want.end_s);
    ASSERT_EQ(tiers[i].labels.size(), want.labels.size());
    for (size_t k = 0; k < want.labels.size(); ++k) {
      EXPECT_EQ(tiers[i].labels[k].start_s, want.labels[k].start_s);
      EXPECT_EQ(tiers[i].labels[k].end_s, want.labels[k].end_s);
      EXPECT_EQ(tiers[i].labels[k].text, want.labels[k].text);
    }
  }
  EXPECT_THROW(Corpus::Open(path).LoadTiers("nope"), InvalidInput);
}

// The autosave reads a take's tiers through its own transaction (one file,
// whatever the corpus holds): what was stored, then what it wrote itself.
TEST(Corpus, TransactionLoadTiersSeesStoredThenPendingTiers) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("a"), MakeFullTake("b")});
  LabelTier keys{"keys", LabelTier::Kind::kPoint, 0.0, 2.0, {{0.25, 0.25, "13"}, {1.5, 1.5, "00"}}};
  LabelTier words{"mots", LabelTier::Kind::kInterval, 0.0, 1.0, {{0.0, 0.5, "bonjour"}, {0.5, 1.0, "ça"}}};
  {
    CorpusTransaction tx(path);
    tx.WriteTiers("a", {keys});
    tx.Commit();
  }
  CorpusTransaction tx(path);
  std::vector<LabelTier> stored = tx.LoadTiers("a");
  ASSERT_EQ(stored.size(), 1u);
  EXPECT_EQ(stored[0].name, "keys");
  EXPECT_EQ(stored[0].kind, LabelTier::Kind::kPoint);
  ASSERT_EQ(stored[0].labels.size(), 2u);
  EXPECT_EQ(stored[0].labels[0].start_s, 0.25);
  EXPECT_EQ(stored[0].labels[1].text, "00");
  stored.push_back(words);
  tx.WriteTiers("a", stored);
  const std::vector<LabelTier> pending = tx.LoadTiers("a");
  ASSERT_EQ(pending.size(), 2u);
  EXPECT_EQ(pending[1].name, "mots");
  ASSERT_EQ(pending[1].labels.size(), 2u);
  EXPECT_EQ(pending[1].labels[1].text, "ça");
  EXPECT_EQ(pending[1].labels[1].end_s, 1.0);
  // The other take is untouched; a missing one is an error naming it.
  EXPECT_EQ(tx.LoadTiers("b").size(), Corpus::Open(path).LoadTiers("b").size());
  try {
    tx.LoadTiers("nope");
    ADD_FAILURE() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("'nope'"), std::string::npos) << e.what();
  }
  tx.Commit();
  EXPECT_EQ(Corpus::Open(path).LoadTiers("a").size(), 2u);
  EXPECT_THROW(tx.LoadTiers("a"), Error);  // a committed transaction cannot be used
}

TEST(Corpus, RepeatedTierEditsKeepTheFileSizeBounded) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take t = MakeFullTake("t", 2000, 10);
  WriteCorpus(path, {t});
  const auto size_before = fs::file_size(path);
  LabelTier tier = t.tiers[0];
  for (int i = 0; i < 30; ++i) {
    tier.labels[0].text = "edit " + std::to_string(i);
    CorpusTransaction tx(path);
    tx.WriteTiers("t", {tier});
    tx.Commit();
  }
  EXPECT_LT(fs::file_size(path), size_before + (1u << 20));
  Take back = Corpus::Open(path).LoadTake("t");
  ASSERT_EQ(back.tiers.size(), 1u);
  EXPECT_EQ(back.tiers[0].labels[0].text, "edit 29");
  testing::ExpectSameMarkers(t.markers, back.markers);
}

TEST(Corpus, WriterReplacedByMoveRemovesItsPartialTake) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  CorpusTransaction tx(path);
  Take first = MakeFullTake("first", 10, 2);
  Take second = MakeFullTake("second", 10, 2);
  CorpusTransaction::TakeWriter w = tx.BeginTake(first);
  w.AppendFrames(first.markers.data().data(), 5);
  w = tx.BeginTake(second);  // abandons "first"
  w.AppendFrames(second.markers.data().data(), 10);
  w.Finish();
  tx.Commit();
  Corpus corpus = Corpus::Open(path);
  EXPECT_FALSE(corpus.HasTake("first"));
  ExpectSameTake(second, corpus.LoadTake("second"));
}

TEST(Corpus, TakeWithoutMarkersAnalogOrAudio) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take empty;
  empty.name = "empty";
  empty.rate_hz = 120;
  empty.provenance.imported_utc = "2026-01-01T00:00:00Z";
  empty.provenance.csw_version = "x";
  WriteCorpus(path, {empty});
  Corpus corpus = Corpus::Open(path);
  ExpectSameTake(empty, corpus.LoadTake("empty"));
  TakeSummary s = corpus.Summary("empty");
  EXPECT_EQ(s.frames, 0);
  EXPECT_EQ(s.markers, 0);
  EXPECT_FALSE(s.has_audio);
  EXPECT_EQ(s.analog_channels, 0);
}

TEST(Corpus, ManyWarningsFitInTheProvenanceAttribute) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take t = MakeFullTake("t", 10, 2);
  t.provenance.warnings.clear();
  for (int i = 0; i < 6000; ++i) t.provenance.warnings.push_back("warning number " + std::to_string(i));
  WriteCorpus(path, {t});
  EXPECT_EQ(Corpus::Open(path).LoadTake("t").provenance.warnings, t.provenance.warnings);
}

TEST(Corpus, GapsAreCountedWhenTheAttributeIsAbsent) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take t = MakeFullTake("t", 9000, 6);
  WriteCorpus(path, {t});
  // As if another tool (h5py, MATLAB) had written the take.
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  hid_t d = H5Dopen2(f, "/takes/t/markers", H5P_DEFAULT);
  ASSERT_GE(H5Adelete(d, "gaps"), 0);
  H5Dclose(d);
  hid_t g = H5Gopen2(f, "/takes/t", H5P_DEFAULT);  // and the index's cached copy
  ASSERT_GE(H5Adelete(g, "gap_count"), 0);
  H5Gclose(g);
  H5Fclose(f);
  EXPECT_EQ(Corpus::Open(path).Summary("t").gaps, TotalGaps(t.markers));
}

TEST(Corpus, InvalidTakeNamesAndInputsAreRejected) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  CorpusTransaction tx(path);
  Take t = MakeFullTake("a/b", 10, 2);
  EXPECT_THROW(tx.WriteTake(t), InvalidInput);
  t.name = "";
  EXPECT_THROW(tx.WriteTake(t), InvalidInput);
  t.name = "ok";
  t.marker_names.pop_back();
  EXPECT_THROW(tx.WriteTake(t), InvalidInput);
  t = MakeFullTake("ok", 10, 2);
  t.analog.data.pop_back();
  EXPECT_THROW(tx.WriteTake(t), InvalidInput);
  EXPECT_FALSE(tx.HasTake("ok"));
}

TEST(Corpus, CancelledTransactionLeavesTheCorpusUnchangedAndNoTempFile) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take a = MakeFullTake("a");
  WriteCorpus(path, {a});
  const std::string temp = CorpusTransaction::TempPath(path);
  const std::string folder = CorpusTransaction::FolderPath(path);
  auto files = [&] {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(folder)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
  };
  const std::vector<std::string> files_before = files();
  Progress progress;
  try {
    CorpusTransaction tx(path);
    tx.RemoveTake("a");
    Take b = MakeFullTake("b", 2000, 8);
    Take header = b;
    header.markers = MarkerArray();
    CorpusTransaction::TakeWriter w = tx.BeginTake(header);
    w.AppendFrames(b.markers.data().data(), 1000);
    EXPECT_GT(files().size(), files_before.size());  // the new take's files
    progress.Cancel();
    progress.Update("import", 0.5);  // throws Cancelled
    FAIL() << "Update did not throw";
  } catch (const Cancelled&) {
  }
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_FALSE(fs::exists(temp + ".compact"));
  EXPECT_EQ(files(), files_before);  // the cancelled take's files are gone
  Corpus corpus = Corpus::Open(path);
  ASSERT_EQ(corpus.Takes().size(), 1u);
  ExpectSameTake(a, corpus.LoadTake("a"));
  // A writer dropped without Finish removes its partial take; the rest commits.
  {
    CorpusTransaction tx(path);
    Take header = MakeFullTake("partial", 0, 2);
    { CorpusTransaction::TakeWriter w = tx.BeginTake(header); }
    EXPECT_FALSE(tx.HasTake("partial"));
    tx.WriteTake(MakeFullTake("c", 10, 2));
    tx.Commit();
  }
  EXPECT_EQ(Corpus::Open(path).Takes().size(), 2u);
  EXPECT_FALSE(Corpus::Open(path).HasTake("partial"));
}

TEST(Corpus, CommitWithAnOpenWriterThrows) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  CorpusTransaction tx(path);
  CorpusTransaction::TakeWriter w = tx.BeginTake(MakeFullTake("t", 0, 2));
  EXPECT_THROW(tx.Commit(), Error);
  w.Finish();
  tx.Commit();
  EXPECT_THROW(tx.WriteTake(MakeFullTake("u", 1, 1)), Error);
  EXPECT_TRUE(Corpus::Open(path).HasTake("t"));
}

TEST(Corpus, SecondConcurrentTransactionIsRefused) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  CorpusTransaction first(path);
  std::string message = ErrorOf([&] { CorpusTransaction second(path); });
  EXPECT_NE(message.find("(pid " + std::to_string(::getpid()) + ") since "), std::string::npos) << message;
  EXPECT_NE(message.find("is writing this corpus"), std::string::npos) << message;
  EXPECT_NE(message.find(path), std::string::npos) << message;
}

// The refused transaction must not touch the first one's files (its new take
// files, its temporary index): the first one still commits everything.
TEST(Corpus, RefusedTransactionLeavesTheWritersFilesAlone) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("a", 20, 2)});
  CorpusTransaction first(path);
  Take b = MakeFullTake("b", 30, 3);
  first.WriteTake(b);
  std::ofstream(CorpusTransaction::TempPath(path)) << "stand-in for the writer's temporary index";
  EXPECT_THROW(CorpusTransaction second(path), IoError);
  EXPECT_TRUE(fs::exists(CorpusTransaction::TempPath(path)));
  first.Commit();
  Corpus corpus = Corpus::Open(path);
  ASSERT_EQ(corpus.Takes().size(), 2u);
  ExpectSameTake(b, corpus.LoadTake("b"));
}

TEST(Corpus, ReadersAndAWriterInDifferentThreads) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  const std::string other = (dir / "other.h5").string();
  Take t = MakeFullTake("t", 3000, 8);
  WriteCorpus(path, {t});
  Corpus corpus = Corpus::Open(path);
  std::atomic<int> mismatches{0};
  auto reader = [&](int64_t first) {
    for (int i = 0; i < 20; ++i) {
      MarkerArray w = corpus.LoadMarkers("t", first, 500);
      if (std::memcmp(w.data().data(), t.markers.data().data() + first * 24, w.data().size() * sizeof(float)) != 0) {
        ++mismatches;
      }
    }
  };
  std::thread r1(reader, 0);
  std::thread r2(reader, 1700);
  std::thread writer([&] {
    for (int i = 0; i < 5; ++i) {
      CorpusTransaction tx(other);
      tx.WriteTake(MakeFullTake("w" + std::to_string(i), 500, 8));
      tx.Commit();
    }
  });
  r1.join();
  r2.join();
  writer.join();
  EXPECT_EQ(mismatches.load(), 0);
  EXPECT_EQ(Corpus::Open(other).Takes().size(), 5u);
}

TEST(Corpus, NonHdf5FileGivesOneClearError) {
  TempDir dir;
  const std::string path = (dir / "notes.h5").string();
  std::ofstream(path) << "this is not an HDF5 file\n";
  try {
    Corpus::Open(path);
    FAIL() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.where().file, path);
    EXPECT_NE(std::string(e.what()).find("not an HDF5 file"), std::string::npos) << e.what();
  }
  // A transaction refuses to replace it, and leaves it alone.
  EXPECT_THROW(CorpusTransaction tx(path), ParseError);
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "this is not an HDF5 file");
  EXPECT_FALSE(fs::exists(CorpusTransaction::TempPath(path)));
  // A missing file is an IoError naming it.
  std::string missing = ErrorOf([&] { Corpus::Open((dir / "missing.h5").string()); });
  EXPECT_NE(missing.find("missing.h5: no such file"), std::string::npos) << missing;
}

TEST(Corpus, TruncatedHdf5FileGivesOneClearError) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteCorpus(path, {MakeFullTake("t", 3000, 10)});
  fs::resize_file(path, fs::file_size(path) / 2);
  try {
    Corpus::Open(path);
    FAIL() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.where().file, path);
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

// Writes a minimal HDF5 file by hand: root attributes and one take whose
// markers dataset has the given shape and marker_names the given length.
void WriteHandMadeCorpus(const std::string& path, const char* format, int64_t version,
                         const std::vector<hsize_t>& marker_dims, hsize_t name_count) {
  hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  hid_t scalar = H5Screate(H5S_SCALAR);
  if (format != nullptr) {
    hid_t st = H5Tcopy(H5T_C_S1);
    H5Tset_size(st, H5T_VARIABLE);
    hid_t a = H5Acreate2(f, "format", st, scalar, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, st, &format);
    H5Aclose(a);
    H5Tclose(st);
  }
  hid_t a = H5Acreate2(f, "format_version", H5T_STD_I64LE, scalar, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(a, H5T_NATIVE_INT64, &version);
  H5Aclose(a);
  H5Sclose(scalar);
  hid_t takes = H5Gcreate2(f, "takes", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  hid_t g = H5Gcreate2(takes, "bad take", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  hid_t s = H5Screate_simple(static_cast<int>(marker_dims.size()), marker_dims.data(), nullptr);
  hid_t d = H5Dcreate2(g, "markers", H5T_IEEE_F32LE, s, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dclose(d);
  H5Sclose(s);
  hid_t ns = H5Screate_simple(1, &name_count, nullptr);
  hid_t st = H5Tcopy(H5T_C_S1);
  H5Tset_size(st, 8);
  d = H5Dcreate2(g, "marker_names", st, ns, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dclose(d);
  H5Tclose(st);
  H5Sclose(ns);
  H5Gclose(g);
  H5Gclose(takes);
  H5Fclose(f);
}

// Rewrites the markers of take `take` with HDF5's own filter pipeline and the
// given chunk shape and filters, as h5py or MATLAB would write them.
void RewriteMarkersWithHdf5(const std::string& path, const std::string& take, const MarkerArray& markers,
                            const std::vector<hsize_t>& chunk, bool filters) {
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  hid_t g = H5Gopen2(f, ("/takes/" + take).c_str(), H5P_DEFAULT);
  ASSERT_GE(H5Ldelete(g, "markers", H5P_DEFAULT), 0);
  hsize_t dims[3] = {static_cast<hsize_t>(markers.frames()), static_cast<hsize_t>(markers.markers()), 3};
  hid_t s = H5Screate_simple(3, dims, nullptr);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dcpl, 3, chunk.data());
  if (filters) {
    H5Pset_shuffle(dcpl);
    H5Pset_deflate(dcpl, 6);
  }
  hid_t d = H5Dcreate2(g, "markers", H5T_IEEE_F32LE, s, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  ASSERT_GE(d, 0);
  EXPECT_GE(H5Dwrite(d, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, markers.data().data()), 0);
  H5Dclose(d);
  H5Pclose(dcpl);
  H5Sclose(s);
  H5Gclose(g);
  H5Fclose(f);
}

TEST(Corpus, MarkersWrittenByHdf5ItselfReadBack) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  Take t = MakeFullTake("t", 1000, 6);
  WriteCorpus(path, {t});
  // Same layout family, HDF5's zlib at level 6 and 100-frame chunks; then
  // per-marker chunks; then chunks without filters.
  const std::vector<std::pair<std::vector<hsize_t>, bool>> layouts = {
      {{100, 6, 3}, true}, {{50, 1, 3}, true}, {{128, 6, 3}, false}};
  for (const auto& [chunk, filters] : layouts) {
    RewriteMarkersWithHdf5(path, "t", t.markers, chunk, filters);
    Corpus corpus = Corpus::Open(path);
    ExpectSameMarkers(t.markers, corpus.LoadTake("t").markers);
    MarkerArray window = corpus.LoadMarkers("t", 333, 400);
    MarkerArray expected(400, 6);
    std::copy(t.markers.data().begin() + 333 * 18, t.markers.data().begin() + 733 * 18, expected.data().begin());
    ExpectSameMarkers(expected, window);
  }
}

TEST(Corpus, DamagedTakesAreNamedInTheError) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteHandMadeCorpus(path, "csw-corpus", 1, {10, 4}, 4);
  std::string e = ErrorOf([&] { Corpus::Open(path); });
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_NE(e.find("take 'bad take'"), std::string::npos) << e;
  EXPECT_NE(e.find("rank 2, expected 3"), std::string::npos) << e;

  WriteHandMadeCorpus(path, "csw-corpus", 1, {10, 4, 2}, 4);
  e = ErrorOf([&] { Corpus::Open(path); });
  EXPECT_NE(e.find("last dimension 2, expected 3"), std::string::npos) << e;

  WriteHandMadeCorpus(path, "csw-corpus", 1, {10, 4, 3}, 5);
  e = ErrorOf([&] { Corpus::Open(path); });
  EXPECT_NE(e.find("marker_names has 5 names but markers has 4 markers"), std::string::npos) << e;

  // A well-formed hand-made take opens; its fixed-length (empty) names read back.
  WriteHandMadeCorpus(path, "csw-corpus", 1, {10, 4, 3}, 4);
  Corpus ok = Corpus::Open(path);
  Take t = ok.LoadTake("bad take");
  EXPECT_EQ(t.marker_names, std::vector<std::string>(4, ""));
  EXPECT_EQ(t.frames(), 10);
}

TEST(Corpus, WrongFormatOrNewerVersionIsRefused) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  WriteHandMadeCorpus(path, nullptr, 1, {1, 1, 3}, 1);
  EXPECT_NE(ErrorOf([&] { Corpus::Open(path); }).find("not a csw corpus"), std::string::npos);
  WriteHandMadeCorpus(path, "something-else", 1, {1, 1, 3}, 1);
  EXPECT_NE(ErrorOf([&] { Corpus::Open(path); }).find("format is 'something-else'"), std::string::npos);
  WriteHandMadeCorpus(path, "csw-corpus", 3, {1, 1, 3}, 1);
  std::string e = ErrorOf([&] { Corpus::Open(path); });
  EXPECT_NE(e.find("format_version 3 is newer"), std::string::npos) << e;
  EXPECT_THROW(Corpus::Open(path), ParseError);
}

}  // namespace
}  // namespace csw

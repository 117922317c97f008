// Score sets of a take (io/corpus/corpus.h TakeScores; docs/corpus-format.md,
// "scores/"): round trip, replacing one set keeps the others, the take's other
// members and a replaced take, packing, damaged and bad sets.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <filesystem>
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

// rows × cols values that are not round in binary (exact float64 round trip).
ScoreMatrix Matrix(const std::string& name, int64_t rows, int64_t cols, double seed) {
  ScoreMatrix m;
  m.name = name;
  m.rows = rows;
  m.cols = cols;
  for (int64_t i = 0; i < rows * cols; ++i) m.values.push_back(std::sin(seed + 0.37 * static_cast<double>(i)) / 3.0);
  for (int64_t c = 0; c < cols; ++c) m.column_names.push_back("c" + std::to_string(c));
  return m;
}

TakeScores Set(const std::string& name, int64_t rows, double seed) {
  TakeScores s;
  s.name = name;
  s.rate_hz = 100.0;
  s.start_s = 0.01;
  s.source = "keys.h5";
  s.matrices = {Matrix("shape", rows, 9, seed), Matrix("placement", rows, 6, seed + 1)};
  return s;
}

void ExpectSame(const TakeScores& want, const std::optional<TakeScores>& got) {
  ASSERT_TRUE(got.has_value()) << want.name;
  EXPECT_EQ(got->name, want.name);
  EXPECT_EQ(got->rate_hz, want.rate_hz);
  EXPECT_EQ(got->start_s, want.start_s);
  EXPECT_EQ(got->source, want.source);
  ASSERT_EQ(got->matrices.size(), want.matrices.size());
  for (const ScoreMatrix& w : want.matrices) {  // read back in name order
    const auto it = std::find_if(got->matrices.begin(), got->matrices.end(),
                                 [&](const ScoreMatrix& g) { return g.name == w.name; });
    ASSERT_NE(it, got->matrices.end()) << w.name;
    EXPECT_EQ(it->rows, w.rows);
    EXPECT_EQ(it->cols, w.cols);
    EXPECT_EQ(it->values, w.values) << w.name;  // bit for bit
    EXPECT_EQ(it->column_names, w.column_names);
  }
}

TEST(CorpusScores, RoundTripReplaceKeepOthersAndPack) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  const Take a = MakeFullTake("a", 300, 3);
  {
    CorpusTransaction tx(path);
    tx.WriteTake(a);
    tx.WriteTake(MakeFullTake("b", 50, 2));
    tx.Commit();
  }
  EXPECT_EQ(Corpus::Open(path).ScoreNames("a"), std::vector<std::string>{});
  EXPECT_FALSE(Corpus::Open(path).LoadScores("a", "keys").has_value());
  const TakeScores keys = Set("keys", 300, 0.5), other = Set("other", 10, 2.0);
  {
    CorpusTransaction tx(path);
    tx.WriteScores("a", keys);
    tx.WriteScores("a", other);
    tx.Commit();
  }
  {
    const Corpus c = Corpus::Open(path);
    EXPECT_EQ(c.ScoreNames("a"), (std::vector<std::string>{"keys", "other"}));
    ExpectSame(keys, c.LoadScores("a", "keys"));
    ExpectSame(other, c.LoadScores("a", "other"));
    EXPECT_TRUE(c.ScoreNames("b").empty());
    ExpectSameTake(a, c.LoadTake("a"));  // the take itself is unchanged
  }
  // Replacing one set (in a later transaction, with tier edits) keeps the other.
  const TakeScores keys2 = Set("keys", 300, 7.0);
  {
    CorpusTransaction tx(path);
    tx.WriteScores("a", keys2);
    tx.WriteTiers("a", {});
    tx.Commit();
  }
  ExpectSame(keys2, Corpus::Open(path).LoadScores("a", "keys"));
  ExpectSame(other, Corpus::Open(path).LoadScores("a", "other"));
  // Packed: the scores travel; a transaction on the packed file splits them out again.
  const std::string packed = (dir / "packed.h5").string();
  Progress progress;
  PackCorpus(path, packed, progress);
  ExpectSame(keys2, Corpus::Open(packed).LoadScores("a", "keys"));
  {
    CorpusTransaction tx(packed);
    tx.RemoveTake("b");
    tx.Commit();
  }
  ExpectSame(keys2, Corpus::Open(packed).LoadScores("a", "keys"));
  ExpectSame(other, Corpus::Open(packed).LoadScores("a", "other"));
  // Replacing the take drops its scores.
  {
    CorpusTransaction tx(path);
    tx.WriteTake(a, IfTakeExists::kReplace);
    tx.Commit();
  }
  EXPECT_TRUE(Corpus::Open(path).ScoreNames("a").empty());
}

TEST(CorpusScores, BadSetsAreRefusedAndDamagedOnesNamed) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  {
    CorpusTransaction tx(path);
    tx.WriteTake(MakeFullTake("a", 20, 2));
    tx.Commit();
  }
  CorpusTransaction tx(path);
  TakeScores s = Set("keys", 20, 0.0);
  s.matrices[0].values.pop_back();
  try {
    tx.WriteScores("a", s);
    FAIL() << "short matrix accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("take 'a': score set 'keys': matrix 'shape': 179 values for 20 × 9"),
              std::string::npos)
        << e.what();
  }
  s = Set("a/b", 20, 0.0);
  EXPECT_THROW(tx.WriteScores("a", s), InvalidInput);
  s = Set("keys", 20, 0.0);
  s.rate_hz = 0;
  EXPECT_THROW(tx.WriteScores("a", s), InvalidInput);
  EXPECT_THROW(tx.WriteScores("nope", Set("keys", 20, 0.0)), InvalidInput);
  // A stored set of rank 1: ParseError naming the corpus and the object.
  s = Set("keys", 20, 0.0);
  s.matrices.resize(1);
  tx.WriteScores("a", s);
  tx.Commit();
  const std::string linked = (dir / "c.h5.d").string();
  std::string scores_file;
  for (const auto& f : fs::directory_iterator(linked))
    if (f.path().string().ends_with(".scores.h5")) scores_file = f.path().string();
  ASSERT_FALSE(scores_file.empty());
  {
    hid_t f = H5Fopen(scores_file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    ASSERT_GE(H5Ldelete(f, "/scores/keys/shape", H5P_DEFAULT), 0);
    hsize_t n = 4;
    hid_t space = H5Screate_simple(1, &n, nullptr);
    hid_t ds = H5Dcreate2(f, "/scores/keys/shape", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(ds, 0);
    H5Dclose(ds);
    H5Sclose(space);
    H5Fclose(f);
  }
  try {
    Corpus::Open(path).LoadScores("a", "keys");
    FAIL() << "damaged set read";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/takes/a/scores/keys/shape has rank 1, expected 2"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace csw

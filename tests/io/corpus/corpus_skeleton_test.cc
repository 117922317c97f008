// Skeleton captures in the corpus: the `orientations` member (frames x joints x
// 4 float32) with the skeleton as JSON in its `skeleton` attribute, written
// whole or streamed, kept by transactions, packing and upgrades, absent from
// (and empty when loading) takes without a skeleton, and damage reported.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <functional>
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
using testing::MakeSkeletonTake;
using testing::TempDir;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// The data file of the only take of a corpus (in its folder, not the tiers,
// audio or scores file).
std::string DataFileOf(const std::string& corpus) {
  std::string found;
  for (const auto& entry : fs::directory_iterator(CorpusTransaction::FolderPath(corpus))) {
    const std::string name = entry.path().filename().string();
    if (name.find(".tiers.") == std::string::npos && name.find(".audio.") == std::string::npos &&
        name.find(".scores.") == std::string::npos) {
      EXPECT_TRUE(found.empty()) << "two data files";
      found = entry.path().string();
    }
  }
  return found;
}

TEST(CorpusSkeleton, WholeTakeRoundTrip) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  const Take take = MakeSkeletonTake("signer01");
  {
    CorpusTransaction tx(path);
    tx.WriteTake(take);
    tx.WriteTake(MakeFullTake("plain"));
    tx.Commit();
  }
  // Stored as documented: [frames][joints][4] float32 with the JSON skeleton.
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t ds = H5Dopen2(f, "takes/signer01/orientations", H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  hid_t space = H5Dget_space(ds);
  hsize_t dims[3] = {0, 0, 0};
  ASSERT_EQ(H5Sget_simple_extent_ndims(space), 3);
  H5Sget_simple_extent_dims(space, dims, nullptr);
  EXPECT_EQ(dims[0], 120u);
  EXPECT_EQ(dims[1], 4u);
  EXPECT_EQ(dims[2], 4u);
  hid_t type = H5Dget_type(ds);
  EXPECT_EQ(H5Tget_class(type), H5T_FLOAT);
  EXPECT_EQ(H5Tget_size(type), 4u);
  EXPECT_GT(H5Aexists(ds, "skeleton"), 0);
  H5Tclose(type);
  H5Sclose(space);
  H5Dclose(ds);
  // A take without a skeleton has no orientations member and loads empty fields.
  EXPECT_EQ(H5Lexists(f, "takes/plain/orientations", H5P_DEFAULT), 0);
  H5Fclose(f);
  Corpus c = Corpus::Open(path);
  ExpectSameTake(take, c.LoadTake("signer01"));
  Take plain = c.LoadTake("plain");
  EXPECT_TRUE(plain.skeleton.empty());
  EXPECT_TRUE(plain.orientations.empty());
  ExpectSameTake(MakeFullTake("plain"), plain);
}

TEST(CorpusSkeleton, StreamingInUnevenChunksEqualsOneShot) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  const Take take = MakeSkeletonTake("s", 1000);
  {
    CorpusTransaction tx(path);
    Take header = take;
    header.markers = MarkerArray();
    header.orientations = OrientationArray();
    auto w = tx.BeginTake(header);
    const int64_t steps[] = {1, 255, 300, 2, 442};
    int64_t f = 0;
    for (int64_t n : steps) {
      w.AppendFrames(take.markers.at(f, 0), n);
      f += n;
    }
    // Orientations in other chunks than the markers.
    w.AppendOrientations(take.orientations.at(0, 0), 700);
    w.AppendOrientations(take.orientations.at(700, 0), 300);
    w.Finish();
    tx.Commit();
  }
  ExpectSameTake(take, Corpus::Open(path).LoadTake("s"));
}

TEST(CorpusSkeleton, KeptByLaterTransactionsPackAndUpgrade) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  const Take take = MakeSkeletonTake("signer");
  {
    CorpusTransaction tx(path);
    tx.WriteTake(take);
    tx.Commit();
  }
  {
    // A later transaction rewrites the index from its table (links kept).
    CorpusTransaction tx(path);
    tx.WriteTake(MakeFullTake("other"));
    tx.WriteTiers("signer", {});
    tx.Commit();
  }
  Take after = Corpus::Open(path).LoadTake("signer");
  Take expected = take;
  expected.tiers.clear();
  ExpectSameTake(expected, after);
  Progress progress;
  const std::string packed = (dir / "packed.h5").string();
  PackCorpus(path, packed, progress);
  ExpectSameTake(expected, Corpus::Open(packed).LoadTake("signer"));
  // A transaction on the packed file copies the take into new files (the upgrade).
  {
    CorpusTransaction tx(packed);
    tx.RemoveTake("other");
    tx.Commit();
  }
  ExpectSameTake(expected, Corpus::Open(packed).LoadTake("signer"));
}

TEST(CorpusSkeleton, MismatchesAreRefused) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  CorpusTransaction tx(path);
  Take wrong = MakeSkeletonTake("wrong");
  wrong.skeleton.pop_back();
  EXPECT_NE(ErrorOf([&] { tx.WriteTake(wrong); }).find("a skeleton of 3 joints for 4 markers"), std::string::npos);
  Take loose = MakeFullTake("loose");
  loose.orientations.Resize(120, 4);
  EXPECT_NE(ErrorOf([&] { tx.WriteTake(loose); }).find("orientations but no skeleton"), std::string::npos);
  Take parent = MakeSkeletonTake("parent");
  parent.skeleton[1].parent = 3;
  EXPECT_NE(ErrorOf([&] { tx.WriteTake(parent); }).find("parents must come first"), std::string::npos);
  // Fewer orientation frames than marker frames: Finish refuses and the take is dropped.
  {
    Take header = MakeSkeletonTake("short");
    const Take full = header;
    header.markers = MarkerArray();
    header.orientations = OrientationArray();
    auto w = tx.BeginTake(header);
    w.AppendFrames(full.markers.at(0, 0), 120);
    w.AppendOrientations(full.orientations.at(0, 0), 100);
    EXPECT_NE(ErrorOf([&] { w.Finish(); }).find("orientations for 100 frames but markers for 120 frames"),
              std::string::npos);
  }
  EXPECT_FALSE(tx.HasTake("short"));
  Take plain = MakeFullTake("plain");
  tx.WriteTake(plain);
  {
    Take header = plain;
    header.name = "plain2";
    auto w = tx.BeginTake(header);
    EXPECT_THROW(w.AppendOrientations(MakeSkeletonTake("x").orientations.data().data(), 1), InvalidInput);
  }
  tx.Commit();
  EXPECT_EQ(Corpus::Open(path).Takes().size(), 1u);
}

TEST(CorpusSkeleton, DamagedSkeletonIsNamedInTheError) {
  TempDir dir;
  const std::string path = (dir / "c.h5").string();
  {
    CorpusTransaction tx(path);
    tx.WriteTake(MakeSkeletonTake("signer"));
    tx.Commit();
  }
  const std::string data = DataFileOf(path);
  {
    hid_t f = H5Fopen(data.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    hid_t ds = H5Dopen2(f, "orientations", H5P_DEFAULT);
    H5Adelete(ds, "skeleton");
    hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    hid_t space = H5Screate(H5S_SCALAR);
    hid_t attr = H5Acreate2(ds, "skeleton", type, space, H5P_DEFAULT, H5P_DEFAULT);
    const char* bad = "[{\"name\": \"Hips\"}]";
    H5Awrite(attr, type, &bad);
    H5Aclose(attr);
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(ds);
    H5Fclose(f);
  }
  const std::string e = ErrorOf([&] { Corpus::Open(path).LoadTake("signer"); });
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_NE(e.find("/takes/signer/orientations"), std::string::npos) << e;
  EXPECT_NE(e.find("skeleton"), std::string::npos) << e;
}

}  // namespace
}  // namespace csw

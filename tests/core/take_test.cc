#include "core/take.h"

#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "core/progress.h"
#include "core/sha256.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

TEST(MarkerArray, CountsVisibleSamplesAndGaps) {
  MarkerArray m(10, 2);
  for (int f = 0; f < 10; ++f) {
    float* p = m.at(f, 0);
    p[0] = p[1] = p[2] = static_cast<float>(f);
  }
  // Marker 1 visible on frames 2-3 and 6 only: gaps 0-1, 4-5, 7-9.
  for (int f : {2, 3, 6}) {
    float* p = m.at(f, 1);
    p[0] = p[1] = p[2] = 1.0f;
  }
  EXPECT_EQ(m.CountVisible(), 13);
  EXPECT_EQ(CountGaps(m, 0), 0);
  EXPECT_EQ(CountGaps(m, 1), 3);
  m.SetMissing(5, 0);
  EXPECT_EQ(CountGaps(m, 0), 1);
  EXPECT_FALSE(m.Visible(5, 0));
}

TEST(Units, MillimetresPerUnit) {
  EXPECT_DOUBLE_EQ(MillimetresPerUnit("mm"), 1.0);
  EXPECT_DOUBLE_EQ(MillimetresPerUnit(" M "), 1000.0);
  EXPECT_DOUBLE_EQ(MillimetresPerUnit("cm"), 10.0);
  EXPECT_DOUBLE_EQ(MillimetresPerUnit("in"), 25.4);
  EXPECT_DOUBLE_EQ(MillimetresPerUnit("furlong"), 0.0);
}

TEST(Errors, MessageNamesFileAndOffset) {
  ParseError e({"take03.c3d", 1536, std::nullopt}, "parameter block 3 overruns the file");
  EXPECT_STREQ(e.what(), "take03.c3d: offset 1536: parameter block 3 overruns the file");
  ParseError l({"a.TextGrid", std::nullopt, 12}, "expected a number");
  EXPECT_STREQ(l.what(), "a.TextGrid: line 12: expected a number");
}

TEST(Progress, CancelThrowsAtNextUpdate) {
  double last = -1;
  Progress p([&](const std::string&, double f) { last = f; });
  p.Update("import", 0.5);
  EXPECT_DOUBLE_EQ(last, 0.5);
  p.Cancel();
  EXPECT_THROW(p.Update("import", 0.6), Cancelled);
  EXPECT_DOUBLE_EQ(last, 0.5);
}

TEST(Sha256, KnownAnswer) {
  testing::TempDir dir;
  auto path = dir / "abc.txt";
  std::ofstream(path) << "abc";
  // FIPS 180-2 test vector for "abc".
  EXPECT_EQ(Sha256OfFile(path.string()), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_THROW(Sha256OfFile((dir / "none").string()), IoError);
  // The same digest of the bytes in memory; the empty input's known digest.
  EXPECT_EQ(Sha256OfBytes("abc", 3), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256OfBytes(nullptr, 0), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

}  // namespace
}  // namespace csw

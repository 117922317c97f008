// Hostile input: truncations, byte flips and crafted headers must give a ParseError
// or a successful read, never a crash (run under ASan/UBSan with -DCSW_SANITIZE=ON).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "io/c3d/c3d.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

std::vector<char> SmallFile(const testing::TempDir& dir) {
  Take t;
  t.rate_hz = 100;
  t.marker_names = {"A", "B", "C"};
  t.markers.Resize(20, 3);
  for (size_t i = 0; i < t.markers.data().size(); ++i) t.markers.data()[i] = static_cast<float>(i);
  t.analog.rate_hz = 200;
  t.analog.names = {"X"};
  t.analog.samples = 40;
  t.analog.data.assign(40, 1.5f);
  t.events = {{"E", "Left", 0.05, ""}};
  const std::string path = (dir / "small.c3d").string();
  WriteC3d(path, t);
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Returns 0 when read, 1 for a ParseError; anything else fails the test.
int TryRead(const std::string& path, const std::vector<char>& bytes) {
  {
    // Unlink first: rewriting a truncated file makes ext4 flush it on close (slow).
    std::filesystem::remove(path);
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  try {
    Take t = ReadC3d(path);
    C3dReader r(path);
    int64_t n = 0;
    double s = 0;
    r.ValidPointStats(&n, &s);
    EXPECT_LE(n, r.info().frames * r.info().points);
    EXPECT_EQ(t.frames(), r.info().frames);
    return 0;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.where().file, path);
    return 1;
  }
}

TEST(C3dHostile, Truncations) {
  testing::TempDir dir;
  std::vector<char> good = SmallFile(dir);
  const std::string path = (dir / "t.c3d").string();
  int errors = 0, reads = 0;
  for (size_t n = 0; n <= good.size(); n += (n < 1200 ? 1 : 37)) {
    int r = TryRead(path, std::vector<char>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n)));
    (r ? errors : reads)++;
  }
  EXPECT_GT(errors, 0);
  EXPECT_GT(reads, 0);
  EXPECT_EQ(TryRead(path, good), 0);
}

TEST(C3dHostile, RandomByteFlips) {
  testing::TempDir dir;
  std::vector<char> good = SmallFile(dir);
  const std::string path = (dir / "f.c3d").string();
  std::mt19937 rng(12345);
  int errors = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    std::vector<char> bad = good;
    const int flips = 1 + static_cast<int>(rng() % 8);
    // Mostly the header and the parameter section, where the structure lives.
    for (int k = 0; k < flips; ++k) {
      size_t at = rng() % 4 ? rng() % std::min<size_t>(bad.size(), 1536) : rng() % bad.size();
      bad[at] = static_cast<char>(rng() & 0xFF);
    }
    errors += TryRead(path, bad);
  }
  EXPECT_GT(errors, 0);
}

TEST(C3dHostile, EveryHeaderAndParameterByteMutated) {
  testing::TempDir dir;
  std::vector<char> good = SmallFile(dir);
  const std::string path = (dir / "m.c3d").string();
  // The parameter section of SmallFile ends well before byte 1536 (data start block 4).
  const size_t end = std::min<size_t>(good.size(), 1536);
  int errors = 0, reads = 0;
  for (size_t at = 0; at < end; at += at < 512 ? 4 : 1) {
    for (unsigned char v : {0x00, 0x80, 0xFF}) {
      if (static_cast<unsigned char>(good[at]) == v) continue;
      std::vector<char> bad = good;
      bad[at] = static_cast<char>(v);
      (TryRead(path, bad) ? errors : reads)++;
    }
  }
  EXPECT_GT(errors, 0);
  EXPECT_GT(reads, errors);  // most single-byte damage is recoverable
}

TEST(C3dHostile, CraftedHeaders) {
  testing::TempDir dir;
  std::vector<char> good = SmallFile(dir);
  const std::string path = (dir / "c.c3d").string();
  auto with = [&](std::initializer_list<std::pair<size_t, unsigned char>> edits) {
    std::vector<char> b = good;
    for (auto [at, v] : edits) b[at] = static_cast<char>(v);
    return b;
  };
  EXPECT_EQ(TryRead(path, with({{1, 0x00}})), 1);                 // wrong key
  EXPECT_EQ(TryRead(path, with({{0, 0}})), 1);                    // parameter block 0
  EXPECT_EQ(TryRead(path, with({{0, 200}})), 1);                  // parameter block past the end
  EXPECT_EQ(TryRead(path, with({{16, 1}, {17, 0}})), 0);          // header data start bad, POINT:DATA_START rescues
  EXPECT_EQ(TryRead(path, with({{8, 0xFF}, {9, 0xFF}})), 0);      // last frame 65535: clamped to the file
  EXPECT_EQ(TryRead(path, with({{2, 0xFF}, {3, 0x7F}})), 0);      // 32767 points: no frame fits
  EXPECT_EQ(TryRead(path, with({{18, 0}, {19, 0}})), 1);          // analog words but 0 samples per frame
  EXPECT_EQ(TryRead(path, with({{300, 0xFF}, {301, 0x7F}})), 0);  // absurd event count: warning
  EXPECT_EQ(TryRead(path, with({{512 + 3, 99}})), 0);             // unknown processor: warning
  EXPECT_EQ(TryRead(path, std::vector<char>(512, 0)), 1);
}

}  // namespace
}  // namespace csw

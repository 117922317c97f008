// Conformance against c3d/REFERENCE.tsv (values from an independent, widely used
// C++ reader). Where that reader is demonstrably wrong, the row's fields are listed in
// kPeerDivergences and checked instead by an independent test below (continuity of the
// trajectories, a twin file, or the file size).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/build_paths.h"
#include "io/c3d/c3d.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

struct RefRow {
  std::string file;
  int64_t points, first_frame, frames;
  double rate;
  int64_t analog_channels, subframes, valid;
  double sum;
};

std::vector<RefRow> LoadReference() {
  std::vector<RefRow> rows;
  std::filesystem::path tsv = testing::SharedData("c3d/REFERENCE.tsv");
  if (tsv.empty()) tsv = std::filesystem::path(CSW_C3D_DEFAULT_SHARED_DATA) / "c3d/REFERENCE.tsv";
  if (!std::filesystem::exists(tsv)) return rows;
  std::ifstream in(tsv);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, '\t')) f.push_back(cell);
    if (f.size() < 10 || f[1] != "ok") continue;
    rows.push_back({f[0], std::stoll(f[2]), std::stoll(f[3]), std::stoll(f[4]), std::stod(f[5]), std::stoll(f[6]),
                    std::stoll(f[7]), std::stoll(f[8]), std::stod(f[9])});
  }
  return rows;
}

// Fields where the peer reader is wrong, and why; each is covered by a test below.
const std::map<std::string, std::set<std::string>>& PeerDivergences() {
  static const std::map<std::string, std::set<std::string>> m = {
      // Header: 476 analog words = 28 channels x 17 samples; the peer derives 16 samples
      // from ANALOG:RATE / POINT:RATE and misaligns every frame (EvartLayoutIsContinuous).
      {"c3d.org/sample_11/evart.c3d", {"subframes", "valid", "sum"}},
      // Empty parameter section: the peer reads nothing; the header describes 40 float
      // points x 701 frames that fill the file exactly (PhasespaceHeaderOnlyFileIsRead).
      {"c3d.org/sample_20/phasespace_sample.c3d", {"points", "frames", "rate", "subframes", "valid", "sum"}},
      // The peer ignores the 6 analog channels declared in the header and misaligns
      // frames; the points equal those of its twin dynamic.C3D (Type1EqualsDynamicTwin).
      {"c3d.org/sample_28/type1.C3D", {"analog_channels", "subframes", "valid", "sum"}},
      // No POINT group: the peer reports rate 0 and 1 sample per frame, while the header
      // (60 Hz, 160 words = 16 x 10) fills the file exactly (KistlerLayoutFillsTheFile).
      {"ezc3d/Kistler.c3d", {"rate", "subframes"}},
  };
  return m;
}

class C3dReference : public ::testing::TestWithParam<RefRow> {};

TEST_P(C3dReference, InfoAndValidPointStatsMatch) {
  const RefRow& r = GetParam();
  const std::string rel = "c3d/" + r.file;
  CSW_REQUIRE_SHARED_DATA(rel);
  C3dReader reader(testing::SharedData(rel).string());
  const C3dInfo& info = reader.info();
  int64_t valid = 0;
  double sum = 0;
  reader.ValidPointStats(&valid, &sum);
  std::set<std::string> skip;
  if (auto it = PeerDivergences().find(r.file); it != PeerDivergences().end()) skip = it->second;
  // With no analog channel the samples-per-frame count has no meaning.
  if (r.analog_channels == 0 && info.analog_channels == 0) skip.insert("subframes");
  if (!skip.count("points")) {
    EXPECT_EQ(info.points, r.points);
  }
  EXPECT_EQ(info.first_frame, r.first_frame);
  if (!skip.count("frames")) {
    EXPECT_EQ(info.frames, r.frames);
  }
  if (!skip.count("rate")) {
    EXPECT_NEAR(info.point_rate_hz, r.rate, 1e-4 * std::max(1.0, r.rate));
  }
  if (!skip.count("analog_channels")) {
    EXPECT_EQ(info.analog_channels, r.analog_channels);
  }
  if (!skip.count("subframes")) {
    EXPECT_EQ(info.analog_subframes_per_frame, r.subframes);
  }
  if (!skip.count("valid")) {
    EXPECT_EQ(valid, r.valid);
  }
  if (!skip.count("sum")) {
    EXPECT_NEAR(sum, r.sum, 1e-6 * std::max(1.0, std::fabs(r.sum)));
  }
}

std::string RowName(const ::testing::TestParamInfo<RefRow>& info) {
  std::string n = info.param.file;
  for (char& c : n) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return n;
}

TEST(C3dReferenceTable, IsReadable) {
  CSW_REQUIRE_SHARED_DATA("c3d/REFERENCE.tsv");
  std::vector<RefRow> rows = LoadReference();
  EXPECT_GE(rows.size(), 60u);
  for (const auto& entry : PeerDivergences()) {
    const std::string& file = entry.first;
    EXPECT_TRUE(std::any_of(rows.begin(), rows.end(), [&](const RefRow& r) { return r.file == file; })) << file;
  }
}

INSTANTIATE_TEST_SUITE_P(C3dReferenceTsv, C3dReference, ::testing::ValuesIn(LoadReference()), RowName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(C3dReference);

// 95th percentile of |second difference| (mm) over valid consecutive triples: small
// for real trajectories, large when frames are misaligned.
double P95Acceleration(const Take& take) {
  std::vector<double> acc;
  for (int64_t m = 0; m < take.markers.markers(); ++m) {
    for (int64_t f = 2; f < take.frames(); ++f) {
      if (!take.markers.Visible(f - 2, m) || !take.markers.Visible(f - 1, m) || !take.markers.Visible(f, m)) continue;
      double s = 0;
      for (int k = 0; k < 3; ++k) {
        s += std::fabs(take.markers.at(f, m)[k] - 2.0 * take.markers.at(f - 1, m)[k] + take.markers.at(f - 2, m)[k]);
      }
      acc.push_back(s);
    }
  }
  if (acc.empty()) return -1;
  std::sort(acc.begin(), acc.end());
  return acc[acc.size() * 95 / 100];
}

TEST(C3dPeerDivergence, EvartLayoutIsContinuous) {
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_11/evart.c3d");
  Take take = ReadC3d(testing::SharedData("c3d/c3d.org/sample_11/evart.c3d").string());
  EXPECT_EQ(take.analog.channels(), 28);
  EXPECT_EQ(take.analog.samples, take.frames() * 17);
  // Walking at 60 Hz: accelerations of a few mm per frame^2 (misaligned frames give metres).
  double p95 = P95Acceleration(take);
  EXPECT_GT(p95, 0.0);
  EXPECT_LT(p95, 20.0);
}

TEST(C3dPeerDivergence, PhasespaceHeaderOnlyFileIsRead) {
  const std::string rel = "c3d/c3d.org/sample_20/phasespace_sample.c3d";
  CSW_REQUIRE_SHARED_DATA(rel);
  C3dReader reader(testing::SharedData(rel).string());
  EXPECT_EQ(reader.info().points, 40);
  EXPECT_EQ(reader.info().frames, 701);
  EXPECT_DOUBLE_EQ(reader.info().point_rate_hz, 30.0);
  EXPECT_FALSE(reader.info().warnings.empty());
  // 40 float points x 16 bytes x 701 frames exactly fill the file after block 3.
  EXPECT_EQ(2 * 512 + 40 * 16 * 701, static_cast<int64_t>(std::filesystem::file_size(testing::SharedData(rel))));
  Take take = ReadC3d(testing::SharedData(rel).string());
  // 30 Hz capture: tens of mm per frame^2 at most (misaligned frames give metres).
  double p95 = P95Acceleration(take);
  EXPECT_GT(p95, 0.0);
  EXPECT_LT(p95, 100.0);
}

TEST(C3dPeerDivergence, Type1EqualsDynamicTwin) {
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_28/type1.C3D");
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_28/dynamic.C3D");
  Take t1 = ReadC3d(testing::SharedData("c3d/c3d.org/sample_28/type1.C3D").string());
  Take dy = ReadC3d(testing::SharedData("c3d/c3d.org/sample_28/dynamic.C3D").string());
  ASSERT_EQ(t1.frames(), dy.frames());
  ASSERT_EQ(t1.markers.markers(), 28);
  ASSERT_EQ(t1.analog.channels(), 6);
  // type1.C3D is dynamic.C3D with the BTS format errors corrected (sample readme): each
  // of its 28 trajectories is one of dynamic's, relabelled and reordered; dynamic's
  // other 6 points are never valid.
  auto same = [&](int64_t m, int64_t d) {
    for (int64_t f = 0; f < t1.frames(); ++f) {
      for (int k = 0; k < 3; ++k) {
        float a = t1.markers.at(f, m)[k], b = dy.markers.at(f, d)[k];
        if (!((std::isnan(a) && std::isnan(b)) || a == b)) return false;
      }
    }
    return true;
  };
  std::vector<bool> used(static_cast<size_t>(dy.markers.markers()), false);
  for (int64_t m = 0; m < 28; ++m) {
    int64_t match = -1;
    for (int64_t d = 0; d < dy.markers.markers() && match < 0; ++d) {
      if (!used[d] && same(m, d)) match = d;
    }
    ASSERT_GE(match, 0) << "type1 marker " << t1.marker_names[m] << " has no twin";
    used[match] = true;
  }
  for (int64_t d = 0; d < dy.markers.markers(); ++d) {
    if (used[d]) continue;
    for (int64_t f = 0; f < dy.frames(); ++f) EXPECT_FALSE(dy.markers.Visible(f, d));
  }
  EXPECT_EQ(t1.analog.data, dy.analog.data);
}

TEST(C3dPeerDivergence, KistlerLayoutFillsTheFile) {
  const std::string rel = "c3d/ezc3d/Kistler.c3d";
  CSW_REQUIRE_SHARED_DATA(rel);
  C3dReader reader(testing::SharedData(rel).string());
  const C3dInfo& info = reader.info();
  EXPECT_DOUBLE_EQ(info.point_rate_hz, 60.0);
  EXPECT_EQ(info.analog_channels, 16);
  EXPECT_EQ(info.analog_subframes_per_frame, 10);
  EXPECT_DOUBLE_EQ(info.analog_rate_hz, 600.0);  // = ANALOG:RATE
  // data from block 4: frames x 16 channels x 10 samples x int16 end exactly at EOF.
  EXPECT_EQ(3 * 512 + info.frames * 16 * 10 * 2,
            static_cast<int64_t>(std::filesystem::file_size(testing::SharedData(rel))));
}

}  // namespace
}  // namespace csw

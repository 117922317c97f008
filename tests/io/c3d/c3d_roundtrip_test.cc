// read -> write -> read round trips, with takes built in memory and with real files.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "io/c3d/c3d.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

bool SameFloats(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!((std::isnan(a[i]) && std::isnan(b[i])) || a[i] == b[i])) return false;
  }
  return true;
}

// A take with known values: marker m in frame f at (f + m/8, -m, 0.25 f) mm, every
// 7th sample missing, `channels` analog channels at `subframes` x the frame rate.
Take MakeTake(int64_t frames, int64_t markers, int64_t channels, int64_t subframes) {
  Take t;
  t.name = "synthetic";
  t.rate_hz = 120.0;
  t.first_frame = 1;
  for (int64_t m = 0; m < markers; ++m) t.marker_names.push_back("M" + std::to_string(m));
  t.markers.Resize(frames, markers);
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < markers; ++m) {
      if ((f * markers + m) % 7 == 3) continue;  // stays NaN
      float* p = t.markers.at(f, m);
      p[0] = static_cast<float>(f) + static_cast<float>(m) / 8.0f;
      p[1] = -static_cast<float>(m);
      p[2] = 0.25f * static_cast<float>(f);
    }
  }
  if (channels > 0) {
    t.analog.rate_hz = t.rate_hz * static_cast<double>(subframes);
    for (int64_t c = 0; c < channels; ++c) {
      t.analog.names.push_back("EMG" + std::to_string(c));
      t.analog.units.push_back(c % 2 ? "V" : "N");
    }
    t.analog.samples = frames * subframes;
    t.analog.data.resize(static_cast<size_t>(t.analog.samples * channels));
    for (size_t i = 0; i < t.analog.data.size(); ++i) t.analog.data[i] = std::sin(0.01f * static_cast<float>(i));
  }
  return t;
}

void ExpectSame(const Take& a, const Take& b) {
  EXPECT_EQ(a.rate_hz, b.rate_hz);
  EXPECT_EQ(a.first_frame, b.first_frame);
  EXPECT_EQ(a.marker_names, b.marker_names);
  ASSERT_EQ(a.frames(), b.frames());
  ASSERT_EQ(a.markers.markers(), b.markers.markers());
  EXPECT_TRUE(SameFloats(a.markers.data(), b.markers.data()));
  EXPECT_EQ(a.analog.names, b.analog.names);
  EXPECT_EQ(a.analog.channels() > 0 ? a.analog.units : std::vector<std::string>(),
            b.analog.channels() > 0 ? b.analog.units : std::vector<std::string>());
  EXPECT_EQ(a.analog.samples, b.analog.samples);
  EXPECT_EQ(a.analog.descriptions, b.analog.descriptions);
  if (a.analog.channels() > 0) {
    EXPECT_EQ(a.analog.rate_hz, b.analog.rate_hz);
  }
  EXPECT_TRUE(SameFloats(a.analog.data, b.analog.data));
  ASSERT_EQ(a.events.size(), b.events.size());
  for (size_t i = 0; i < a.events.size(); ++i) {
    EXPECT_EQ(a.events[i].label, b.events[i].label);
    EXPECT_EQ(a.events[i].context, b.events[i].context);
    EXPECT_EQ(a.events[i].description, b.events[i].description);
    EXPECT_EQ(a.events[i].time_s, b.events[i].time_s);
  }
}

TEST(C3dRoundTrip, PointsAnalogEventsNaNs) {
  testing::TempDir dir;
  Take t = MakeTake(50, 12, 3, 4);
  t.analog.descriptions = {"left tibialis", "", "force plate 1 Fz"};
  t.events = {{"Foot Strike", "Left", 0.125, "heel contact"}, {"Foot Off", "Right", 75.5, ""}, {"RIC", "", 2.75, ""}};
  const std::string path = (dir / "rt.c3d").string();
  WriteC3d(path, t);
  C3dReader r(path);
  EXPECT_EQ(r.info().processor, "intel");
  EXPECT_EQ(r.info().storage, "float");
  EXPECT_EQ(r.info().units, "mm");
  EXPECT_TRUE(r.info().warnings.empty()) << r.info().warnings[0];
  int64_t valid = 0;
  double sum = 0;
  r.ValidPointStats(&valid, &sum);
  EXPECT_EQ(valid, t.markers.CountVisible());
  Take back = ReadC3d(path);
  ExpectSame(t, back);
  EXPECT_TRUE(back.provenance.warnings.empty());
  ASSERT_EQ(back.provenance.sources.size(), 1u);
  EXPECT_EQ(back.provenance.sources[0].format, "c3d");
  EXPECT_EQ(back.provenance.sources[0].sha256.size(), 64u);
}

TEST(C3dRoundTrip, Int16StorageIsWithinHalfAScaleStep) {
  testing::TempDir dir;
  Take t = MakeTake(300, 9, 3, 4);
  const std::string path = (dir / "int16.c3d").string();
  C3dWriteOptions options;
  options.storage = C3dWriteOptions::Storage::kInt16;
  options.point_scale_mm = 0.05;
  WriteC3d(path, t, options);
  C3dReader reader(path);
  EXPECT_EQ(reader.info().storage, "int16");
  EXPECT_NEAR(reader.info().point_scale, 0.05, 1e-7);
  Take back = ReadC3d(path);
  ASSERT_EQ(back.frames(), t.frames());
  for (size_t i = 0; i < t.markers.data().size(); ++i) {
    float a = t.markers.data()[i], b = back.markers.data()[i];
    ASSERT_EQ(std::isnan(a), std::isnan(b)) << i;
    if (!std::isnan(a)) {
      ASSERT_NEAR(a, b, 0.025 + 1e-4) << i;
    }
  }
  ASSERT_EQ(back.analog.data.size(), t.analog.data.size());
  for (size_t i = 0; i < t.analog.data.size(); ++i)
    ASSERT_NEAR(back.analog.data[i], t.analog.data[i], 1.0 / 32000) << i;
  // Half the bytes of float storage (for the data part).
  const std::string fpath = (dir / "float.c3d").string();
  WriteC3d(fpath, t);
  EXPECT_LT(std::filesystem::file_size(path), std::filesystem::file_size(fpath) * 6 / 10);
  // Coordinates beyond 32767 steps are refused, not wrapped.
  t.markers.at(0, 0)[0] = 5000.0f;
  EXPECT_THROW(WriteC3d(path, t, options), InvalidInput);
}

TEST(C3dRoundTrip, MoreThan255LabelsGoToLabels2) {
  testing::TempDir dir;
  Take t = MakeTake(5, 600, 0, 0);
  const std::string path = (dir / "many.c3d").string();
  WriteC3d(path, t);
  C3dReader r(path);
  ASSERT_EQ(r.info().labels.size(), 600u);
  EXPECT_EQ(r.info().labels[255], "M255");
  EXPECT_EQ(r.info().labels[599], "M599");
  ExpectSame(t, ReadC3d(path));
}

TEST(C3dRoundTrip, MoreThan65535FramesAndLateFirstFrame) {
  testing::TempDir dir;
  Take t = MakeTake(70000, 2, 1, 2);
  t.first_frame = 100;
  const std::string path = (dir / "long.c3d").string();
  WriteC3d(path, t);
  C3dReader r(path);
  EXPECT_EQ(r.info().frames, 70000);
  EXPECT_EQ(r.info().first_frame, 100);
  Take back = ReadC3d(path);
  ExpectSame(t, back);
  // The last frame is where it should be.
  EXPECT_EQ(back.markers.at(69999, 1)[2], 0.25f * 69999.0f);
}

TEST(C3dRoundTrip, FirstFrameBeyond16Bits) {
  testing::TempDir dir;
  Take t = MakeTake(10, 1, 0, 0);
  t.first_frame = 80000;
  const std::string path = (dir / "late.c3d").string();
  WriteC3d(path, t);
  EXPECT_EQ(C3dReader(path).info().first_frame, 80000);
  ExpectSame(t, ReadC3d(path));
}

TEST(C3dRoundTrip, ReadFramesInPiecesEqualsWholeRead) {
  testing::TempDir dir;
  Take t = MakeTake(300, 5, 2, 3);
  const std::string path = (dir / "pieces.c3d").string();
  WriteC3d(path, t);
  C3dReader r(path);
  std::vector<float> pts(static_cast<size_t>(5 * 3 * 100)), an(static_cast<size_t>(2 * 3 * 100));
  r.ReadFrames(150, 100, pts.data(), nullptr, an.data());
  for (int64_t f = 0; f < 100; ++f) {
    for (int64_t m = 0; m < 5; ++m) {
      for (int k = 0; k < 3; ++k) {
        float want = t.markers.at(150 + f, m)[k], got = pts[static_cast<size_t>((f * 5 + m) * 3 + k)];
        ASSERT_TRUE((std::isnan(want) && std::isnan(got)) || want == got);
      }
    }
  }
  for (size_t i = 0; i < an.size(); ++i) EXPECT_EQ(an[i], t.analog.data[150 * 6 + i]);
  EXPECT_THROW(r.ReadFrames(250, 51, pts.data(), nullptr, nullptr), InvalidInput);
}

TEST(C3dRoundTrip, EmptyTake) {
  testing::TempDir dir;
  Take t = MakeTake(0, 3, 0, 0);
  const std::string path = (dir / "empty.c3d").string();
  WriteC3d(path, t);
  ExpectSame(t, ReadC3d(path));
}

TEST(C3dRoundTrip, WriterRejectsWhatC3dCannotHold) {
  testing::TempDir dir;
  Take t = MakeTake(10, 2, 1, 2);
  t.analog.data.pop_back();
  EXPECT_THROW(WriteC3d((dir / "x.c3d").string(), t), InvalidInput);
  Take u = MakeTake(10, 2, 0, 0);
  u.marker_names.pop_back();
  EXPECT_THROW(WriteC3d((dir / "y.c3d").string(), u), InvalidInput);
  Take v = MakeTake(10, 2, 0, 0);
  EXPECT_THROW(WriteC3d((dir / "no-such-dir" / "z.c3d").string(), v), IoError);
}

// Real files: read -> write -> read keeps points, analog (already scaled), labels, events.
TEST(C3dRoundTrip, RealFiles) {
  for (const char* rel : {"c3d/ezc3d/Vicon.c3d", "c3d/c3d.org/sample_01/Eb015vi.c3d",
                          "c3d/c3d.org/sample_03/gait-pig-nz.c3d", "c3d/c3d.org/sample_02/sgi_int.c3d"}) {
    CSW_REQUIRE_SHARED_DATA(rel);
    SCOPED_TRACE(rel);
    testing::TempDir dir;
    Take a = ReadC3d(testing::SharedData(rel).string());
    const std::string path = (dir / "copy.c3d").string();
    WriteC3d(path, a);
    Take b = ReadC3d(path);
    ExpectSame(a, b);
    EXPECT_GT(a.events.size() + a.analog.data.size(), 0u);
  }
}

}  // namespace
}  // namespace csw

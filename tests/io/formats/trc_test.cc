// TRC reader/writer: BTK sample files (values read by eye in the files and in
// BTK's own TRCFileReaderTest), round trips and hostile inputs.
#include "io/formats/trc.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "core/error.h"
#include "tests/io/formats/test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

using testing::ExpectParseError;
using testing::SharedData;
using testing::TempDir;
using testing::WriteBytes;

const char kBtk[] = "trc/btk/";

Take ReadBtk(const std::string& name) { return ReadTrc(SharedData(kBtk + name).string()); }

bool HasWarning(const Take& take, const std::string& needle) {
  for (const std::string& w : take.provenance.warnings) {
    if (w.find(needle) != std::string::npos) return true;
  }
  return false;
}

void ExpectMarker(const Take& take, int64_t frame, int64_t marker, double x, double y, double z) {
  ASSERT_TRUE(take.markers.Visible(frame, marker)) << "frame " << frame << " marker " << marker;
  const float* p = take.markers.at(frame, marker);
  EXPECT_NEAR(p[0], x, 1e-4);
  EXPECT_NEAR(p[1], y, 1e-4);
  EXPECT_NEAR(p[2], z, 1e-4);
}

// Same shape, names, rate and bit-identical samples (NaN in the same places).
void ExpectSameTake(const Take& a, const Take& b) {
  EXPECT_EQ(a.rate_hz, b.rate_hz);
  EXPECT_EQ(a.first_frame, b.first_frame);
  EXPECT_EQ(a.marker_names, b.marker_names);
  ASSERT_EQ(a.markers.frames(), b.markers.frames());
  ASSERT_EQ(a.markers.markers(), b.markers.markers());
  const auto& da = a.markers.data();
  const auto& db = b.markers.data();
  for (size_t i = 0; i < da.size(); ++i) {
    if (std::isnan(da[i])) {
      ASSERT_TRUE(std::isnan(db[i])) << "sample " << i;
    } else {
      ASSERT_EQ(da[i], db[i]) << "sample " << i;
    }
  }
}

TEST(TrcRead, MotekTPose) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/MOTEK/T.trc");
  Take take = ReadBtk("MOTEK/T.trc");
  EXPECT_EQ(take.name, "T");
  EXPECT_EQ(take.rate_hz, 30.0);
  EXPECT_EQ(take.first_frame, 1);
  EXPECT_EQ(take.frames(), 89);
  EXPECT_EQ(take.markers.markers(), 41);
  EXPECT_EQ(take.source_units, "mm");
  EXPECT_EQ(take.marker_names[0], "RFHD");
  EXPECT_EQ(take.marker_names[1], "LBHD");
  // Line 10 (frame 4): RFHD -334.72..., LBHD -171.03949 (BTK test: point 1, row 3).
  EXPECT_NEAR(take.markers.at(3, 1)[0], -171.03949, 1e-4);
  EXPECT_NEAR(take.markers.at(3, 0)[1], 1639.13681, 1e-4);
  ASSERT_EQ(take.provenance.sources.size(), 1u);
  EXPECT_EQ(take.provenance.sources[0].format, "trc");
  EXPECT_EQ(take.provenance.sources[0].sha256.size(), 64u);
}

TEST(TrcRead, MotekBallet) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/MOTEK/ballet_reduced.trc");
  Take take = ReadBtk("MOTEK/ballet_reduced.trc");
  EXPECT_EQ(take.frames(), 100);
  EXPECT_EQ(take.markers.markers(), 41);
  // BTK test: point 40, row 82, z = -112.24601.
  EXPECT_NEAR(take.markers.at(82, 40)[2], -112.24601, 1e-4);
}

TEST(TrcRead, KneeLabelWithSpacesAndOcclusion) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/Knee.trc");
  Take take = ReadBtk("Knee.trc");
  EXPECT_EQ(take.rate_hz, 200.0);
  EXPECT_EQ(take.frames(), 200);
  EXPECT_EQ(take.markers.markers(), 71);
  EXPECT_EQ(take.marker_names[0], "genou1_ NewMarker");  // inner space kept
  EXPECT_EQ(take.marker_names[3], "genou1_NewMarker3");  // " genou1_NewMarker3 " trimmed
  // Line 90 (frame 84): marker 1 = 301.65476 84.11798 132.86554.
  ExpectMarker(take, 83, 1, 301.65476, 84.11798, 132.86554);
  // Line 89: the last marker's cells are empty.
  EXPECT_FALSE(take.markers.Visible(82, 70));
}

TEST(TrcRead, GaitNumMarkersMismatchTrustsTheData) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/Gait.trc");
  Take take = ReadBtk("Gait.trc");
  EXPECT_EQ(take.rate_hz, 100.0);
  EXPECT_EQ(take.frames(), 487);
  // 33 names, NumMarkers=66, rows fill up to 105 markers.
  EXPECT_EQ(take.markers.markers(), 105);
  EXPECT_EQ(take.marker_names[0], "R.Shoulder");
  EXPECT_EQ(take.marker_names[32], "PX");
  EXPECT_EQ(take.marker_names[33], "unnamed_34");
  EXPECT_TRUE(HasWarning(take, "NumMarkers=66"));
  // Line 7 (frame 1): only columns 201-206 are filled (markers 67 and 68, 1-based).
  EXPECT_FALSE(take.markers.Visible(0, 0));
  ExpectMarker(take, 0, 66, 4012.05127, 112.96879, 1347.57288);
  ExpectMarker(take, 0, 67, 3072.72217, -147.32408, 758.08044);
  EXPECT_FALSE(take.markers.Visible(0, 68));
}

TEST(TrcRead, UnnamedNumMarkersZero) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/10002-20130626160334-Unnamed.trc");
  Take take = ReadBtk("10002-20130626160334-Unnamed.trc");
  EXPECT_EQ(take.rate_hz, 400.0);
  EXPECT_EQ(take.frames(), 882);
  ASSERT_EQ(take.markers.markers(), 10);  // BTK finds 10 points too
  for (int m = 0; m < 10; ++m) {
    EXPECT_EQ(take.marker_names[static_cast<size_t>(m)], "unnamed_" + std::to_string(m + 1));
    for (int f = 0; f < 11; ++f) EXPECT_FALSE(take.markers.Visible(f, m));
  }
  ExpectMarker(take, 11, 0, 19.91857, 1362.18750, -124.33382);
  ExpectMarker(take, 356, 1, -161.65665, 1223.79883, -198.66595);
  ExpectMarker(take, 881, 0, -799.76202, 801.21472, -391.54608);
  EXPECT_FALSE(take.markers.Visible(881, 1));
  ExpectMarker(take, 881, 3, -1837.97595, -1082.82910, -1182.05762);
  EXPECT_TRUE(HasWarning(take, "without a name"));
}

TEST(TrcRead, UnnamedSecondFile) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/10002-20130731010438-Unnamed.trc");
  Take take = ReadBtk("10002-20130731010438-Unnamed.trc");
  EXPECT_EQ(take.frames(), 1313);
  EXPECT_EQ(take.markers.markers(), 37);
  ExpectMarker(take, 0, 0, -352.45120, 985.40039, 288.96054);
  ExpectMarker(take, 0, 12, 799.99994, 1593.03601, 427.78055);
  EXPECT_FALSE(take.markers.Visible(893, 0));
  ExpectMarker(take, 893, 27, -376.94412, 1453.94983, 208.30200);
  ExpectMarker(take, 1312, 32, 950.22644, 1470.34619, 951.17596);
}

TEST(TrcRead, OtherSamplesShapes) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/Anto.trc", "trc/btk/Res16bits.trc", "trc/btk/SprintMotion.trc");
  struct Case {
    const char* file;
    int64_t frames, markers;
    double rate;
  };
  for (const Case& c :
       {Case{"Anto.trc", 128, 34, 100}, Case{"Res16bits.trc", 100, 44, 100}, Case{"SprintMotion.trc", 788, 59, 250}}) {
    Take take = ReadBtk(c.file);
    EXPECT_EQ(take.frames(), c.frames) << c.file;
    EXPECT_EQ(take.markers.markers(), c.markers) << c.file;
    EXPECT_EQ(take.rate_hz, c.rate) << c.file;
  }
}

TEST(TrcRead, UpperLimbStaticRowsBeyondTheNames) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/UpperLimbStatic.trc");
  Take take = ReadBtk("UpperLimbStatic.trc");
  EXPECT_EQ(take.frames(), 146);
  // 34 names (NumMarkers=34); line 131 (frame 125) fills columns 108-110.
  ASSERT_EQ(take.markers.markers(), 36);
  EXPECT_EQ(take.marker_names[33], "L.D2M1");
  EXPECT_EQ(take.marker_names[35], "unnamed_36");
  ExpectMarker(take, 124, 35, -12.69762, 430.13324, 1040.39417);
  EXPECT_FALSE(take.markers.Visible(0, 35));
}

TEST(TrcRead, SprintCalibHasMoreDataColumnsThanNames) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/SprintCalib.trc");
  Take take = ReadBtk("SprintCalib.trc");
  EXPECT_EQ(take.frames(), 337);
  EXPECT_EQ(take.markers.markers(), 70);  // 65 names; rows fill 70 markers
  EXPECT_EQ(take.marker_names[0], "C7");
  EXPECT_EQ(take.marker_names[65], "unnamed_66");
  EXPECT_TRUE(HasWarning(take, "NumMarkers=65"));
  // Line 7 (frame 1), columns 198-200: marker 66 = -76.32621 166.11128 1148.26831.
  ExpectMarker(take, 0, 65, -76.32621, 166.11128, 1148.26831);
}

TEST(TrcRead, EmptyFileIsAClearError) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/Empty.trc");
  const std::string path = SharedData("trc/btk/Empty.trc").string();
  std::string msg = ExpectParseError([&] { ReadTrc(path); }, path);
  EXPECT_NE(msg.find("empty"), std::string::npos) << msg;
}

TEST(TrcRead, TruncatedHeaderIsAClearError) {
  CSW_REQUIRE_SHARED_DATA("trc/btk/Truncated.trc");
  const std::string path = SharedData("trc/btk/Truncated.trc").string();
  std::string msg = ExpectParseError([&] { ReadTrc(path); }, path, 3);
  EXPECT_NE(msg.find("end of file"), std::string::npos) << msg;
}

TEST(TrcRead, MissingFileIsIoError) {
  TempDir dir;
  EXPECT_THROW(ReadTrc((dir / "nope.trc").string()), IoError);
}

TEST(TrcRoundTrip, EveryBtkSample) {
  const char* const names[] = {"10002-20130626160334-Unnamed.trc",
                               "10002-20130731010438-Unnamed.trc",
                               "Anto.trc",
                               "Gait.trc",
                               "Knee.trc",
                               "Res16bits.trc",
                               "SprintCalib.trc",
                               "SprintMotion.trc",
                               "UpperLimbStatic.trc",
                               "MOTEK/T.trc",
                               "MOTEK/ballet_reduced.trc"};
  for (const char* name : names) CSW_REQUIRE_SHARED_DATA(std::string(kBtk) + name);
  TempDir dir;
  for (const char* name : names) {
    Take a = ReadBtk(name);
    const std::string out = (dir / "rt.trc").string();
    WriteTrc(out, a);
    Take b = ReadTrc(out);
    SCOPED_TRACE(name);
    ExpectSameTake(a, b);
    EXPECT_FALSE(HasWarning(b, "NumMarkers")) << "the writer's header must match its data";
  }
}

// A take built from known values survives write -> read exactly.
TEST(TrcRoundTrip, SyntheticTakeIsExact) {
  Take take;
  take.rate_hz = 120.0;
  take.first_frame = 17;
  take.marker_names = {"Head 1", "lip.left", "tab\tname"};
  take.markers.Resize(5, 3);
  for (int f = 0; f < 5; ++f) {
    for (int m = 0; m < 3; ++m) {
      float* p = take.markers.at(f, m);
      p[0] = 0.1f * static_cast<float>(f + 1) + static_cast<float>(m) * 1000.0f;
      p[1] = -1.0f / 3.0f * static_cast<float>(f);
      p[2] = 1e-7f * static_cast<float>(m + 1);
    }
  }
  take.markers.SetMissing(2, 1);
  TempDir dir;
  const std::string out = (dir / "syn.trc").string();
  WriteTrc(out, take);
  Take back = ReadTrc(out);
  take.marker_names[2] = "tab name";  // tabs in names are written as spaces
  ExpectSameTake(take, back);
  EXPECT_TRUE(back.provenance.warnings.empty()) << back.provenance.warnings[0];
}

TEST(TrcWrite, RejectsInconsistentTakes) {
  TempDir dir;
  Take take;
  take.marker_names = {"a"};
  take.markers.Resize(1, 1);
  EXPECT_THROW(WriteTrc((dir / "x.trc").string(), take), InvalidInput);  // no rate
  take.rate_hz = 100;
  take.marker_names.clear();
  EXPECT_THROW(WriteTrc((dir / "x.trc").string(), take), InvalidInput);  // names != markers
}

// --- Synthetic files with known content --------------------------------------

std::string Header(const std::string& units, int frames, int markers, const std::string& rate = "100.00") {
  return "PathFileType\t4\t(X/Y/Z)\tx.trc\n"
         "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOri"
         "gNumFrames\n" +
         rate + "\t" + rate + "\t" + std::to_string(frames) + "\t" + std::to_string(markers) + "\t" + units + "\t" +
         rate + "\t1\t" + std::to_string(frames) + "\n";
}

TEST(TrcRead, UnitsAreConvertedToMillimetres) {
  TempDir dir;
  const std::string path = (dir / "m.trc").string();
  WriteBytes(path, Header("m", 2, 1) +
                       "Frame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n\n"
                       "5\t0.00\t0.1\t-0.25\t2\n6\t0.01\t\t\t\n");
  Take take = ReadTrc(path);
  EXPECT_EQ(take.source_units, "m");
  EXPECT_EQ(take.first_frame, 5);
  ExpectMarker(take, 0, 0, 100.0, -250.0, 2000.0);
  EXPECT_FALSE(take.markers.Visible(1, 0));
  EXPECT_TRUE(take.provenance.warnings.empty());
}

TEST(TrcRead, PartialAndNanCellsAreMissing) {
  TempDir dir;
  const std::string path = (dir / "p.trc").string();
  WriteBytes(path, Header("mm", 3, 2) +
                       "Frame#\tTime\tA\t\t\tB\t\t\n\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n"
                       "1\t0\t1\t2\t\t4\t5\t6\n"
                       "2\t0.01\tNaN\tNaN\tNaN\t7\t8\t9\n"
                       "3\t0.02\t1\t1\t1\n");
  Take take = ReadTrc(path);
  ASSERT_EQ(take.frames(), 3);
  EXPECT_FALSE(take.markers.Visible(0, 0));  // z missing
  ExpectMarker(take, 0, 1, 4, 5, 6);
  EXPECT_FALSE(take.markers.Visible(1, 0));
  ExpectMarker(take, 1, 1, 7, 8, 9);
  ExpectMarker(take, 2, 0, 1, 1, 1);
  EXPECT_FALSE(take.markers.Visible(2, 1));  // row ends early
  EXPECT_TRUE(HasWarning(take, "only some of X/Y/Z"));
}

TEST(TrcRead, SpaceSeparatedFileAndNoBlankLine) {
  TempDir dir;
  const std::string path = (dir / "s.trc").string();
  WriteBytes(path,
             "PathFileType 4 (X/Y/Z) s.trc\r\nDataRate CameraRate NumFrames NumMarkers Units\r\n"
             "60 60 2 1 mm\r\nFrame# Time M1\r\n X1 Y1 Z1\r\n1 0 1.5 2.5 3.5\r\n2 0.0167 4 5 6\r\n");
  Take take = ReadTrc(path);
  EXPECT_EQ(take.rate_hz, 60.0);
  ASSERT_EQ(take.marker_names, std::vector<std::string>{"M1"});
  ExpectMarker(take, 0, 0, 1.5, 2.5, 3.5);
  ExpectMarker(take, 1, 0, 4, 5, 6);
}

TEST(TrcRead, TruncatedDataGivesRowsPresentAndWarns) {
  TempDir dir;
  const std::string path = (dir / "t.trc").string();
  WriteBytes(path, Header("mm", 1000000000, 1) + "Frame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n1\t0\t1\t2\t3\n2\t0.01\t4\t5");
  Take take = ReadTrc(path);
  ASSERT_EQ(take.frames(), 2);
  ExpectMarker(take, 0, 0, 1, 2, 3);
  EXPECT_FALSE(take.markers.Visible(1, 0));
  EXPECT_TRUE(HasWarning(take, "NumFrames=1000000000"));
}

TEST(TrcRead, HostileInputsGiveOneParseErrorWithLine) {
  TempDir dir;
  const std::string path = (dir / "bad.trc").string();
  const std::string names = "Frame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n";
  struct Case {
    std::string content;
    int64_t line;
  };
  const Case cases[] = {
      {"hello world\n", 1},
      {std::string("\x89PNG\r\n\x1a\n\0\0", 10), 1},
      {"PathFileType\t4\n", 2},
      {Header("mm", 1, 1, "nan"), 3},
      {Header("mm", 1, 1, "inf"), 3},
      {Header("mm", 1, 1, "-100"), 3},
      {Header("mm", 1, 1), 4},
      {Header("mm", 1, 1) + "garbage\n", 4},
      {Header("mm", 1, 1) + names + "1\t0\tinf\t0\t0\n", 6},
      {Header("mm", 1, 1) + names + "1\t0\t1e300\t0\t0\n", 6},
      {Header("mm", 1, 1) + names + "1\t0\t1\t2\t3\nx\t0\t1\t2\t3\n", 7},
      {Header("mm", 1, 1) + names + "1\tnan\t1\t2\t3\n", 6},
      {Header("mm", 1, 1) + names + "1\t0\t1\t0x10\t3\n", 6},
  };
  for (const Case& c : cases) {
    WriteBytes(path, c.content);
    SCOPED_TRACE(c.content.substr(0, 60));
    ExpectParseError([&] { ReadTrc(path); }, path, c.line);
  }
}

// A short file must not be able to make the reader allocate frames x markers
// far beyond its size (many one-cell rows plus one very wide row).
TEST(TrcRead, ImpliedTableLargerThanFileIsRefused) {
  TempDir dir;
  const std::string path = (dir / "wide.trc").string();
  std::string content = Header("mm", 1, 1) + "Frame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n";
  for (int i = 0; i < 20000; ++i) content += "1\t0\n";
  content += "2\t0" + std::string(60000, '\t') + "1\n";
  WriteBytes(path, content);
  ExpectParseError([&] { ReadTrc(path); }, path, 20006);
}

}  // namespace
}  // namespace csw

// Known facts about the third-party C3D samples (shared/data/README.md), the MIPS
// twins, and the files another reader rejects.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "io/c3d/c3d.h"
#include "io/c3d/c3d_format.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

std::string Data(const std::string& rel) { return testing::SharedData("c3d/" + rel).string(); }

C3dInfo InfoOf(const std::string& rel) {
  C3dReader reader(Data(rel));
  return reader.info();
}

std::vector<unsigned char> Bytes(const std::string& path, size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> b(n);
  in.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(n));
  b.resize(static_cast<size_t>(in.gcount()));
  return b;
}

bool SameFloats(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!((std::isnan(a[i]) && std::isnan(b[i])) || a[i] == b[i])) return false;
  }
  return true;
}

void ExpectSameTake(const std::string& a_rel, const std::string& b_rel) {
  Take a = ReadC3d(Data(a_rel));
  Take b = ReadC3d(Data(b_rel));
  EXPECT_EQ(a.rate_hz, b.rate_hz);
  EXPECT_EQ(a.first_frame, b.first_frame);
  EXPECT_EQ(a.marker_names, b.marker_names);
  ASSERT_EQ(a.frames(), b.frames());
  ASSERT_GT(a.markers.CountVisible(), 0);
  EXPECT_TRUE(SameFloats(a.markers.data(), b.markers.data()));
  EXPECT_EQ(a.analog.names, b.analog.names);
  EXPECT_EQ(a.analog.rate_hz, b.analog.rate_hz);
  ASSERT_GT(a.analog.data.size(), 0u);
  EXPECT_TRUE(SameFloats(a.analog.data, b.analog.data));
  ASSERT_EQ(a.events.size(), b.events.size());
  for (size_t i = 0; i < a.events.size(); ++i) {
    EXPECT_EQ(a.events[i].label, b.events[i].label);
    EXPECT_EQ(a.events[i].time_s, b.events[i].time_s);
  }
}

TEST(C3dFacts, MipsTwinsEqualIntel) {
  for (auto [mips, intel] : {std::pair{"c3d.org/sample_01/Eb015si.c3d", "c3d.org/sample_01/Eb015pi.c3d"},
                             std::pair{"c3d.org/sample_01/Eb015sr.c3d", "c3d.org/sample_01/Eb015pr.c3d"},
                             std::pair{"c3d.org/sample_02/sgi_int.c3d", "c3d.org/sample_02/pc_int.c3d"},
                             std::pair{"c3d.org/sample_02/sgi_real.c3d", "c3d.org/sample_02/pc_real.c3d"}}) {
    CSW_REQUIRE_SHARED_DATA(std::string("c3d/") + mips, std::string("c3d/") + intel);
    SCOPED_TRACE(mips);
    EXPECT_EQ(InfoOf(mips).processor, "mips");
    EXPECT_EQ(InfoOf(intel).processor, "intel");
    ExpectSameTake(mips, intel);
    int64_t na = 0, nb = 0;
    double sa = 0, sb = 0;
    C3dReader(Data(mips)).ValidPointStats(&na, &sa);
    C3dReader(Data(intel)).ValidPointStats(&nb, &sb);
    EXPECT_EQ(na, nb);
    EXPECT_EQ(sa, sb);
  }
}

TEST(C3dFacts, DecTwinsOfSample01EqualIntel) {
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_01/Eb015vi.c3d", "c3d/c3d.org/sample_01/Eb015vr.c3d",
                          "c3d/c3d.org/sample_01/Eb015pi.c3d", "c3d/c3d.org/sample_01/Eb015pr.c3d");
  EXPECT_EQ(InfoOf("c3d.org/sample_01/Eb015vr.c3d").processor, "dec");
  ExpectSameTake("c3d.org/sample_01/Eb015vi.c3d", "c3d.org/sample_01/Eb015pi.c3d");
  ExpectSameTake("c3d.org/sample_01/Eb015vr.c3d", "c3d.org/sample_01/Eb015pr.c3d");
}

TEST(C3dFacts, DecFloatIsSwappedHalvesDividedByFour) {
  // 1.0 in VAX F-float is IEEE 4.0f (0x40800000) with its 16-bit halves swapped.
  const unsigned char one[4] = {0x80, 0x40, 0x00, 0x00};
  EXPECT_EQ(c3d::LoadF32<c3d::Processor::kDec>(one), 1.0f);
  // -0.28 (sample_02's POINT:SCALE magnitude, negated): encode through IEEE x 4.
  float v = -0.28f * 4.0f;
  uint32_t bits;
  std::memcpy(&bits, &v, 4);
  const unsigned char dec[4] = {static_cast<unsigned char>((bits >> 16) & 0xFF), static_cast<unsigned char>(bits >> 24),
                                static_cast<unsigned char>(bits & 0xFF),
                                static_cast<unsigned char>((bits >> 8) & 0xFF)};
  EXPECT_EQ(c3d::LoadF32<c3d::Processor::kDec>(dec), -0.28f);
  const unsigned char zero[4] = {0, 0, 0x12, 0x34};  // zero exponent: a true zero in VAX
  EXPECT_EQ(c3d::LoadF32<c3d::Processor::kDec>(zero), 0.0f);
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_02/dec_real.c3d");
  C3dReader dec_reader(Data("c3d.org/sample_02/dec_real.c3d"));
  EXPECT_EQ(dec_reader.info().processor, "dec");
  EXPECT_EQ(dec_reader.info().point_rate_hz, 50.0);  // header rate, a DEC float
  EXPECT_EQ(dec_reader.info().analog_rate_hz, 200.0);
}

TEST(C3dFacts, Sample01HasThreeHeaderEvents) {
  const char* const files[] = {"Eb015pi.c3d", "Eb015pr.c3d", "Eb015si.c3d",
                               "Eb015sr.c3d", "Eb015vi.c3d", "Eb015vr.c3d"};
  for (const char* f : files) CSW_REQUIRE_SHARED_DATA(std::string("c3d/c3d.org/sample_01/") + f);
  for (const char* f : files) {
    const std::string rel = std::string("c3d.org/sample_01/") + f;
    SCOPED_TRACE(rel);
    // The header's event count is the 16-bit word at byte 300.
    std::vector<unsigned char> h = Bytes(Data(rel), 512);
    ASSERT_EQ(h.size(), 512u);
    const bool mips = f[5] == 's';
    EXPECT_EQ(mips ? c3d::LoadU16Be(h.data() + 300) : c3d::LoadU16Le(h.data() + 300), 3);
    const std::vector<Event> ev = InfoOf(rel).events;
    ASSERT_EQ(ev.size(), 3u);
    EXPECT_EQ(ev[0].label, "RIC");
    EXPECT_NEAR(ev[0].time_s, 2.72, 1e-6);
    EXPECT_EQ(ev[1].label, "RHS");
    EXPECT_NEAR(ev[1].time_s, 5.40, 1e-6);
    EXPECT_EQ(ev[2].label, "RTO");
    EXPECT_NEAR(ev[2].time_s, 7.32, 1e-6);
  }
}

TEST(C3dFacts, Sample02HasNineHeaderEventsEightInDecInt) {
  for (const char* f : {"pc_int.c3d", "pc_real.c3d", "dec_real.c3d", "sgi_int.c3d", "sgi_real.c3d", "dec_int.c3d"}) {
    CSW_REQUIRE_SHARED_DATA(std::string("c3d/c3d.org/sample_02/") + f);
  }
  for (const char* f : {"pc_int.c3d", "pc_real.c3d", "dec_real.c3d", "sgi_int.c3d", "sgi_real.c3d"}) {
    EXPECT_EQ(InfoOf(std::string("c3d.org/sample_02/") + f).events.size(), 9u) << f;
  }
  std::vector<Event> dec = InfoOf("c3d.org/sample_02/dec_int.c3d").events;
  std::vector<Event> pc = InfoOf("c3d.org/sample_02/pc_int.c3d").events;
  ASSERT_EQ(dec.size(), 8u);
  for (size_t i = 0; i < dec.size(); ++i) {
    EXPECT_EQ(dec[i].label, pc[i].label);
    EXPECT_FLOAT_EQ(static_cast<float>(dec[i].time_s), static_cast<float>(pc[i].time_s));
  }
}

TEST(C3dFacts, Sample33DataStartIsUnsigned188) {
  const std::string rel = "c3d.org/sample_33/bigparlove.c3d";
  CSW_REQUIRE_SHARED_DATA("c3d/" + rel);
  std::vector<unsigned char> h = Bytes(Data(rel), 512);
  ASSERT_EQ(h.size(), 512u);
  EXPECT_EQ(c3d::LoadU16Le(h.data() + 16), 188);  // header word 9
  Take t = ReadC3d(Data(rel));
  EXPECT_EQ(t.frames(), 323);
  EXPECT_EQ(t.markers.markers(), 205);
  EXPECT_EQ(t.markers.CountVisible(), 65063);
}

TEST(C3dFacts, ViconFirstSample) {
  CSW_REQUIRE_SHARED_DATA("c3d/ezc3d/Vicon.c3d");
  C3dReader r(Data("ezc3d/Vicon.c3d"));
  ASSERT_EQ(r.info().units, "mm");
  std::vector<float> p(static_cast<size_t>(r.info().points * 3));
  std::vector<float> res(static_cast<size_t>(r.info().points));
  r.ReadFrames(0, 1, p.data(), res.data(), nullptr);
  EXPECT_EQ(p[0], 44.16278839111328f);
  EXPECT_GE(res[0], 0.0f);
}

TEST(C3dFacts, FacialSing) {
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_29/Facial-Sing.c3d");
  C3dReader r(Data("c3d.org/sample_29/Facial-Sing.c3d"));
  EXPECT_EQ(r.info().points, 38);
  EXPECT_EQ(r.info().frames, 3000);
  EXPECT_EQ(r.info().point_rate_hz, 100.0);
  EXPECT_EQ(r.info().analog_channels, 0);
  int64_t valid = 0;
  double sum = 0;
  r.ValidPointStats(&valid, &sum);
  EXPECT_NEAR(sum, 76900568.0833, 1e-6 * 76900568.0833);
  Take t = ReadC3d(Data("c3d.org/sample_29/Facial-Sing.c3d"));
  for (int i = 1; i <= 6; ++i) EXPECT_GE(t.MarkerIndex("root-" + std::to_string(i)), 0);
  auto missing = [&](const std::string& name) {
    int64_t m = t.MarkerIndex(name), n = 0;
    EXPECT_GE(m, 0) << name;
    for (int64_t f = 0; m >= 0 && f < t.frames(); ++f) n += t.markers.Visible(f, m) ? 0 : 1;
    return n;
  };
  EXPECT_EQ(missing("Unlabeled1"), 3000 - 35);
  EXPECT_EQ(missing("section3-1"), 33);
  EXPECT_EQ(missing("section4-1"), 42);
  EXPECT_EQ(missing("section4-2"), 110);
  EXPECT_EQ(missing("section5-1"), 254);
  EXPECT_EQ(missing("section6-1"), 257);
  EXPECT_EQ(missing("section13-2"), 55);
  EXPECT_EQ(missing("root-1"), 0);
}

TEST(C3dFacts, OptotrakTruncatedGivesWhatItHolds) {
  CSW_REQUIRE_SHARED_DATA("c3d/ezc3d/Optotrak.c3d");
  C3dReader r(Data("ezc3d/Optotrak.c3d"));
  EXPECT_EQ(r.info().frames, 29);
  ASSERT_FALSE(r.info().warnings.empty());
  EXPECT_NE(r.info().warnings[0].find("1149"), std::string::npos);
  Take t = ReadC3d(Data("ezc3d/Optotrak.c3d"));
  EXPECT_EQ(t.frames(), 29);
  EXPECT_EQ(t.markers.CountVisible(), 1507);
  EXPECT_FALSE(t.provenance.warnings.empty());
}

TEST(C3dFacts, EmptyFileIsOneClearParseError) {
  CSW_REQUIRE_SHARED_DATA("c3d/btk/Empty.c3d");
  const std::string path = Data("btk/Empty.c3d");
  try {
    ReadC3d(path);
    FAIL() << "no error for an empty file";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.where().file, path);
    EXPECT_EQ(e.where().offset, 0);
    EXPECT_NE(std::string(e.what()).find("Empty.c3d: offset 0: file is empty"), std::string::npos) << e.what();
  }
}

TEST(C3dFacts, FloatAnalogOffsetReadWithWarning) {
  // sample_13 Dance.c3d / golfswing.c3d store ANALOG:OFFSET as float (and POINT:DATA_START 0).
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_13/Dance.c3d", "c3d/c3d.org/sample_13/golfswing.c3d",
                          "c3d/c3d.org/sample_13/Dance1.c3d");
  for (const char* f : {"Dance.c3d", "golfswing.c3d"}) {
    Take t = ReadC3d(Data(std::string("c3d.org/sample_13/") + f));
    bool warned = false;
    for (const std::string& w : t.provenance.warnings) warned |= w.find("ANALOG:OFFSET") != std::string::npos;
    EXPECT_TRUE(warned) << f;
    EXPECT_EQ(t.analog.channels(), 8) << f;
    EXPECT_GT(t.markers.CountVisible(), 0) << f;
  }
  // Dance1.c3d, the corrected file, declares frames 2..499 (and holds 498 of them).
  Take d = ReadC3d(Data("c3d.org/sample_13/Dance.c3d"));
  Take d1 = ReadC3d(Data("c3d.org/sample_13/Dance1.c3d"));
  EXPECT_EQ(d.frames(), 499);
  EXPECT_EQ(d1.frames(), 498);
  EXPECT_EQ(d1.first_frame, 2);
}

TEST(C3dFacts, DamagedParameterSectionsRecovered) {
  CSW_REQUIRE_SHARED_DATA("c3d/c3d.org/sample_18/bad_parameter_section.c3d",
                          "c3d/c3d.org/sample_22/BKINtechnologies.c3d");
  Take bad = ReadC3d(Data("c3d.org/sample_18/bad_parameter_section.c3d"));
  EXPECT_FALSE(bad.provenance.warnings.empty());
  EXPECT_EQ(bad.markers.markers(), 45);
  EXPECT_EQ(bad.frames(), 332);
  EXPECT_EQ(bad.analog.channels(), 32);
  EXPECT_EQ(bad.events.size(), 7u);  // header events survive
  EXPECT_GT(bad.markers.CountVisible(), 0);

  Take bkin = ReadC3d(Data("c3d.org/sample_22/BKINtechnologies.c3d"));
  EXPECT_EQ(bkin.frames(), 5065);
  EXPECT_EQ(bkin.rate_hz, 1000.0);
  ASSERT_EQ(bkin.events.size(), 2u);  // from the non-standard EVENTS group
  EXPECT_EQ(bkin.events[0].label, "STAY_CENTRE");
  EXPECT_EQ(bkin.events[1].label, "TARGET_ON");
  EXPECT_NEAR(bkin.events[1].time_s, 1.614, 1e-6);
}

TEST(C3dFacts, EveryPeerErrorFileGivesDataOrOneParseError) {
  for (const char* rel :
       {"btk/Empty.c3d", "c3d.org/sample_01/Eb015si.c3d", "c3d.org/sample_01/Eb015sr.c3d",
        "c3d.org/sample_02/sgi_int.c3d", "c3d.org/sample_02/sgi_real.c3d", "c3d.org/sample_06/MACsample.c3d",
        "c3d.org/sample_13/Dance.c3d", "c3d.org/sample_13/golfswing.c3d", "c3d.org/sample_18/bad_parameter_section.c3d",
        "c3d.org/sample_22/BKINtechnologies.c3d", "c3d.org/sample_29/Facial-Sing.c3d"}) {
    CSW_REQUIRE_SHARED_DATA(std::string("c3d/") + rel);
    SCOPED_TRACE(rel);
    try {
      Take t = ReadC3d(Data(rel));
      EXPECT_GT(t.frames(), 0);
      EXPECT_GT(t.markers.CountVisible(), 0);
    } catch (const ParseError& e) {
      EXPECT_EQ(e.where().file, Data(rel));
      EXPECT_TRUE(e.where().offset.has_value());
    }
  }
}

}  // namespace
}  // namespace csw

// Known answers for parameter handling: files written by WriteC3d, then edited in
// place (units, analog scale/offset/gen-scale, 16-bit frame words), and int16 / float
// twins from c3d.org.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>

#include "io/c3d/c3d.h"
#include "io/c3d/c3d_format.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

std::vector<unsigned char> ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void WriteAll(const std::string& path, const std::vector<unsigned char>& b) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

// Offset of the data of GROUP:NAME in an Intel file (walks the parameter links).
size_t ParamData(const std::vector<unsigned char>& b, const std::string& group, const std::string& name) {
  size_t pos = (b[0] - 1) * 512 + 4;
  std::map<int, std::string> groups;
  while (pos + 2 < b.size() && b[pos] != 0) {
    const int len = std::abs(static_cast<int8_t>(b[pos]));
    const int id = static_cast<int8_t>(b[pos + 1]);
    const std::string n(reinterpret_cast<const char*>(&b[pos + 2]), static_cast<size_t>(len));
    const size_t link = pos + 2 + static_cast<size_t>(len);
    const int16_t off = static_cast<int16_t>(c3d::LoadU16Le(&b[link]));
    if (id < 0) {
      groups[-id] = n;
    } else if (groups[id] == group && n == name) {
      const size_t p = link + 2;
      return p + 2 + b[p + 1];  // type, ndims, dims
    }
    if (off == 0) break;
    pos = link + static_cast<size_t>(off);
  }
  ADD_FAILURE() << group << ":" << name << " not found";
  return 0;
}

Take SmallTake() {
  Take t;
  t.rate_hz = 50;
  t.marker_names = {"A", "B"};
  t.markers.Resize(4, 2);
  for (size_t i = 0; i < t.markers.data().size(); ++i) t.markers.data()[i] = 10.0f + static_cast<float>(i);
  t.markers.SetMissing(2, 1);
  t.analog.rate_hz = 100;
  t.analog.names = {"F1", "F2"};
  t.analog.units = {"N", "V"};
  t.analog.samples = 8;
  for (int i = 0; i < 16; ++i) t.analog.data.push_back(static_cast<float>(i) - 3.0f);
  return t;
}

TEST(C3dParams, UnitsAreNormalisedToMillimetres) {
  testing::TempDir dir;
  const std::string path = (dir / "u.c3d").string();
  const Take t = SmallTake();
  for (auto [units, factor] : {std::pair{"m ", 1000.0f}, std::pair{"cm", 10.0f}, std::pair{"mm", 1.0f}}) {
    WriteC3d(path, t);
    std::vector<unsigned char> b = ReadAll(path);
    size_t at = ParamData(b, "POINT", "UNITS");
    std::memcpy(&b[at], units, 2);
    WriteAll(path, b);
    C3dReader r(path);
    EXPECT_EQ(r.info().units, std::string(units).substr(0, units[1] == ' ' ? 1 : 2));
    Take back = ReadC3d(path);
    EXPECT_EQ(back.source_units, r.info().units);
    for (size_t i = 0; i < t.markers.data().size(); ++i) {
      float want = t.markers.data()[i] * factor, got = back.markers.data()[i];
      EXPECT_TRUE((std::isnan(want) && std::isnan(got)) || want == got) << units << " " << i;
    }
    // ValidPointStats stays in the file's units.
    int64_t n = 0;
    double s = 0;
    r.ValidPointStats(&n, &s);
    EXPECT_EQ(n, 7);
    double want = 0;
    for (int64_t f = 0; f < 4; ++f) {
      for (int64_t m = 0; m < 2; ++m) {
        if (t.markers.Visible(f, m)) want += t.markers.at(f, m)[0] + t.markers.at(f, m)[1] + t.markers.at(f, m)[2];
      }
    }
    EXPECT_EQ(s, want);
  }
}

TEST(C3dParams, AnalogScaleOffsetGenScale) {
  testing::TempDir dir;
  const std::string path = (dir / "a.c3d").string();
  const Take t = SmallTake();
  WriteC3d(path, t);
  std::vector<unsigned char> b = ReadAll(path);
  c3d::StoreF32Le(&b[ParamData(b, "ANALOG", "GEN_SCALE")], 2.0f);
  size_t sc = ParamData(b, "ANALOG", "SCALE");
  c3d::StoreF32Le(&b[sc], 0.5f);
  c3d::StoreF32Le(&b[sc + 4], -0.25f);
  size_t of = ParamData(b, "ANALOG", "OFFSET");
  c3d::StoreU16Le(&b[of], 3);
  c3d::StoreU16Le(&b[of + 2], static_cast<uint16_t>(-2));
  WriteAll(path, b);
  Take back = ReadC3d(path);
  ASSERT_EQ(back.analog.data.size(), 16u);
  for (size_t i = 0; i < 16; ++i) {
    const float raw = t.analog.data[i];
    const float want = i % 2 == 0 ? (raw - 3.0f) * 0.5f * 2.0f : (raw + 2.0f) * -0.25f * 2.0f;
    EXPECT_FLOAT_EQ(back.analog.data[i], want) << i;
  }
  EXPECT_EQ(back.analog.units, t.analog.units);
}

TEST(C3dParams, HeaderFrameWordsAreUnsigned) {
  testing::TempDir dir;
  const std::string path = (dir / "h.c3d").string();
  Take t = SmallTake();
  t.first_frame = 40000;  // above the signed 16-bit range
  WriteC3d(path, t);
  std::vector<unsigned char> b = ReadAll(path);
  EXPECT_EQ(c3d::LoadU16Le(&b[6]), 40000);
  EXPECT_EQ(c3d::LoadU16Le(&b[8]), 40003);
  C3dReader r(path);
  EXPECT_EQ(r.info().first_frame, 40000);
  EXPECT_EQ(r.info().frames, 4);
}

TEST(C3dParams, IntAndRealTwinsAgree) {
  for (auto [int_rel, real_rel] :
       {std::pair{"c3d/c3d.org/sample_01/Eb015pi.c3d", "c3d/c3d.org/sample_01/Eb015pr.c3d"},
        std::pair{"c3d/c3d.org/sample_02/pc_int.c3d", "c3d/c3d.org/sample_02/pc_real.c3d"}}) {
    CSW_REQUIRE_SHARED_DATA(int_rel, real_rel);
    SCOPED_TRACE(int_rel);
    C3dReader ri(testing::SharedData(int_rel).string());
    EXPECT_EQ(ri.info().storage, "int16");
    EXPECT_EQ(C3dReader(testing::SharedData(real_rel).string()).info().storage, "float");
    Take a = ReadC3d(testing::SharedData(int_rel).string());
    Take b = ReadC3d(testing::SharedData(real_rel).string());
    ASSERT_EQ(a.markers.data().size(), b.markers.data().size());
    // Points agree to one int16 step of POINT:SCALE (sample_02 truncates rather than rounds).
    const double step = std::fabs(ri.info().point_scale);
    for (size_t i = 0; i < a.markers.data().size(); ++i) {
      float x = a.markers.data()[i], y = b.markers.data()[i];
      ASSERT_EQ(std::isnan(x), std::isnan(y)) << i;
      if (!std::isnan(x)) {
        ASSERT_NEAR(x, y, step + 1e-3) << i;
      }
    }
    // Analog: (raw - offset) * scale * gen_scale of the int16 file equals the float file.
    ASSERT_EQ(a.analog.data.size(), b.analog.data.size());
    ASSERT_GT(a.analog.data.size(), 0u);
    EXPECT_EQ(a.analog.data, b.analog.data);
  }
}

}  // namespace
}  // namespace csw

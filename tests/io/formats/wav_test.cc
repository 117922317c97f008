// WAV through libsndfile: generated sine round trips, praatio's bobby.wav
// (rate and length from `soxi`), hostile files.
#include "io/formats/wav.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "core/error.h"
#include "tests/io/formats/test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

using testing::ExpectParseError;
using testing::ReadBytes;
using testing::SharedData;
using testing::TempDir;
using testing::WriteBytes;

Audio Sine(double rate, int channels, int64_t frames, double freq, double amplitude) {
  Audio a;
  a.rate_hz = rate;
  a.channels = channels;
  a.samples.resize(static_cast<size_t>(frames * channels));
  for (int64_t f = 0; f < frames; ++f) {
    for (int c = 0; c < channels; ++c) {
      a.samples[static_cast<size_t>(f * channels + c)] = static_cast<float>(
          amplitude * std::sin(2 * std::numbers::pi * freq * (c + 1) * static_cast<double>(f) / rate));
    }
  }
  return a;
}

TEST(WavRoundTrip, Pcm16SineWithinHalfAStep) {
  const Audio sine = Sine(16000, 2, 16000, 440, 0.9);
  TempDir dir;
  const std::string path = (dir / "sine.wav").string();
  WriteWav(path, sine);
  Audio back = ReadWav(path);
  EXPECT_EQ(back.rate_hz, 16000);
  EXPECT_EQ(back.channels, 2);
  ASSERT_EQ(back.samples.size(), sine.samples.size());
  double worst = 0;
  for (size_t i = 0; i < sine.samples.size(); ++i) {
    worst = std::max(worst, std::abs(static_cast<double>(back.samples[i]) - sine.samples[i]));
    // Every sample read from a 16-bit file is k / 32768.
    ASSERT_EQ(std::fmod(static_cast<double>(back.samples[i]) * 32768.0, 1.0), 0.0);
  }
  EXPECT_LE(worst, 0.5 / 32768 + 1e-9);
  // Read -> write -> read is bit exact.
  const std::string again = (dir / "again.wav").string();
  WriteWav(again, back);
  Audio back2 = ReadWav(again);
  EXPECT_EQ(back2.samples, back.samples);
}

TEST(WavRoundTrip, FullScaleIsClampedAndFloat32IsExact) {
  Audio a;
  a.rate_hz = 8000;
  a.samples = {1.0f, -1.0f, 1.5f, -2.0f, 0.25f, 1.0f / 32768.0f};
  TempDir dir;
  const std::string p16 = (dir / "clip.wav").string();
  WriteWav(p16, a);
  Audio b = ReadWav(p16);
  ASSERT_EQ(b.samples.size(), 6u);
  EXPECT_EQ(b.samples[0], 32767.0f / 32768.0f);
  EXPECT_EQ(b.samples[1], -1.0f);
  EXPECT_EQ(b.samples[2], 32767.0f / 32768.0f);
  EXPECT_EQ(b.samples[3], -1.0f);
  EXPECT_EQ(b.samples[4], 0.25f);
  EXPECT_EQ(b.samples[5], 1.0f / 32768.0f);
  const std::string p32 = (dir / "float.wav").string();
  const Audio sine = Sine(44100, 1, 4410, 1000, 1.2);
  WriteWav(p32, sine, 32);
  Audio f = ReadWav(p32);
  EXPECT_EQ(f.rate_hz, 44100);
  EXPECT_EQ(f.samples, sine.samples);
}

TEST(WavRead, PraatioBobbyMatchesSoxi) {
  CSW_REQUIRE_SHARED_DATA("textgrid/praatio/bobby.wav");
  Audio a = ReadWav(SharedData("textgrid/praatio/bobby.wav").string());
  // soxi: 1 channel, 48000 Hz, 16-bit, 57342 samples (00:00:01.19).
  EXPECT_EQ(a.rate_hz, 48000);
  EXPECT_EQ(a.channels, 1);
  EXPECT_EQ(a.frames(), 57342);
  EXPECT_NEAR(a.duration_s(), 57342.0 / 48000.0, 1e-12);
  float peak = 0;
  for (float s : a.samples) peak = std::max(peak, std::abs(s));
  EXPECT_GT(peak, 0.01f);
  EXPECT_LE(peak, 1.0f);
}

TEST(WavWrite, RejectsBadAudio) {
  TempDir dir;
  const std::string p = (dir / "x.wav").string();
  Audio a;
  a.rate_hz = 8000;
  a.samples = {0.0f, 0.5f};
  EXPECT_THROW(WriteWav(p, a, 8), InvalidInput);
  a.rate_hz = 8000.5;
  EXPECT_THROW(WriteWav(p, a), InvalidInput);
  a.rate_hz = 8000;
  a.channels = 3;
  EXPECT_THROW(WriteWav(p, a), InvalidInput);  // 2 samples, 3 channels
  a.channels = 1;
  a.samples[1] = NAN;
  EXPECT_THROW(WriteWav(p, a), InvalidInput);
}

TEST(WavRead, HostileFiles) {
  TempDir dir;
  EXPECT_THROW(ReadWav((dir / "missing.wav").string()), IoError);
  const std::string p = (dir / "bad.wav").string();
  WriteBytes(p, "this is not audio at all, just some text");
  ExpectParseError([&] { ReadWav(p); }, p, -1);
  WriteBytes(p, "");
  ExpectParseError([&] { ReadWav(p); }, p, -1);

  // A header declaring far more data than present: the frames present are read.
  const std::string good = (dir / "good.wav").string();
  WriteWav(good, Sine(8000, 1, 800, 100, 0.5));
  std::string bytes = ReadBytes(good);
  ASSERT_EQ(bytes.size(), 44u + 1600u);
  const std::string cut = (dir / "cut.wav").string();
  WriteBytes(cut, bytes.substr(0, 44 + 1000));
  Audio a = ReadWav(cut);
  EXPECT_EQ(a.frames(), 500);
  // Huge declared RIFF and data sizes.
  std::string huge = bytes;
  for (size_t off : {size_t{4}, size_t{40}}) std::memset(&huge[off], 0xFF, 4);
  WriteBytes(cut, huge);
  try {
    Audio h = ReadWav(cut);
    EXPECT_EQ(h.frames(), 800);
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.wav"), std::string::npos);
  }
}

TEST(WavRead, NanInFloatFileIsParseError) {
  TempDir dir;
  const std::string p = (dir / "nan.wav").string();
  WriteWav(p, Sine(8000, 1, 100, 100, 0.5), 32);
  std::string bytes = ReadBytes(p);
  const size_t data = bytes.find("data");
  ASSERT_NE(data, std::string::npos);
  const unsigned char nan_le[4] = {0x00, 0x00, 0xC0, 0x7F};
  std::memcpy(&bytes[data + 8 + 4 * 10], nan_le, 4);
  WriteBytes(p, bytes);
  std::string msg = ExpectParseError([&] { ReadWav(p); }, p, -1);
  EXPECT_NE(msg.find("sample 10"), std::string::npos) << msg;
}

}  // namespace
}  // namespace csw

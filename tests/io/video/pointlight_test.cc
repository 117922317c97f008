// Point-light videos (io/video/pointlight.h): synthetic takes with markers on
// known paths, rendered to MP4 and read back with OpenCV's VideoCapture.
#include "io/video/pointlight.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/error.h"
#include "io/formats/wav.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;

constexpr double kRate = 120.0;
constexpr int64_t kFrames = 276;  // 2.3 s at 120 Hz
const Eigen::Vector3d kProbe(50, 30, -20);
const Eigen::Vector3d kCircleCentre(-40, 0, 40);
constexpr double kCircleRadius = 30;
constexpr double kCircleHz = 0.5;

Eigen::Vector3d CircleAt(double t) {
  const double a = 2 * std::numbers::pi * kCircleHz * t;
  return kCircleCentre + kCircleRadius * Eigen::Vector3d(std::cos(a), 0, std::sin(a));
}

void Set(Take* take, int64_t f, int64_t j, const Eigen::Vector3d& p) {
  float* q = take->markers.at(f, j);
  q[0] = static_cast<float>(p.x());
  q[1] = static_cast<float>(p.y());
  q[2] = static_cast<float>(p.z());
}

// Markers: two fixed corners spanning x, z in [-100, 100] (so the lab-axes
// view is known), a fixed probe, a marker on a circle (0.5 Hz) and one that
// is missing in the second half.
Take MakeTake(int64_t frames = kFrames) {
  Take t;
  t.name = "synthetic_take";
  t.rate_hz = kRate;
  t.marker_names = {"corner_lo", "corner_hi", "probe", "circle", "half"};
  t.markers.Resize(frames, 5);
  for (int64_t f = 0; f < frames; ++f) {
    const double time = static_cast<double>(f) / kRate;
    Set(&t, f, 0, {-100, 5, -100});
    Set(&t, f, 1, {100, -5, 100});
    Set(&t, f, 2, kProbe);
    Set(&t, f, 3, CircleAt(time));
    if (f < frames / 2) Set(&t, f, 4, {0, 0, -60});
  }
  return t;
}

// Small picture, 30 frames/s.
PointLightOptions SmallOptions() {
  PointLightOptions o;
  o.fps = 30;
  o.width = 320;
  o.height = 240;
  return o;
}

// Centroid of the pixels brighter than `threshold` (grey level) in a square of
// half-size `radius` around (x, y); (-1, -1) when none.
cv::Point2d BrightCentroid(const cv::Mat& bgr, double x, double y, int radius, int threshold = 100) {
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  double sx = 0, sy = 0, n = 0;
  for (int v = static_cast<int>(y) - radius; v <= static_cast<int>(y) + radius; ++v) {
    for (int u = static_cast<int>(x) - radius; u <= static_cast<int>(x) + radius; ++u) {
      if (u < 0 || v < 0 || u >= grey.cols || v >= grey.rows) continue;
      const int g = grey.at<uint8_t>(v, u);
      if (g < threshold) continue;
      sx += g * u;
      sy += g * v;
      n += g;
    }
  }
  return n > 0 ? cv::Point2d(sx / n, sy / n) : cv::Point2d(-1, -1);
}

std::vector<cv::Mat> ReadAll(const fs::path& path, double* fps, int* reported_frames) {
  cv::VideoCapture cap(path.string(), cv::CAP_FFMPEG);
  EXPECT_TRUE(cap.isOpened()) << path;
  *fps = cap.get(cv::CAP_PROP_FPS);
  *reported_frames = static_cast<int>(cap.get(cv::CAP_PROP_FRAME_COUNT));
  std::vector<cv::Mat> frames;
  cv::Mat m;
  while (cap.read(m)) frames.push_back(m.clone());
  return frames;
}

std::vector<std::string> FilesIn(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  return out;
}

std::string Joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += x + " ";
  return s;
}

void WriteFile(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// A silent WAV of `seconds` at 16 kHz.
void WriteSilence(const fs::path& path, double seconds) {
  Audio a;
  a.rate_hz = 16000;
  a.samples.assign(static_cast<size_t>(std::lround(seconds * a.rate_hz)), 0.0f);
  WriteWav(path.string(), a);
}

TEST(PointLight, FrameCountIsRoundedDurationTimesFps) {
  EXPECT_EQ(PointLightFrameCount(2.3, 30), 69);
  EXPECT_EQ(PointLightFrameCount(1.0, 25), 25);
  EXPECT_EQ(PointLightFrameCount(0.02, 25), 1);   // 0.5 frames: round half away from zero
  EXPECT_EQ(PointLightFrameCount(0.001, 25), 1);  // at least one frame
  EXPECT_EQ(PointLightFrameCount(10.0 / 3.0, 30), 100);
}

// The lab-axes view checked by hand: the corners span x, z in [-100, 100] mm;
// 320 x 240 with a 6 % margin each side leaves 0.88 × 240 = 211.2 px for
// 200 mm vertically (the tighter way): 1.056 px/mm, centred on (0, 0).
TEST(PointLight, LabAxesViewProjectsAsComputedByHand) {
  const Take take = MakeTake();
  const PointLightView v = FitPointLightView(take, nullptr, SmallOptions());
  EXPECT_EQ(v.how, "lab axes (x right, z up)");
  EXPECT_NEAR(v.scale_px_per_mm, 1.056, 1e-9);
  EXPECT_NEAR(v.center_mm.x(), 0, 1e-9);
  EXPECT_NEAR(v.center_mm.y(), 0, 1e-9);
  // probe (50, 30, -20): x = 160 + 1.056 × 50, y = 120 + 1.056 × 20 (y down; lab y is depth).
  const Eigen::Vector2d p = v.Project(kProbe);
  EXPECT_NEAR(p.x(), 212.8, 1e-9);
  EXPECT_NEAR(p.y(), 141.12, 1e-9);
  const Eigen::Vector2d lo = v.Project({-100, 0, -100}), hi = v.Project({100, 0, 100});
  EXPECT_NEAR(lo.x(), 160 - 105.6, 1e-9);
  EXPECT_NEAR(lo.y(), 120 + 105.6, 1e-9);
  EXPECT_NEAR(hi.x(), 160 + 105.6, 1e-9);
  EXPECT_NEAR(hi.y(), 120 - 105.6, 1e-9);
}

TEST(PointLight, MarkersAtTimeInterpolatesAndKeepsTheNearerSample) {
  const Take take = MakeTake();
  // Between frames 10 and 11: linear interpolation of the circle.
  const double t = 10.25 / kRate;
  const Eigen::Matrix3Xd m = MarkersAtTime(take, t);
  const Eigen::Vector3d expected = 0.75 * CircleAt(10 / kRate) + 0.25 * CircleAt(11 / kRate);
  EXPECT_LT((m.col(3) - expected).norm(), 1e-4);
  EXPECT_LT((m.col(2) - kProbe).norm(), 1e-5);
  // "half" is seen up to frame 137: near 137 shown, near 138 missing.
  const int64_t last = kFrames / 2 - 1;
  EXPECT_TRUE(MarkersAtTime(take, (last + 0.4) / kRate).col(4).allFinite());
  EXPECT_FALSE(MarkersAtTime(take, (last + 0.6) / kRate).col(4).allFinite());
  EXPECT_FALSE(MarkersAtTime(take, 2.0).col(4).allFinite());
  // Past the end: the last frame.
  EXPECT_LT((MarkersAtTime(take, 100.0).col(3) - CircleAt((kFrames - 1) / kRate)).norm(), 1e-4);
}

TEST(PointLight, RenderedFrameHasDotsWhereTheViewProjects) {
  const Take take = MakeTake();
  const PointLightOptions o = SmallOptions();
  const PointLightView v = FitPointLightView(take, nullptr, o);
  const PointLightImage img = RenderPointLightFrame(take, nullptr, v, 0, o);
  ASSERT_EQ(img.width, 320);
  ASSERT_EQ(img.height, 240);
  ASSERT_EQ(img.bgr.size(), 320u * 240u * 3u);
  const cv::Mat mat(img.height, img.width, CV_8UC3, const_cast<uint8_t*>(img.bgr.data()));
  const cv::Point2d c = BrightCentroid(mat, 212.8, 141.12, 6);
  EXPECT_NEAR(c.x, 212.8, 0.5);
  EXPECT_NEAR(c.y, 141.12, 0.5);
  // White dot (no marker set), black background 10 px away.
  const uint8_t* centre = img.At(213, 141);
  EXPECT_GT(centre[0], 200);
  EXPECT_GT(centre[1], 200);
  EXPECT_GT(centre[2], 200);
  const uint8_t* off = img.At(223, 141);
  EXPECT_EQ(off[0] + off[1] + off[2], 0);
}

TEST(PointLight, SticksAndRoleColoursFromTheMarkerSet) {
  const Take take = MakeTake();
  MarkerSet set;
  set.name = "test";
  set.fingertips = {"probe"};  // hand: yellow
  set.sticks = {{"corner_lo", "probe"}, {"probe", "no_such_marker"}};
  const PointLightOptions o = SmallOptions();
  const PointLightView v = FitPointLightView(take, &set, o);
  EXPECT_EQ(v.how, "lab axes (x right, z up)");  // no head, face or throat markers
  const PointLightImage img = RenderPointLightFrame(take, &set, v, 0, o);
  const uint8_t* tip = img.At(213, 141);
  EXPECT_LT(tip[0], 40);   // blue
  EXPECT_GT(tip[1], 180);  // green
  EXPECT_GT(tip[2], 230);  // red
  // The stick's midpoint is grey.
  const Eigen::Vector2d mid = 0.5 * (v.Project({-100, 5, -100}) + v.Project(kProbe));
  const uint8_t* s = img.At(static_cast<int>(std::lround(mid.x())), static_cast<int>(std::lround(mid.y())));
  EXPECT_GT(s[0], 50);
  EXPECT_EQ(s[0], s[1]);
  EXPECT_EQ(s[1], s[2]);
}

// A cuer facing -y: head cluster around the head, face markers in a plane
// in front, a throat marker below. The view must be x right, z up; the same
// take turned by 90° about z must turn the view with it.
TEST(PointLight, FrontViewFromTheMarkerSetRoles) {
  MarkerSet set;
  set.name = "roles";
  set.head_cluster = {"h1", "h2", "h3"};
  set.face = {"f1", "f2", "f3", "f4"};
  set.throat = {ThroatMarker{"t1", std::nullopt}};
  const std::vector<Eigen::Vector3d> pos = {
      {-80, 10, 1300},  {80, 10, 1300},  {0, 60, 1330},                   // head cluster
      {-30, -90, 1200}, {30, -90, 1200}, {0, -90, 1170}, {0, -90, 1230},  // face, plane y = -90
  };
  Eigen::Vector3d top = Eigen::Vector3d::Zero();
  for (const auto& p : pos) top += p;
  top /= static_cast<double>(pos.size());
  const Eigen::Vector3d throat(top.x(), top.y(), 1080);  // straight below: up = +z
  for (const double turn_deg : {0.0, 90.0}) {
    const Eigen::Matrix3d r = Eigen::AngleAxisd(turn_deg * std::numbers::pi / 180, Eigen::Vector3d::UnitZ()).matrix();
    Take t;
    t.name = "cuer";
    t.rate_hz = 100;
    t.marker_names = {"h1", "h2", "h3", "f1", "f2", "f3", "f4", "t1"};
    t.markers.Resize(10, 8);
    for (int64_t f = 0; f < 10; ++f) {
      for (size_t j = 0; j < pos.size(); ++j) Set(&t, f, static_cast<int64_t>(j), r * pos[j]);
      Set(&t, f, 7, r * throat);
    }
    const PointLightView v = FitPointLightView(t, &set, SmallOptions());
    EXPECT_EQ(v.how.rfind("marker set 'roles'", 0), 0u) << v.how;
    EXPECT_LT((v.up - Eigen::Vector3d::UnitZ()).norm(), 1e-9) << turn_deg;
    EXPECT_LT((v.right - r * Eigen::Vector3d::UnitX()).norm(), 1e-9) << turn_deg << ": " << v.right.transpose();
    // The face is above the throat on the screen (y down).
    EXPECT_LT(v.Project(r * pos[5]).y(), v.Project(r * throat).y());
    // No frame sees every marker (h1 on even frames only, f1 on odd ones) and a
    // second throat marker is never seen: each marker's own mean gives the same view.
    MarkerSet set2 = set;
    set2.throat.push_back(ThroatMarker{"t2", std::nullopt});
    Take gaps = t;
    gaps.marker_names.push_back("t2");
    gaps.markers.Resize(10, 9);
    for (int64_t f = 0; f < 10; ++f) {
      for (int64_t j = 0; j < 8; ++j) {
        if ((j == 0 && f % 2 == 1) || (j == 3 && f % 2 == 0)) continue;
        std::copy(t.markers.at(f, j), t.markers.at(f, j) + 3, gaps.markers.at(f, j));
      }
    }
    const PointLightView g = FitPointLightView(gaps, &set2, SmallOptions());
    EXPECT_EQ(g.how.rfind("marker set 'roles'", 0), 0u) << g.how;
    EXPECT_LT((g.up - v.up).norm(), 1e-6) << turn_deg;
    EXPECT_LT((g.right - v.right).norm(), 1e-6) << turn_deg;
  }
}

TEST(PointLight, VideoReadsBackWithTheRightFramesSizeAndDots) {
  testing::TempDir dir;
  const Take take = MakeTake();
  const PointLightOptions o = SmallOptions();
  const fs::path out = dir / "take.mp4";
  std::vector<double> fractions;
  Progress progress([&](const std::string&, double f) { fractions.push_back(f); });
  const PointLightResult r = WritePointLightVideo(take, nullptr, out.string(), o, "", &progress);
  EXPECT_EQ(r.frames, std::llround(take.duration_s() * o.fps));
  EXPECT_EQ(r.frames, 69);
  EXPECT_EQ(r.width, 320);
  EXPECT_EQ(r.height, 240);
  EXPECT_EQ(r.markers, 5);
  EXPECT_EQ(r.codec, "h264");  // H.264 (Debian's libavcodec has libx264), which browsers play
  EXPECT_FALSE(r.audio);
  EXPECT_TRUE(r.warnings.empty());
  ASSERT_FALSE(fractions.empty());
  EXPECT_EQ(fractions.back(), 1.0);
  EXPECT_EQ(FilesIn(dir.path()), std::vector<std::string>{"take.mp4"});  // no temporary left

  double fps = 0;
  int reported = 0;
  const std::vector<cv::Mat> frames = ReadAll(out, &fps, &reported);
  const double expected = take.duration_s() * o.fps;  // 69
  EXPECT_LE(std::abs(static_cast<double>(frames.size()) - expected), 1.0) << frames.size();
  EXPECT_LE(std::abs(reported - expected), 1.0) << reported;
  EXPECT_NEAR(fps, 30.0, 1e-6);
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(frames[0].cols, 320);
  EXPECT_EQ(frames[0].rows, 240);
  // The fixed probe in every 10th frame, the moving circle marker where the
  // view projects its position at that frame's time (k / fps).
  for (size_t k = 0; k < frames.size(); k += 10) {
    const cv::Point2d c = BrightCentroid(frames[k], 212.8, 141.12, 6);
    EXPECT_NEAR(c.x, 212.8, 1.0) << "frame " << k;
    EXPECT_NEAR(c.y, 141.12, 1.0) << "frame " << k;
    const Eigen::Vector2d q = r.view.Project(CircleAt(static_cast<double>(k) / o.fps));
    const cv::Point2d m = BrightCentroid(frames[k], q.x(), q.y(), 6);
    EXPECT_NEAR(m.x, q.x(), 1.0) << "frame " << k;
    EXPECT_NEAR(m.y, q.y(), 1.0) << "frame " << k;
  }
  // "half" (0, 0, -60) is drawn in the first half only.
  const Eigen::Vector2d h = r.view.Project({0, 0, -60});
  EXPECT_GE(BrightCentroid(frames[5], h.x(), h.y(), 4).x, 0);
  EXPECT_LT(BrightCentroid(frames[60], h.x(), h.y(), 4).x, 0);
}

TEST(PointLight, OtherSizeAndRate) {
  testing::TempDir dir;
  const Take take = MakeTake(250);  // 2.0833 s
  PointLightOptions o;
  o.fps = 24;
  o.width = 200;
  o.height = 100;
  const fs::path out = dir / "small.mp4";
  const PointLightResult r = WritePointLightVideo(take, nullptr, out.string(), o);
  EXPECT_EQ(r.frames, 50);
  double fps = 0;
  int reported = 0;
  const std::vector<cv::Mat> frames = ReadAll(out, &fps, &reported);
  EXPECT_LE(std::abs(static_cast<double>(frames.size()) - 50.0), 1.0);
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(frames[0].cols, 200);
  EXPECT_EQ(frames[0].rows, 100);
}

TEST(PointLight, CancelledRenderLeavesNoFile) {
  testing::TempDir dir;
  const Take take = MakeTake();
  Progress* self = nullptr;
  int updates = 0;
  Progress progress([&](const std::string&, double f) {
    ++updates;
    if (f > 0.3) self->Cancel();
  });
  self = &progress;
  EXPECT_THROW(WritePointLightVideo(take, nullptr, (dir / "c.mp4").string(), SmallOptions(), "", &progress), Cancelled);
  EXPECT_GT(updates, 2);
  EXPECT_TRUE(FilesIn(dir.path()).empty()) << Joined(FilesIn(dir.path()));
}

TEST(PointLight, FailingMuxLeavesNoFile) {
  testing::TempDir dir;
  const Take take = MakeTake();
  WriteSilence(dir / "audio.wav", 2.3);
  PointLightOptions o = SmallOptions();
  o.ffmpeg = "/bin/false";  // found, runs, fails
  try {
    WritePointLightVideo(take, nullptr, (dir / "f.mp4").string(), o, (dir / "audio.wav").string());
    ADD_FAILURE() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("exit status 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("f.mp4"), std::string::npos) << e.what();
  }
  EXPECT_EQ(FilesIn(dir.path()), std::vector<std::string>{"audio.wav"}) << Joined(FilesIn(dir.path()));
}

TEST(PointLight, UnwritableOutputIsAnIoErrorAndLeavesNoFile) {
  testing::TempDir dir;
  const Take take = MakeTake();
  EXPECT_THROW(WritePointLightVideo(take, nullptr, (dir / "no_folder" / "x.mp4").string(), SmallOptions()), IoError);
  fs::create_directory(dir / "is_a_folder.mp4");
  EXPECT_THROW(WritePointLightVideo(take, nullptr, (dir / "is_a_folder.mp4").string(), SmallOptions()), IoError);
  EXPECT_THROW(
      WritePointLightVideo(take, nullptr, (dir / "x.mp4").string(), SmallOptions(), (dir / "none.wav").string()),
      IoError);
  EXPECT_EQ(FilesIn(dir.path()), std::vector<std::string>{"is_a_folder.mp4"});
}

TEST(PointLight, MissingFfmpegGivesASilentVideoAndAWarning) {
  testing::TempDir dir;
  const Take take = MakeTake();
  WriteSilence(dir / "audio.wav", 2.0);  // shorter than the take's 2.3 s: the video follows the audio
  PointLightOptions o = SmallOptions();
  o.ffmpeg = "/nonexistent/ffmpeg";
  const PointLightResult r =
      WritePointLightVideo(take, nullptr, (dir / "s.mp4").string(), o, (dir / "audio.wav").string());
  EXPECT_FALSE(r.audio);
  EXPECT_EQ(r.frames, 60);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("ffmpeg not found"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("silent"), std::string::npos) << r.warnings[0];
  double fps = 0;
  int reported = 0;
  EXPECT_EQ(ReadAll(dir / "s.mp4", &fps, &reported).size(), 60u);
  EXPECT_EQ(reported, 60);
}

// Audio longer than the take: the last marker frame is held to the end.
TEST(PointLight, LongerAudioHoldsTheLastFrame) {
  testing::TempDir dir;
  const Take take = MakeTake();
  WriteSilence(dir / "audio.wav", 3.0);
  PointLightOptions o = SmallOptions();
  o.ffmpeg = "/nonexistent/ffmpeg";
  const PointLightResult r =
      WritePointLightVideo(take, nullptr, (dir / "l.mp4").string(), o, (dir / "audio.wav").string());
  EXPECT_EQ(r.frames, 90);
  double fps = 0;
  int reported = 0;
  const std::vector<cv::Mat> frames = ReadAll(dir / "l.mp4", &fps, &reported);
  ASSERT_EQ(frames.size(), 90u);
  const Eigen::Vector2d q = r.view.Project(CircleAt((kFrames - 1) / kRate));
  const cv::Point2d m = BrightCentroid(frames.back(), q.x(), q.y(), 6);
  EXPECT_NEAR(m.x, q.x(), 1.0);
  EXPECT_NEAR(m.y, q.y(), 1.0);
}

TEST(PointLight, DamagedWavIsAnErrorAndLeavesNoFile) {
  testing::TempDir dir;
  WriteFile(dir / "audio.wav", "not really a wav");
  PointLightOptions o = SmallOptions();
  o.ffmpeg = "/nonexistent/ffmpeg";
  EXPECT_THROW(WritePointLightVideo(MakeTake(), nullptr, (dir / "d.mp4").string(), o, (dir / "audio.wav").string()),
               Error);
  EXPECT_EQ(FilesIn(dir.path()), std::vector<std::string>{"audio.wav"});
}

// A stand-in for ffmpeg (not installed here): copies the video input to the
// output and records its arguments, so the muxing path and its command line
// are checked without ffmpeg.
TEST(PointLight, MuxRunsFfmpegWithTheDocumentedArguments) {
  testing::TempDir dir;
  const Take take = MakeTake();
  WriteSilence(dir / "audio.wav", 2.3);
  const fs::path fake = dir / "fake-ffmpeg";
  WriteFile(fake, "#!/bin/sh\necho \"$@\" > \"" + (dir / "args.txt").string() + "\"\ncp \"$5\" \"${18}\"\n");
  fs::permissions(fake, fs::perms::owner_all);
  PointLightOptions o = SmallOptions();
  o.ffmpeg = fake.string();
  const PointLightResult r =
      WritePointLightVideo(take, nullptr, (dir / "a.mp4").string(), o, (dir / "audio.wav").string());
  EXPECT_TRUE(r.audio);
  EXPECT_TRUE(r.warnings.empty());
  std::ifstream in(dir / "args.txt");
  std::string args;
  std::getline(in, args);
  EXPECT_NE(args.find("-y -v error -i "), std::string::npos) << args;
  EXPECT_NE(args.find("-map 0:v:0 -map 1:a:0 -c:v copy -c:a aac -b:a 128k"), std::string::npos) << args;
  std::vector<std::string> files = FilesIn(dir.path());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"a.mp4", "args.txt", "audio.wav", "fake-ffmpeg"}));
  double fps = 0;
  int reported = 0;
  EXPECT_EQ(ReadAll(dir / "a.mp4", &fps, &reported).size(), 69u);
}

TEST(PointLight, BadOptionsAreInvalidInput) {
  testing::TempDir dir;
  const Take take = MakeTake();
  const std::string out = (dir / "b.mp4").string();
  for (double fps : {0.0, -5.0, std::nan("")}) {
    PointLightOptions o = SmallOptions();
    o.fps = fps;
    EXPECT_THROW(WritePointLightVideo(take, nullptr, out, o), InvalidInput) << fps;
  }
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{10, 240}, {320, 8}, {0, 0}, {321, 240}, {8192, 240}}) {
    PointLightOptions o = SmallOptions();
    o.width = w;
    o.height = h;
    EXPECT_THROW(WritePointLightVideo(take, nullptr, out, o), InvalidInput) << w << "x" << h;
    EXPECT_FALSE(o.Check().empty());
  }
  EXPECT_EQ(SmallOptions().Check(), "");
  EXPECT_TRUE(FilesIn(dir.path()).empty());
}

TEST(PointLight, TakeWithoutVisibleSamplesIsInvalidInputNamingIt) {
  testing::TempDir dir;
  Take take = MakeTake(20);
  take.name = "all_gone";
  for (int64_t f = 0; f < take.frames(); ++f) {
    for (int64_t j = 0; j < take.markers.markers(); ++j) take.markers.SetMissing(f, j);
  }
  const std::string out = (dir / "n.mp4").string();
  try {
    WritePointLightVideo(take, nullptr, out, SmallOptions());
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("all_gone"), std::string::npos) << e.what();
  }
  Take empty;
  empty.name = "no_markers";
  empty.rate_hz = 120;
  EXPECT_THROW(WritePointLightVideo(empty, nullptr, out, SmallOptions()), InvalidInput);
  Take no_rate = MakeTake(20);
  no_rate.rate_hz = 0;
  EXPECT_THROW(WritePointLightVideo(no_rate, nullptr, out, SmallOptions()), InvalidInput);
  EXPECT_TRUE(FilesIn(dir.path()).empty());
}

TEST(PointLight, SavesOneFrameAsPng) {
  testing::TempDir dir;
  const Take take = MakeTake();
  const fs::path png = dir / "frame.png";
  SavePointLightFrame(take, nullptr, 3, png.string(), SmallOptions());
  const cv::Mat m = cv::imread(png.string());
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(m.cols, 320);
  EXPECT_EQ(m.rows, 240);
  const cv::Point2d c = BrightCentroid(m, 212.8, 141.12, 6);
  EXPECT_NEAR(c.x, 212.8, 0.5);
}

TEST(PointLight, FindProgram) {
  EXPECT_EQ(FindProgram("/bin/sh"), "/bin/sh");
  EXPECT_EQ(FindProgram("/nonexistent/ffmpeg"), "");
  EXPECT_EQ(FindProgram(""), "");
  EXPECT_FALSE(FindProgram("sh").empty());
  EXPECT_EQ(FindProgram("csw-no-such-program-anywhere"), "");
}

}  // namespace
}  // namespace csw

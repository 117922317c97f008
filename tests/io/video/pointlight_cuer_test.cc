// A point-light video of a virtual-cuer sentence (datasets/virtual_cuer.h)
// with its marker set and audio: the front view from the marker set's roles,
// the video's length against the audio's, the hand drawn. With
// CSW_VIDEO_DOC_FRAME=FILE.png in the environment it also writes the frame
// shown in docs/video.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "datasets/virtual_cuer.h"
#include "io/formats/wav.h"
#include "io/video/pointlight.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;

const SimulationResult& Sentence() {
  static const SimulationResult r = [] {
    VirtualCuer cuer{SimulateOptions()};
    return cuer.SimulateSentence("pointlight_cuer", ShippedSentences().at(0));
  }();
  return r;
}

MarkerSet CuerSet() {
  VirtualCuer cuer{SimulateOptions()};
  return cuer.MakeMarkerSet();
}

// The frame nearest the middle of the first key's shape target: the hand at the face.
int64_t DocFrame(const SimulationResult& s, double fps) {
  const double t = s.keys.size() > 1 ? s.keys[1].timing.shape_target_s : 0.5 * s.take.duration_s();
  return std::llround(t * fps);
}

TEST(PointLightCuer, FrontViewFromTheVirtualCuersMarkerSet) {
  const SimulationResult& s = Sentence();
  const MarkerSet set = CuerSet();
  PointLightOptions o;
  const PointLightView v = FitPointLightView(s.take, &set, o);
  EXPECT_EQ(v.how.rfind("marker set", 0), 0u) << v.how;
  // The virtual cuer stands upright in the lab (HeadReference: z up).
  EXPECT_GT(v.up.z(), 0.95) << v.up.transpose();
  EXPECT_NEAR(v.right.dot(v.up), 0, 1e-9);
  // Its face markers are in front (+y) of its head cluster, so the screen's
  // x axis, up × forward, is the lab's -x.
  EXPECT_LT(v.right.x(), -0.99) << v.right.transpose();
  EXPECT_NEAR(v.right.norm(), 1, 1e-9);
  // The face is drawn above the throat, as seen at the middle of the take.
  const Eigen::Matrix3Xd m = MarkersAtTime(s.take, 0.5 * s.take.duration_s());
  Eigen::Vector2d face = Eigen::Vector2d::Zero(), throat = Eigen::Vector2d::Zero();
  int nf = 0, nt = 0;
  for (const std::string& name : set.face) {
    const int64_t j = s.take.MarkerIndex(name);
    if (j >= 0 && m.col(j).allFinite()) face += v.Project(m.col(j)), ++nf;
  }
  for (const ThroatMarker& t : set.throat) {
    const int64_t j = s.take.MarkerIndex(t.marker);
    if (j >= 0 && m.col(j).allFinite()) throat += v.Project(m.col(j)), ++nt;
  }
  ASSERT_GT(nf, 3);
  ASSERT_GT(nt, 0);
  EXPECT_LT(face.y() / nf + 50, throat.y() / nt);
}

TEST(PointLightCuer, VideoLastsAsLongAsTheAudio) {
  const SimulationResult& s = Sentence();
  ASSERT_GT(s.take.audio.duration_s(), 0);
  testing::TempDir dir;
  const std::string wav = (dir / "take.wav").string();
  WriteWav(wav, s.take.audio);
  const MarkerSet set = CuerSet();
  PointLightOptions o;
  o.ffmpeg = "/nonexistent/ffmpeg";  // ffmpeg is not needed here: the silent video and a warning
  const std::string out = (dir / "take.mp4").string();
  const PointLightResult r = WritePointLightVideo(s.take, &set, out, o, wav);
  EXPECT_FALSE(r.audio);
  EXPECT_EQ(r.warnings.size(), 1u);
  EXPECT_GT(r.sticks, 20);

  cv::VideoCapture cap(out, cv::CAP_FFMPEG);
  ASSERT_TRUE(cap.isOpened());
  int64_t n = 0;
  cv::Mat m, doc;
  const int64_t doc_frame = DocFrame(s, o.fps);
  double hand_pixels = 0;
  while (cap.read(m)) {
    if (n == doc_frame) doc = m.clone();
    ++n;
  }
  const double audio_frames = s.take.audio.duration_s() * o.fps;
  std::printf("take %.3f s (%lld frames at %.0f Hz), audio %.3f s: %lld video frames at %.0f/s, audio x fps = %.2f\n",
              s.take.duration_s(), static_cast<long long>(s.take.frames()), s.take.rate_hz, s.take.audio.duration_s(),
              static_cast<long long>(n), o.fps, audio_frames);
  EXPECT_LE(std::abs(static_cast<double>(n) - audio_frames), 1.0);
  EXPECT_EQ(n, r.frames);
  EXPECT_EQ(cap.get(cv::CAP_PROP_FRAME_WIDTH), 640);
  EXPECT_EQ(cap.get(cv::CAP_PROP_FRAME_HEIGHT), 720);
  // The hand's yellow dots (BGR 0, 220, 255) are in the picture.
  ASSERT_FALSE(doc.empty());
  for (int y = 0; y < doc.rows; ++y) {
    for (int x = 0; x < doc.cols; ++x) {
      const cv::Vec3b p = doc.at<cv::Vec3b>(y, x);
      if (p[0] < 90 && p[1] > 150 && p[2] > 200) ++hand_pixels;
    }
  }
  EXPECT_GT(hand_pixels, 50);
}

TEST(PointLightCuer, WritesTheDocumentationFrameWhenAsked) {
  const char* png = std::getenv("CSW_VIDEO_DOC_FRAME");
  if (!png || !*png) GTEST_SKIP() << "set CSW_VIDEO_DOC_FRAME=FILE.png to write the frame of docs/video.md";
  const SimulationResult& s = Sentence();
  const MarkerSet set = CuerSet();
  PointLightOptions o;
  SavePointLightFrame(s.take, &set, DocFrame(s, o.fps), png, o);
  EXPECT_TRUE(fs::exists(png));
}

}  // namespace
}  // namespace csw

// csw video (workbench/jobs/video_job.h): option checks, the size parser, the
// exact text output, and the job end to end on a small C3D take through the
// dlopen'ed module libcsw_video.so.
#include "workbench/jobs/video_job.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "io/c3d/c3d.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/import_job.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

VideoOptions Valid() {
  VideoOptions o;
  o.input = "take.c3d";
  o.output = "out.mp4";
  return o;
}

TEST(VideoOptionsCheck, AcceptsTheDefaults) {
  EXPECT_EQ(Valid().Check(), "");
  VideoOptions o = Valid();
  o.input = "corpus.h5";
  o.take = "t1";
  o.fps = 60;
  o.size = "1280x720";
  o.audio = "a.wav";
  o.png = "f.png";
  EXPECT_EQ(o.Check(), "");
}

TEST(VideoOptionsCheck, RejectsEachBadRequestWithItsReason) {
  auto why = [](auto change) {
    VideoOptions o = Valid();
    change(o);
    return o.Check();
  };
  EXPECT_EQ(why([](VideoOptions& o) { o.input.clear(); }), "no input given: a C3D file or a corpus (.h5) with --take");
  EXPECT_EQ(why([](VideoOptions& o) { o.input = "t.trc"; }),
            "csw video reads a C3D file or a corpus (.h5), not 't.trc'");
  EXPECT_EQ(why([](VideoOptions& o) { o.input = "c.h5"; }), "a corpus needs --take NAME");
  EXPECT_EQ(why([](VideoOptions& o) { o.take = "x"; }), "--take selects a take of a corpus; a C3D file is one take");
  EXPECT_EQ(why([](VideoOptions& o) { o.output.clear(); }), "-o OUT.mp4 is required");
  EXPECT_EQ(why([](VideoOptions& o) { o.output = "v.avi"; }), "-o must name an .mp4 file, not 'v.avi'");
  EXPECT_EQ(why([](VideoOptions& o) { o.fps = 0; }), "--fps must be in (0, 240]");
  EXPECT_EQ(why([](VideoOptions& o) { o.fps = -25; }), "--fps must be in (0, 240]");
  EXPECT_EQ(why([](VideoOptions& o) { o.size = "640"; }),
            "--size must be WIDTHxHEIGHT in pixels (e.g. 640x720), not '640'");
  EXPECT_EQ(why([](VideoOptions& o) { o.size = "32x32"; }),
            "--size must be even and 64..4096 pixels each way, not '32x32'");
  EXPECT_EQ(why([](VideoOptions& o) { o.size = "641x480"; }),
            "--size must be even and 64..4096 pixels each way, not '641x480'");
  EXPECT_EQ(why([](VideoOptions& o) { o.audio = "a.mp3"; }), "--audio must name a .wav file, not 'a.mp3'");
  EXPECT_EQ(why([](VideoOptions& o) { o.png = "f.jpg"; }), "--png must name a .png file, not 'f.jpg'");
  EXPECT_EQ(why([](VideoOptions& o) { o.png_time_s = -1; }), "--png-time must be >= 0 seconds");
}

TEST(VideoSize, Parses) {
  int w = 0, h = 0;
  EXPECT_TRUE(ParseVideoSize("640x720", &w, &h));
  EXPECT_EQ(w, 640);
  EXPECT_EQ(h, 720);
  EXPECT_TRUE(ParseVideoSize("1920X1080", &w, &h));
  EXPECT_EQ(w, 1920);
  EXPECT_EQ(h, 1080);
  for (const char* bad : {"", "x", "640x", "x480", "640x480x2", "-640x480", "64 0x480", "9999999x480", "axb"}) {
    EXPECT_FALSE(ParseVideoSize(bad, &w, &h)) << bad;
  }
}

TEST(VideoText, IsExact) {
  const json r = json::parse(R"J({"input": "t.c3d", "take": "t", "output": "t.mp4", "frames": 58, "fps": 25.0,
      "duration_s": 2.32, "width": 640, "height": 720, "markers": 5, "sticks": 2, "markerset": "none",
      "view": "lab axes (x right, z up)", "audio": {"wav": "t.wav", "muxed": false},
      "png": {"path": "f.png", "frame": 12},
      "warnings": ["ffmpeg not found (ffmpeg): the video is silent (install Debian's ffmpeg to mux the audio)"]})J");
  EXPECT_EQ(VideoText(r),
            "take t: 58 frames at 25.00/s (2.320 s), 640x720, 5 markers, 2 sticks\n"
            "  view: lab axes (x right, z up)\n"
            "  warning: ffmpeg not found (ffmpeg): the video is silent (install Debian's ffmpeg to mux the audio)\n"
            "wrote t.mp4 (silent)\n"
            "wrote f.png (frame 12)\n");
  json muxed = r;
  muxed["audio"]["muxed"] = true;
  muxed["png"] = nullptr;
  muxed["warnings"] = json::array();
  EXPECT_EQ(VideoText(muxed),
            "take t: 58 frames at 25.00/s (2.320 s), 640x720, 5 markers, 2 sticks\n"
            "  view: lab axes (x right, z up)\n"
            "wrote t.mp4 with the audio of t.wav\n");
}

// Three markers on a line, 1.5 s at 100 Hz.
Take SmallTake() {
  Take t;
  t.name = "small";
  t.rate_hz = 100;
  t.marker_names = {"a", "b", "c"};
  t.markers.Resize(150, 3);
  for (int64_t f = 0; f < 150; ++f) {
    for (int64_t j = 0; j < 3; ++j) {
      float* p = t.markers.at(f, j);
      p[0] = static_cast<float>(100 * j + f);
      p[1] = 0;
      p[2] = static_cast<float>(1000 + 50 * j);
    }
  }
  return t;
}

TEST(VideoJob, WritesTheVideoAndAFrameOfAC3dTake) {
  testing::TempDir dir;
  WriteC3d((dir / "small.c3d").string(), SmallTake());
  VideoOptions o;
  o.input = (dir / "small.c3d").string();
  o.output = (dir / "small.mp4").string();
  o.size = "320x240";
  o.png = (dir / "f.png").string();
  o.png_time_s = 0.5;
  Progress progress;
  const json r = Video(o, progress);
  EXPECT_EQ(r.at("take"), "small");
  EXPECT_EQ(r.at("frames"), 38);  // round(1.5 s × 25)
  EXPECT_EQ(r.at("width"), 320);
  EXPECT_EQ(r.at("height"), 240);
  EXPECT_EQ(r.at("markers"), 3);
  EXPECT_EQ(r.at("markerset"), "none");
  EXPECT_EQ(r.at("view"), "lab axes (x right, z up)");
  EXPECT_EQ(r.at("audio").at("muxed"), false);
  EXPECT_EQ(r.at("png").at("frame"), 13);  // round(0.5 × 25) = 12.5 -> 13
  EXPECT_TRUE(r.at("warnings").empty());
  EXPECT_GT(fs::file_size(dir / "small.mp4"), 1000u);
  EXPECT_GT(fs::file_size(dir / "f.png"), 100u);
}

TEST(VideoJob, ModuleErrorsKeepTheirKind) {
  testing::TempDir dir;
  Take t = SmallTake();
  WriteC3d((dir / "small.c3d").string(), t);
  VideoOptions o;
  o.input = (dir / "small.c3d").string();
  o.output = (dir / "no_folder" / "x.mp4").string();
  Progress progress;
  try {
    Video(o, progress);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x.mp4"), std::string::npos) << e.what();
  }
  o.output = (dir / "c.mp4").string();
  // Cancelled inside the module (while rendering): the same exception here.
  Progress* self = nullptr;
  Progress cancelling([&](const std::string& stage, double f) {
    if (stage == "rendering video" && f > 0.2) self->Cancel();
  });
  self = &cancelling;
  EXPECT_THROW(Video(o, cancelling), Cancelled);
  o.fps = 0;
  EXPECT_THROW(Video(o, progress), UsageError);
  EXPECT_FALSE(fs::exists(dir / "c.mp4"));
}

TEST(VideoJob, ReadsACorpusTake) {
  testing::TempDir dir;
  WriteC3d((dir / "small.c3d").string(), SmallTake());
  ImportOptions io;
  io.files = {(dir / "small.c3d").string()};
  io.corpus = (dir / "c.h5").string();
  Progress progress;
  Import(io, progress);
  VideoOptions o;
  o.input = io.corpus;
  o.take = "small";
  o.output = (dir / "small.mp4").string();
  o.fps = 30;
  const json r = Video(o, progress);
  EXPECT_EQ(r.at("take"), "small");
  EXPECT_EQ(r.at("frames"), 45);         // 1.5 s × 30
  EXPECT_EQ(r.at("markerset"), "none");  // imported without one
  EXPECT_TRUE(fs::exists(dir / "small.mp4"));
  o.take = "absent";
  try {
    Video(o, progress);
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("no take 'absent'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace csw::jobs

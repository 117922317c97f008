#pragma once
// Point-light video of a take's markers (issue 15 §5): an MP4 (H.264, or
// MPEG-4 Part 2 (mp4v) when the H.264 encoder is missing;
// OpenCV's videoio) of the markers seen from the front, as white and coloured
// dots on black, with the marker set's sticks, a frame counter and the time.
// docs/video.md describes the picture and the choices below.
//
// View ("front"): with a marker set whose head cluster, face and throat
// markers the take has, the view is the cuer's own: up = from the throat
// markers' centroid to the head cluster and face markers' centroid;
// forward = the normal of the face markers' least-squares plane (their
// smallest principal axis), made orthogonal to up and pointing from the head
// cluster's centroid towards the face's (the head cluster sits around the
// head, the lips and jaw in front); the screen's x axis is up × forward (the
// cuer's left, as a camera facing the cuer sees it), its y axis up. Centroids
// and plane are of the markers' mean positions over the frames where all are
// seen (when no frame sees them all, each marker's own mean; markers the take
// never sees are left out). Otherwise the lab's axes: x to the right, z up
// (the C3D convention).
//
// Scale: one for the whole video, fitted so that every visible sample of
// every frame fits inside the picture, less a margin.
//
// Frames: round(duration × fps) frames (at least 1), frame k showing time
// k / fps: each marker linearly interpolated between the two take frames
// around that time (the nearer one when the other is missing; missing when
// the nearer one is; the last frame held after the take's end). duration is
// the WAV's when one is given (the sound track sets the length of a video
// with sound; markers past the audio's end are not shown), else the take's
// (frames / rate_hz), so the video lasts as long as its audio, or its take,
// within half a video frame.
//
// Audio: given a WAV, the video is muxed with it by ffmpeg (a subprocess,
// `ffmpeg -y -v error -i VIDEO -i WAV -map 0:v:0 -map 1:a:0 -c:v copy
// -c:a aac -b:a 128k OUT`) when the program is found; otherwise the video is
// silent and the result carries a warning. ffmpeg's failure is an IoError
// quoting its message.
//
// The file is written under a temporary name in the output's folder and
// renamed at the end: a failed or cancelled render leaves no partial file.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/markerset.h"
#include "core/progress.h"
#include "core/take.h"

namespace csw {

struct PointLightOptions {
  double fps = 25;
  int width = 640;
  int height = 720;
  bool sticks = true;             // draw the marker set's sticks
  int dot_radius_px = 0;          // 0 = max(2, round(min(width, height) / 180))
  double margin = 0.06;           // fraction of the picture kept free on each side
  std::string ffmpeg = "ffmpeg";  // the muxing program: a path, or a name looked up on PATH
  std::string Check() const;      // "" or the reason
};

// The front view and the pixel mapping of a video.
struct PointLightView {
  Eigen::Vector3d right = Eigen::Vector3d::UnitX();  // lab direction of the screen's x axis (unit)
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();     // lab direction of the screen's y axis (unit, ⟂ right)
  std::string how;                                   // "marker set (…)" or "lab axes (x right, z up)"
  double scale_px_per_mm = 1;
  Eigen::Vector2d center_mm = Eigen::Vector2d::Zero();  // (right, up) coordinates shown at the picture's centre
  int width = 0, height = 0;
  // Pixel coordinates (x to the right, y down) of a lab point.
  Eigen::Vector2d Project(const Eigen::Vector3d& p) const;
};

// The view of a take (set may be null: lab axes), scale fitted to all its
// visible samples. Throws InvalidInput naming the take when it has no
// visible marker sample.
PointLightView FitPointLightView(const Take& take, const MarkerSet* set, const PointLightOptions& options);

// round(duration_s × fps), at least 1.
int64_t PointLightFrameCount(double duration_s, double fps);

// 3 × markers at a time (s) of the take, as the video shows it (see above); NaN columns when missing.
Eigen::Matrix3Xd MarkersAtTime(const Take& take, double time_s);

// One picture, BGR bytes row by row (height × width × 3).
struct PointLightImage {
  int width = 0, height = 0;
  std::vector<uint8_t> bgr;
  const uint8_t* At(int x, int y) const { return &bgr[(static_cast<size_t>(y) * width + x) * 3]; }
};

// Video frame `frame` (time frame / fps) of the take; set may be null (no
// sticks, every dot white).
PointLightImage RenderPointLightFrame(const Take& take, const MarkerSet* set, const PointLightView& view, int64_t frame,
                                      const PointLightOptions& options);

struct PointLightResult {
  std::string path;
  int64_t frames = 0;
  double fps = 0;
  double duration_s = 0;  // frames / fps (≈ the WAV's duration when given, else the take's)
  int width = 0, height = 0;
  PointLightView view;
  int64_t markers = 0;
  int64_t sticks = 0;  // sticks drawn (both ends in the take)
  bool audio = false;  // muxed with the given WAV
  std::string codec;   // "h264" (fourcc avc1) or "mpeg4" (fourcc mp4v, no H.264 encoder)
  std::vector<std::string> warnings;
};

// Writes the video (see above). wav_path "" = silent without a warning.
// Throws UsageError-like InvalidInput for bad options, InvalidInput naming the
// take when it has no marker or no visible sample or no frame rate, IoError
// naming the path when the file cannot be written or ffmpeg fails, Cancelled
// from progress.
PointLightResult WritePointLightVideo(const Take& take, const MarkerSet* set, const std::string& path,
                                      const PointLightOptions& options, const std::string& wav_path = "",
                                      Progress* progress = nullptr);

// One video frame as a PNG (for documentation); its counter reads
// "frame K/total_frames" (0 = the take's count, as for a video without audio).
// Errors as above.
void SavePointLightFrame(const Take& take, const MarkerSet* set, int64_t frame, const std::string& png_path,
                         const PointLightOptions& options, int64_t total_frames = 0);

// The program a name refers to: itself when it contains '/', else the first
// executable PATH entry; "" when none.
std::string FindProgram(const std::string& name);

}  // namespace csw

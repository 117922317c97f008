#pragma once
// `csw video`: a point-light MP4 of one take's markers (docs/video.md,
// io/video/pointlight.h), drawn by the video module libcsw_video.so
// (io/video/video_api.h) loaded with dlopen on first use, so that csw does not
// link OpenCV. The module is looked for in $CSW_VIDEO_MODULE (a file; when
// set, the only place looked at), else next to the running program, in
// <program dir>/../lib/csw/, and where the build wrote it.
//
// The take comes from a C3D file, or from a corpus (.h5) with --take. The
// marker set (front view, colours, sticks) is --markerset, else the one the
// corpus remembers for the take, else none (lab axes, white dots).
#include <nlohmann/json.hpp>
#include <string>

#include "core/markerset.h"
#include "core/progress.h"
#include "core/take.h"
#include "io/video/pointlight.h"

namespace csw::jobs {

struct VideoOptions {
  std::string input;             // a C3D file or a corpus (.h5)
  std::string take;              // corpus: the take (required); C3D: must be empty
  std::string output;            // the MP4 to write
  double fps = 25;               // video frames per second
  std::string size = "640x720";  // WxH in pixels
  std::string audio;             // WAV to mux (ffmpeg); "" = silent
  std::string markerset;         // marker-set JSON; "" = the corpus's for the take, or none
  std::string ffmpeg = "ffmpeg";
  std::string png;            // also write one frame as a PNG ("" = none)
  double png_time_s = 0;      // the time of that frame
  std::string Check() const;  // "" when valid, else the reason (a usage error)
};

// "WxH" -> width, height; false when malformed.
bool ParseVideoSize(const std::string& text, int* width, int* height);

// {"input", "take", "output", "frames", "fps", "duration_s", "width", "height",
//  "markers", "sticks", "codec" ("h264" or "mpeg4"), "markerset", "view", "audio": {"wav", "muxed"}, "png",
//  "warnings": [...]}.
nlohmann::json Video(const VideoOptions& options, Progress& progress);
// The default text output.
std::string VideoText(const nlohmann::json& result);

// WritePointLightVideo (io/video/pointlight.h) through the video module, for
// the jobs that draw takes they made (csw say). Errors as Video's.
PointLightResult WriteTakeVideo(const Take& take, const MarkerSet* set, const std::string& path,
                                const PointLightOptions& options, const std::string& wav_path, Progress* progress);

}  // namespace csw::jobs

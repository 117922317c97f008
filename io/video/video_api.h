#pragma once
// The entry points of the video module (libcsw_video.so): WritePointLightVideo
// and SavePointLightFrame (pointlight.h) behind a table of plain function
// pointers, so that `csw video` loads OpenCV at run time with dlopen
// (workbench/jobs/video_job.cc) and the csw binary does not link it. Each
// function returns an error kind and message instead of throwing (exceptions
// do not cross the module boundary).
#include <string>

#include "core/markerset.h"
#include "core/progress.h"
#include "core/take.h"
#include "io/video/pointlight.h"

namespace csw::video {

inline constexpr int kVideoApiVersion = 2;

// kError: another csw::Error (a damaged WAV); kOther: anything else (an internal error).
enum class ErrorKind { kNone = 0, kInvalidInput, kIoError, kError, kCancelled, kOther };

struct VideoError {
  ErrorKind kind = ErrorKind::kNone;
  std::string message;
};

struct VideoApi {
  int version = kVideoApiVersion;
  VideoError (*write_video)(const Take& take, const MarkerSet* set, const std::string& path,
                            const PointLightOptions& options, const std::string& wav_path, Progress* progress,
                            PointLightResult* result) = nullptr;
  VideoError (*save_frame)(const Take& take, const MarkerSet* set, int64_t frame, const std::string& png_path,
                           const PointLightOptions& options, int64_t total_frames) = nullptr;
};

}  // namespace csw::video

// The module's one exported symbol.
#define CSW_VIDEO_ENTRY_POINT "csw_video_api"
extern "C" const csw::video::VideoApi* csw_video_api();

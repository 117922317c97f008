// libcsw_video.so: the point-light video functions behind video_api.h.
#include <exception>
#include <stdexcept>

#include "core/error.h"
#include "io/video/video_api.h"

namespace csw::video {
namespace {

// Runs f, turning every exception into an error kind and message.
template <typename F>
VideoError Guard(F&& f) {
  try {
    f();
    return {};
  } catch (const Cancelled& e) {
    return {ErrorKind::kCancelled, e.what()};
  } catch (const IoError& e) {
    return {ErrorKind::kIoError, e.what()};
  } catch (const InvalidInput& e) {
    return {ErrorKind::kInvalidInput, e.what()};
  } catch (const Error& e) {
    return {ErrorKind::kError, e.what()};
  } catch (const std::exception& e) {
    return {ErrorKind::kOther, e.what()};
  } catch (...) {
    return {ErrorKind::kOther, "unknown error in the video module"};
  }
}

VideoError WriteVideo(const Take& take, const MarkerSet* set, const std::string& path, const PointLightOptions& options,
                      const std::string& wav_path, Progress* progress, PointLightResult* result) {
  return Guard([&] { *result = WritePointLightVideo(take, set, path, options, wav_path, progress); });
}

VideoError SaveFrame(const Take& take, const MarkerSet* set, int64_t frame, const std::string& png_path,
                     const PointLightOptions& options, int64_t total_frames) {
  return Guard([&] { SavePointLightFrame(take, set, frame, png_path, options, total_frames); });
}

}  // namespace
}  // namespace csw::video

extern "C" __attribute__((visibility("default"))) const csw::video::VideoApi* csw_video_api() {
  static const csw::video::VideoApi api = [] {
    csw::video::VideoApi a;
    a.write_video = &csw::video::WriteVideo;
    a.save_frame = &csw::video::SaveFrame;
    return a;
  }();
  return &api;
}

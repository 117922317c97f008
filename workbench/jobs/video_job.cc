#include "workbench/jobs/video_job.h"

#include <dlfcn.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/build_paths.h"
#include "core/error.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/video/video_api.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kModuleName = "libcsw_video.so";

std::vector<std::string> Candidates() {
  if (const char* env = std::getenv("CSW_VIDEO_MODULE"); env && *env) return {env};  // the only place then
  std::vector<std::string> out;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    out.push_back((exe.parent_path() / kModuleName).string());
    out.push_back((exe.parent_path().parent_path() / "lib" / "csw" / kModuleName).string());
  }
#ifdef CSW_VIDEO_MODULE_PATH
  out.push_back(CSW_VIDEO_MODULE_PATH);
#endif
  return out;
}

const video::VideoApi* LoadApi() {
  std::string tried;
  for (const std::string& path : Candidates()) {
    std::error_code ec;
    if (!fs::exists(path, ec)) {
      tried += "\n  " + path + ": no such file";
      continue;
    }
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);  // never closed
    if (!handle) {
      const char* why = dlerror();
      tried += "\n  " + path + ": " + (why ? why : "cannot load");
      continue;
    }
    using Entry = const video::VideoApi* (*)();
    auto entry = reinterpret_cast<Entry>(dlsym(handle, CSW_VIDEO_ENTRY_POINT));
    const video::VideoApi* api = entry ? entry() : nullptr;
    if (!api || api->version != video::kVideoApiVersion) {
      tried += "\n  " + path + ": not a csw video module of this version";
      continue;
    }
    return api;
  }
  throw InvalidInput("csw video: cannot load the video module " + std::string(kModuleName) +
                     " (set CSW_VIDEO_MODULE to its path); tried:" + tried);
}

const video::VideoApi& Api() {
  static std::mutex mutex;
  static const video::VideoApi* api = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (!api) api = LoadApi();
  return *api;
}

// Rethrows the module's error as this side's exception type.
void Rethrow(const video::VideoError& e) {
  switch (e.kind) {
    case video::ErrorKind::kNone:
      return;
    case video::ErrorKind::kCancelled:
      throw Cancelled();
    case video::ErrorKind::kIoError:  // the messages already name the file
    case video::ErrorKind::kError:
      throw Error(e.message);
    case video::ErrorKind::kInvalidInput:
      throw InvalidInput(e.message);
    case video::ErrorKind::kOther:
      throw std::runtime_error(e.message);
  }
}

std::string Fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

}  // namespace

bool ParseVideoSize(const std::string& text, int* width, int* height) {
  const size_t x = text.find_first_of("xX");
  if (x == std::string::npos || x == 0 || x + 1 >= text.size()) return false;
  for (size_t i = 0; i < text.size(); ++i) {
    if (i != x && (text[i] < '0' || text[i] > '9')) return false;
  }
  if (x > 5 || text.size() - x - 1 > 5) return false;
  *width = std::stoi(text.substr(0, x));
  *height = std::stoi(text.substr(x + 1));
  return true;
}

std::string VideoOptions::Check() const {
  if (input.empty()) return "no input given: a C3D file or a corpus (.h5) with --take";
  const std::string format = FormatOf(input);
  if (format != "c3d" && format != "hdf5") return "csw video reads a C3D file or a corpus (.h5), not '" + input + "'";
  if (format == "hdf5" && take.empty()) return "a corpus needs --take NAME";
  if (format == "c3d" && !take.empty()) return "--take selects a take of a corpus; a C3D file is one take";
  if (output.empty()) return "-o OUT.mp4 is required";
  if (fs::path(output).extension() != ".mp4") return "-o must name an .mp4 file, not '" + output + "'";
  if (!(fps > 0 && fps <= 240)) return "--fps must be in (0, 240]";
  int w = 0, h = 0;
  if (!ParseVideoSize(size, &w, &h)) return "--size must be WIDTHxHEIGHT in pixels (e.g. 640x720), not '" + size + "'";
  // The ranges of PointLightOptions::Check (pointlight.cc, in the module).
  if (w < 64 || h < 64 || w > 4096 || h > 4096 || w % 2 != 0 || h % 2 != 0)
    return "--size must be even and 64..4096 pixels each way, not '" + size + "'";
  if (!audio.empty() && FormatOf(audio) != "wav") return "--audio must name a .wav file, not '" + audio + "'";
  if (!png.empty() && fs::path(png).extension() != ".png") return "--png must name a .png file, not '" + png + "'";
  if (!(png_time_s >= 0)) return "--png-time must be >= 0 seconds";
  return "";
}

json Video(const VideoOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  PointLightOptions o;
  o.fps = options.fps;
  ParseVideoSize(options.size, &o.width, &o.height);
  o.ffmpeg = options.ffmpeg;

  progress.Update("reading the take", 0.0);
  Take take;
  std::string set_json;
  std::string set_from = "none";
  if (FormatOf(options.input) == "hdf5") {
    const Corpus corpus = Corpus::Open(options.input);
    if (!corpus.HasTake(options.take)) throw InvalidInput(options.input + ": no take '" + options.take + "'");
    take = corpus.LoadTake(options.take);
    set_json = take.markerset_json;
    if (!set_json.empty()) set_from = "corpus";
  } else {
    take = ReadC3d(options.input);
  }
  std::optional<MarkerSet> set;
  if (!options.markerset.empty()) {
    set = LoadMarkerSet(options.markerset);
    set_from = options.markerset;
  } else if (!set_json.empty()) {
    set = ParseMarkerSet(set_json, options.input + ": take '" + take.name + "' marker set");
  }

  const video::VideoApi& api = Api();
  PointLightResult r;
  Rethrow(api.write_video(take, set ? &*set : nullptr, options.output, o, options.audio, &progress, &r));
  json out = {{"input", options.input}, {"take", take.name},
              {"output", r.path},       {"frames", r.frames},
              {"fps", r.fps},           {"duration_s", r.duration_s},
              {"width", r.width},       {"height", r.height},
              {"markers", r.markers},   {"sticks", r.sticks},
              {"codec", r.codec},       {"markerset", set_from},
              {"view", r.view.how},     {"audio", {{"wav", options.audio}, {"muxed", r.audio}}},
              {"png", nullptr},         {"warnings", r.warnings}};
  if (!options.png.empty()) {
    const int64_t frame =
        std::min<int64_t>(std::llround(options.png_time_s * options.fps), std::max<int64_t>(0, r.frames - 1));
    Rethrow(api.save_frame(take, set ? &*set : nullptr, frame, options.png, o, r.frames));  // the video's counter
    out["png"] = {{"path", options.png}, {"frame", frame}};
  }
  return out;
}

std::string VideoText(const json& r) {
  std::ostringstream s;
  s << "take " << r.at("take").get<std::string>() << ": " << r.at("frames").get<int64_t>() << " frames at "
    << Fixed(r.at("fps").get<double>(), 2) << "/s (" << Fixed(r.at("duration_s").get<double>(), 3) << " s), "
    << r.at("width").get<int>() << "x" << r.at("height").get<int>() << ", " << r.at("markers").get<int64_t>()
    << " markers, " << r.at("sticks").get<int64_t>() << " sticks\n";
  s << "  view: " << r.at("view").get<std::string>() << "\n";
  for (const auto& w : r.at("warnings")) s << "  warning: " << w.get<std::string>() << "\n";
  const json& a = r.at("audio");
  s << "wrote " << r.at("output").get<std::string>();
  if (a.at("muxed").get<bool>())
    s << " with the audio of " << a.at("wav").get<std::string>();
  else
    s << " (silent)";
  s << "\n";
  if (!r.at("png").is_null()) {
    s << "wrote " << r.at("png").at("path").get<std::string>() << " (frame " << r.at("png").at("frame").get<int64_t>()
      << ")\n";
  }
  return s.str();
}

PointLightResult WriteTakeVideo(const Take& take, const MarkerSet* set, const std::string& path,
                                const PointLightOptions& options, const std::string& wav_path, Progress* progress) {
  PointLightResult r;
  Rethrow(Api().write_video(take, set, path, options, wav_path, progress, &r));
  return r;
}

}  // namespace csw::jobs

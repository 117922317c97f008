#include "io/video/pointlight.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "io/formats/wav.h"

extern char** environ;

namespace csw {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::Vector3d Sample(const MarkerArray& m, int64_t f, int64_t j) {
  const float* p = m.at(f, j);
  return {p[0], p[1], p[2]};
}

// Mean position of each column over the frames where all of them are seen;
// when no frame has them all, each column's mean over its own visible frames;
// empty when a column is never seen.
Eigen::Matrix3Xd MeanPositions(const MarkerArray& m, const std::vector<int>& cols) {
  const Eigen::Index nc = static_cast<Eigen::Index>(cols.size());
  Eigen::Matrix3Xd sum = Eigen::Matrix3Xd::Zero(3, nc);
  int64_t n = 0;
  for (int64_t f = 0; f < m.frames(); ++f) {
    bool all = true;
    for (int c : cols) all = all && m.Visible(f, c);
    if (!all) continue;
    for (Eigen::Index i = 0; i < nc; ++i) sum.col(i) += Sample(m, f, cols[static_cast<size_t>(i)]);
    ++n;
  }
  if (n > 0) return sum / static_cast<double>(n);
  for (Eigen::Index i = 0; i < nc; ++i) {
    int64_t seen = 0;
    for (int64_t f = 0; f < m.frames(); ++f) {
      if (!m.Visible(f, cols[static_cast<size_t>(i)])) continue;
      sum.col(i) += Sample(m, f, cols[static_cast<size_t>(i)]);
      ++seen;
    }
    if (seen == 0) return {};
    sum.col(i) /= static_cast<double>(seen);
  }
  return sum;
}

std::vector<int> Bound(const MarkerBinding& b, const std::vector<std::string>& names) {
  std::vector<int> out;
  for (const std::string& n : names) {
    auto it = b.index.find(n);
    if (it != b.index.end()) out.push_back(it->second);
  }
  return out;
}

std::vector<std::string> ThroatNames(const MarkerSet& set) {
  std::vector<std::string> out;
  for (const ThroatMarker& t : set.throat) out.push_back(t.marker);
  return out;
}

// The cuer's front view from the marker set's roles, or false.
bool RoleView(const Take& take, const MarkerSet& set, PointLightView* view) {
  const MarkerBinding b = BindMarkerSet(set, take.marker_names, false, take.name);
  // Roles' columns, without markers the take never sees.
  auto seen = [&](std::vector<int> cols) {
    std::erase_if(cols, [&](int c) {
      for (int64_t f = 0; f < take.markers.frames(); ++f) {
        if (take.markers.Visible(f, c)) return false;
      }
      return true;
    });
    return cols;
  };
  const std::vector<int> head = seen(Bound(b, set.head_cluster)), face = seen(Bound(b, set.face)),
                         throat = seen(Bound(b, ThroatNames(set)));
  if (head.size() < 3 || face.size() < 3 || throat.empty()) return false;
  std::vector<int> all = head;
  all.insert(all.end(), face.begin(), face.end());
  all.insert(all.end(), throat.begin(), throat.end());
  const Eigen::Matrix3Xd mean = MeanPositions(take.markers, all);
  if (mean.cols() == 0) return false;
  const Eigen::Index nh = static_cast<Eigen::Index>(head.size()), nf = static_cast<Eigen::Index>(face.size());
  const Eigen::Vector3d head_c = mean.leftCols(nh).rowwise().mean();
  const Eigen::Matrix3Xd face_m = mean.middleCols(nh, nf);
  const Eigen::Vector3d face_c = face_m.rowwise().mean();
  const Eigen::Vector3d top = mean.leftCols(nh + nf).rowwise().mean();
  const Eigen::Vector3d throat_c = mean.rightCols(static_cast<Eigen::Index>(throat.size())).rowwise().mean();
  Eigen::Vector3d up = top - throat_c;
  if (!(up.norm() > 1e-6)) return false;
  up.normalize();
  const Eigen::Matrix3Xd centred = face_m.colwise() - face_c;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(centred * centred.transpose());
  Eigen::Vector3d forward = eig.eigenvectors().col(0);  // smallest eigenvalue first
  forward -= forward.dot(up) * up;
  if (!(forward.norm() > 1e-6)) return false;
  forward.normalize();
  if (forward.dot(face_c - head_c) < 0) forward = -forward;
  view->up = up;
  view->right = up.cross(forward).normalized();
  view->how = "marker set '" + set.name +
              "': up from the throat to the head and face markers, facing the normal of the face markers";
  return true;
}

cv::Scalar RoleColour(int role) {
  switch (role) {
    case 1:
      return {160, 160, 160};  // head cluster: grey
    case 2:
      return {255, 255, 255};  // face: white
    case 3:
      return {255, 200, 120};  // throat: light blue
    case 4:
      return {0, 140, 255};  // forearm cluster: orange
    case 5:
      return {0, 220, 255};  // hand: yellow
    default:
      return {255, 255, 255};
  }
}

// Per take column: role (0 none, 1 head, 2 face, 3 throat, 4 forearm, 5 hand);
// the sticks as column pairs.
struct Drawing {
  std::vector<int> role;
  std::vector<std::pair<int, int>> sticks;
};

Drawing MakeDrawing(const Take& take, const MarkerSet* set, bool sticks) {
  Drawing d;
  d.role.assign(take.marker_names.size(), 0);
  if (!set) return d;
  const MarkerBinding b = BindMarkerSet(*set, take.marker_names, false, take.name);
  auto mark = [&](const std::vector<std::string>& names, int role) {
    for (int c : Bound(b, names)) d.role[static_cast<size_t>(c)] = role;
  };
  mark(set->head_cluster, 1);
  mark(set->face, 2);
  mark(ThroatNames(*set), 3);
  mark(set->forearm_cluster, 4);
  std::vector<std::string> hand = set->fingertips;
  hand.insert(hand.end(), set->palm.begin(), set->palm.end());
  for (const HandSegment& s : set->hand_segments) hand.insert(hand.end(), s.markers.begin(), s.markers.end());
  mark(hand, 5);
  if (sticks) {
    for (const auto& [a, c] : set->sticks) {
      auto ia = b.index.find(a), ic = b.index.find(c);
      if (ia != b.index.end() && ic != b.index.end()) d.sticks.emplace_back(ia->second, ic->second);
    }
  }
  return d;
}

int DotRadius(const PointLightOptions& o) {
  return o.dot_radius_px > 0 ? o.dot_radius_px
                             : std::max(2, static_cast<int>(std::lround(std::min(o.width, o.height) / 180.0)));
}

cv::Mat Render(const Take& take, const Drawing& d, const PointLightView& view, int64_t frame,
               const PointLightOptions& o, int64_t frames) {
  cv::Mat img(o.height, o.width, CV_8UC3, cv::Scalar(0, 0, 0));
  const double t = static_cast<double>(frame) / o.fps;
  const Eigen::Matrix3Xd m = MarkersAtTime(take, t);
  std::vector<cv::Point> px(static_cast<size_t>(m.cols()));
  std::vector<bool> seen(static_cast<size_t>(m.cols()), false);
  constexpr int kShift = 4;  // sub-pixel bits of cv::circle and cv::line
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    if (!m.col(j).allFinite()) continue;
    const Eigen::Vector2d p = view.Project(m.col(j));
    if (!(std::abs(p.x()) < 1e6 && std::abs(p.y()) < 1e6)) continue;
    px[static_cast<size_t>(j)] = cv::Point(static_cast<int>(std::lround(p.x() * (1 << kShift))),
                                           static_cast<int>(std::lround(p.y() * (1 << kShift))));
    seen[static_cast<size_t>(j)] = true;
  }
  const int thick = std::max(1, DotRadius(o) / 3);
  for (const auto& [a, b] : d.sticks) {
    if (seen[static_cast<size_t>(a)] && seen[static_cast<size_t>(b)]) {
      cv::line(img, px[static_cast<size_t>(a)], px[static_cast<size_t>(b)], cv::Scalar(110, 110, 110), thick,
               cv::LINE_AA, kShift);
    }
  }
  const int r = DotRadius(o);
  for (size_t j = 0; j < px.size(); ++j) {
    if (seen[j]) cv::circle(img, px[j], r << kShift, RoleColour(d.role[j]), cv::FILLED, cv::LINE_AA, kShift);
  }
  const double font = std::max(0.35, std::min(o.width, o.height) / 1200.0);
  char text[128];
  std::snprintf(text, sizeof(text), "frame %lld/%lld  %.3f s", static_cast<long long>(frame + 1),
                static_cast<long long>(frames), t);
  const int line = static_cast<int>(std::lround(30 * font / 0.6));
  cv::putText(img, text, cv::Point(8, line), cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
  cv::putText(img, take.name, cv::Point(8, o.height - line / 2), cv::FONT_HERSHEY_SIMPLEX, font,
              cv::Scalar(140, 140, 140), 1, cv::LINE_AA);
  return img;
}

void CheckTake(const Take& take) {
  if (take.markers.empty()) throw InvalidInput("take '" + take.name + "': no markers to draw");
  if (!(take.rate_hz > 0)) throw InvalidInput("take '" + take.name + "': no frame rate");
}

// Runs argv and waits; "" on exit status 0, else the reason with the end of
// its standard error (read through a pipe: no file but the given ones is opened).
std::string Run(const std::vector<std::string>& argv) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) return std::string("cannot create a pipe: ") + std::strerror(errno);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    return "cannot run " + argv[0] + ": " + std::strerror(rc);
  }
  std::string err;
  char buf[4096];
  for (;;) {
    const ssize_t n = read(fds[0], buf, sizeof(buf));
    if (n > 0) {
      err.append(buf, static_cast<size_t>(n));
      if (err.size() > 65536) err.erase(0, err.size() - 4096);  // keep the end
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return "cannot wait for " + argv[0];
  }
  while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
  if (err.size() > 600) err = "…" + err.substr(err.size() - 600);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  const std::string why = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                            : "killed by signal " + std::to_string(WTERMSIG(status));
  return argv[0] + " failed (" + why + ")" + (err.empty() ? "" : ": " + err);
}

// Removes a file at destruction unless released.
struct TempFile {
  std::string path;
  ~TempFile() {
    if (path.empty()) return;
    std::error_code ec;
    fs::remove(path, ec);
  }
};

}  // namespace

std::string PointLightOptions::Check() const {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if (!(fps > 0 && fps <= 240)) return "the video frame rate must be in (0, 240] frames/s, got " + std::to_string(fps);
  if (width < 64 || height < 64 || width > 4096 || height > 4096) {
    return "the video size must be 64..4096 pixels each way, got " + size;
  }
  if (width % 2 != 0 || height % 2 != 0) return "the video width and height must be even, got " + size;
  if (dot_radius_px < 0) return "the dot radius must be >= 0 pixels";
  if (!(margin >= 0 && margin < 0.4)) return "the margin must be in [0, 0.4)";
  return "";
}

Eigen::Vector2d PointLightView::Project(const Eigen::Vector3d& p) const {
  const double x = right.dot(p) - center_mm.x(), y = up.dot(p) - center_mm.y();
  return {0.5 * width + scale_px_per_mm * x, 0.5 * height - scale_px_per_mm * y};
}

PointLightView FitPointLightView(const Take& take, const MarkerSet* set, const PointLightOptions& options) {
  CheckTake(take);
  PointLightView view;
  view.width = options.width;
  view.height = options.height;
  if (!set || !RoleView(take, *set, &view)) {
    view.right = Eigen::Vector3d::UnitX();
    view.up = Eigen::Vector3d::UnitZ();
    view.how = "lab axes (x right, z up)";
  }
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (int64_t f = 0; f < take.frames(); ++f) {
    for (int64_t j = 0; j < take.markers.markers(); ++j) {
      if (!take.markers.Visible(f, j)) continue;
      const Eigen::Vector3d p = Sample(take.markers, f, j);
      if (!p.allFinite()) continue;
      const double x = view.right.dot(p), y = view.up.dot(p);
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
  }
  if (!(x1 >= x0)) throw InvalidInput("take '" + take.name + "': no visible marker sample to draw");
  const double span_x = std::max(x1 - x0, 1.0), span_y = std::max(y1 - y0, 1.0);
  const double free = 1.0 - 2.0 * options.margin;
  view.scale_px_per_mm = std::min(free * options.width / span_x, free * options.height / span_y);
  view.center_mm = {0.5 * (x0 + x1), 0.5 * (y0 + y1)};
  return view;
}

int64_t PointLightFrameCount(double duration_s, double fps) {
  return std::max<int64_t>(1, std::llround(duration_s * fps));
}

Eigen::Matrix3Xd MarkersAtTime(const Take& take, double time_s) {
  const int64_t n = take.frames(), nm = take.markers.markers();
  Eigen::Matrix3Xd out = Eigen::Matrix3Xd::Constant(3, nm, kNaN);
  if (n == 0 || !(take.rate_hz > 0)) return out;
  const double u = std::clamp(time_s * take.rate_hz, 0.0, static_cast<double>(n - 1));
  const int64_t i0 = std::min<int64_t>(static_cast<int64_t>(std::floor(u)), n - 1);
  const int64_t i1 = std::min<int64_t>(i0 + 1, n - 1);
  const double a = u - static_cast<double>(i0);
  for (int64_t j = 0; j < nm; ++j) {
    const bool v0 = take.markers.Visible(i0, j), v1 = take.markers.Visible(i1, j);
    if (v0 && v1) {
      out.col(j) = (1 - a) * Sample(take.markers, i0, j) + a * Sample(take.markers, i1, j);
    } else if (a < 0.5 ? v0 : v1) {
      out.col(j) = Sample(take.markers, a < 0.5 ? i0 : i1, j);
    }
  }
  return out;
}

PointLightImage RenderPointLightFrame(const Take& take, const MarkerSet* set, const PointLightView& view, int64_t frame,
                                      const PointLightOptions& options) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  CheckTake(take);
  const Drawing d = MakeDrawing(take, set, options.sticks);
  const int64_t frames = PointLightFrameCount(take.duration_s(), options.fps);
  const cv::Mat img = Render(take, d, view, frame, options, frames);
  PointLightImage out;
  out.width = img.cols;
  out.height = img.rows;
  out.bgr.assign(img.data, img.data + img.total() * img.elemSize());
  return out;
}

std::string FindProgram(const std::string& name) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) return access(name.c_str(), X_OK) == 0 ? name : "";
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) dir = ".";
    const std::string candidate = dir + "/" + name;
    struct stat st {};
    if (stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
  }
  return "";
}

PointLightResult WritePointLightVideo(const Take& take, const MarkerSet* set, const std::string& path,
                                      const PointLightOptions& options, const std::string& wav_path,
                                      Progress* progress) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  CheckTake(take);
  if (path.empty()) throw IoError(path, "no output file given");
  if (!wav_path.empty() && !fs::is_regular_file(wav_path)) throw IoError(wav_path, "no such audio file");
  // With a sound track the video lasts as long as it (the WAV is read whole:
  // a damaged one is an error even when ffmpeg is missing).
  const double duration_s = wav_path.empty() ? take.duration_s() : ReadWav(wav_path).duration_s();
  PointLightResult r;
  r.path = path;
  r.view = FitPointLightView(take, set, options);
  const Drawing d = MakeDrawing(take, set, options.sticks);
  r.fps = options.fps;
  r.frames = PointLightFrameCount(duration_s, options.fps);
  r.duration_s = static_cast<double>(r.frames) / options.fps;
  r.width = options.width;
  r.height = options.height;
  r.markers = take.markers.markers();
  r.sticks = static_cast<int64_t>(d.sticks.size());

  const fs::path out(path);
  const fs::path folder = out.has_parent_path() ? out.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw IoError(path, "cannot write the video: no folder " + folder.string());
  if (fs::is_directory(out, ec)) throw IoError(path, "cannot write the video: a folder has that name");
  const std::string stem = "." + out.filename().string() + ".csw-tmp." + std::to_string(getpid());
  TempFile video{(folder / (stem + ".mp4")).string()};
  try {
    cv::VideoWriter writer;
    // H.264 (fourcc avc1: Debian's libavcodec with libx264), which browsers
    // play; MPEG-4 Part 2 (mp4v) when that encoder is missing. (Sizes are
    // even: H.264's 4:2:0 chroma needs it, PointLightOptions::Check.)
    const cv::Size size(options.width, options.height);
    bool opened =
        writer.open(video.path, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('a', 'v', 'c', '1'), options.fps, size);
    if (opened) {
      r.codec = "h264";
    } else {
      opened = writer.open(video.path, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), options.fps, size);
      r.codec = "mpeg4";
    }
    if (!opened) {
      const bool writable = access(folder.c_str(), W_OK) == 0;
      throw IoError(path, writable ? "cannot write the video (OpenCV could not open an H.264 or mp4v MP4 writer)"
                                   : "cannot write the video: the folder " + folder.string() + " is not writable");
    }
    for (int64_t k = 0; k < r.frames; ++k) {
      if (progress && k % 10 == 0) progress->Update("rendering video", static_cast<double>(k) / r.frames);
      writer.write(Render(take, d, r.view, k, options, r.frames));
    }
    writer.release();
  } catch (const cv::Exception& e) {
    throw IoError(path, std::string("cannot write the video (OpenCV: ") + e.what() + ")");
  }
  if (!fs::exists(video.path, ec) || fs::file_size(video.path, ec) == 0) {
    throw IoError(path, "cannot write the video (OpenCV wrote nothing)");
  }
  std::string final_file = video.path;
  TempFile muxed;
  if (!wav_path.empty()) {
    const std::string ffmpeg = FindProgram(options.ffmpeg);
    if (ffmpeg.empty()) {
      r.warnings.push_back("ffmpeg not found (" + options.ffmpeg +
                           "): the video is silent (install Debian's ffmpeg to mux the audio)");
    } else {
      if (progress) progress->Update("muxing audio", 0.0);
      muxed.path = (folder / (stem + ".mux.mp4")).string();
      const std::string why = Run({ffmpeg, "-y", "-v", "error", "-i", video.path, "-i", wav_path, "-map", "0:v:0",
                                   "-map", "1:a:0", "-c:v", "copy", "-c:a", "aac", "-b:a", "128k", muxed.path});
      if (!why.empty()) throw IoError(path, "cannot mux the audio " + wav_path + ": " + why);
      if (!fs::exists(muxed.path, ec)) throw IoError(path, "cannot mux the audio: " + ffmpeg + " wrote no file");
      final_file = muxed.path;
      r.audio = true;
    }
  }
  if (progress) progress->Update("rendering video", 1.0);  // the last point where a cancel is honoured
  fs::rename(final_file, out, ec);
  if (ec) throw IoError(path, "cannot write the video: " + ec.message());
  if (final_file == video.path) video.path.clear();
  if (final_file == muxed.path) muxed.path.clear();
  return r;
}

void SavePointLightFrame(const Take& take, const MarkerSet* set, int64_t frame, const std::string& png_path,
                         const PointLightOptions& options, int64_t total_frames) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  const PointLightView view = FitPointLightView(take, set, options);
  const Drawing d = MakeDrawing(take, set, options.sticks);
  const int64_t frames = total_frames > 0 ? total_frames : PointLightFrameCount(take.duration_s(), options.fps);
  const cv::Mat img = Render(take, d, view, frame, options, frames);
  bool ok = false;
  try {
    ok = cv::imwrite(png_path, img);
  } catch (const cv::Exception& e) {
    throw IoError(png_path, std::string("cannot write the picture: ") + e.what());
  }
  if (!ok) throw IoError(png_path, "cannot write the picture");
}

}  // namespace csw

#include "datasets/render.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "datasets/virtual_cuer.h"

namespace csw {

namespace {

const cv::Scalar kWhite(255, 255, 255), kBlack(0, 0, 0), kGrey(150, 150, 150), kLightGrey(225, 225, 225);
const cv::Scalar kFace(180, 90, 30), kThroat(60, 150, 40), kHand(20, 120, 230), kRed(30, 30, 220);

bool IsAscii(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return static_cast<unsigned char>(c) < 128; });
}

void Write(const std::string& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image);
  } catch (const cv::Exception& e) {
    throw IoError(path, std::string("cannot write PNG: ") + e.what());
  }
  if (!ok) throw IoError(path, "cannot write PNG");
}

}  // namespace

void RenderFramePng(const std::string& path, const Eigen::Matrix3Xd& positions, const std::vector<std::string>& names,
                    const std::vector<std::pair<std::string, std::string>>& sticks, const FrameRenderOptions& options,
                    const std::vector<std::string>& highlight) {
  cv::Mat img(options.height, options.width, CV_8UC3, kWhite);
  auto project = [&](const Eigen::Vector3d& p) {
    double u =
        options.view == FrameRenderOptions::View::kFront ? p.x() - options.centre.x() : p.y() - options.centre.y();
    double v = -(p.z() - options.centre.z());
    return cv::Point(static_cast<int>(std::lround(options.width / 2.0 + u / options.mm_per_pixel)),
                     static_cast<int>(std::lround(options.height / 2.0 + v / options.mm_per_pixel)));
  };
  std::map<std::string, int> index;
  for (size_t i = 0; i < names.size(); ++i) index[names[i]] = static_cast<int>(i);
  auto valid = [&](int i) { return i >= 0 && i < positions.cols() && std::isfinite(positions(0, i)); };
  // Depth order: draw far things first (front view: smaller y is farther).
  for (const auto& [a, b] : sticks) {
    auto ia = index.find(a), ib = index.find(b);
    if (ia == index.end() || ib == index.end() || !valid(ia->second) || !valid(ib->second)) continue;
    cv::line(img, project(positions.col(ia->second)), project(positions.col(ib->second)), kGrey, 1, cv::LINE_AA);
  }
  std::vector<int> order;
  for (int i = 0; i < positions.cols(); ++i)
    if (valid(i)) order.push_back(i);
  const int depth_axis = options.view == FrameRenderOptions::View::kFront ? 1 : 0;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return depth_axis == 1 ? positions(1, a) < positions(1, b) : positions(0, a) > positions(0, b);
  });
  for (int i : order) {
    const std::string& n = i < static_cast<int>(names.size()) ? names[static_cast<size_t>(i)] : std::string();
    bool hi = std::find(highlight.begin(), highlight.end(), n) != highlight.end();
    cv::Scalar colour = kFace;
    if (n.rfind("THR", 0) == 0) colour = kThroat;
    if (i >= 63) colour = kHand;
    if (hi) colour = kRed;
    cv::circle(img, project(positions.col(i)), hi ? 5 : 3, colour, cv::FILLED, cv::LINE_AA);
  }
  if (!options.title.empty())
    cv::putText(img, options.title, cv::Point(10, 24), cv::FONT_HERSHEY_SIMPLEX, 0.6, kBlack, 1, cv::LINE_AA);
  // Scale bar: 50 mm.
  int bar = static_cast<int>(std::lround(50.0 / options.mm_per_pixel));
  cv::line(img, cv::Point(10, options.height - 12), cv::Point(10 + bar, options.height - 12), kBlack, 2);
  cv::putText(img, "50 mm", cv::Point(14 + bar, options.height - 8), cv::FONT_HERSHEY_SIMPLEX, 0.4, kBlack, 1,
              cv::LINE_AA);
  Write(path, img);
}

void RenderTrajectoryPlotPng(const std::string& path, const SimulationResult& r,
                             const std::vector<std::string>& markers, int width, int height) {
  cv::Mat img(height, width, CV_8UC3, kWhite);
  const int left = 110, right = width - 20, top = 30;
  const int tier_h = 70;
  const int panels = static_cast<int>(markers.size());
  const int plot_bottom = height - tier_h - 40;
  const int panel_h = panels > 0 ? (plot_bottom - top) / panels : 0;
  const double t_end = r.take.duration_s();
  auto tx = [&](double t) { return static_cast<int>(std::lround(left + (right - left) * t / std::max(t_end, 1e-9))); };
  const cv::Scalar axis_colour[3] = {cv::Scalar(40, 40, 220), cv::Scalar(40, 160, 40), cv::Scalar(220, 90, 30)};
  // Key target lines across all panels.
  for (const GestureTruth& g : r.keys) {
    int x = tx(g.timing.shape_target_s);
    cv::line(img, cv::Point(x, top), cv::Point(x, plot_bottom + tier_h), kLightGrey, 1);
  }
  for (int p = 0; p < panels; ++p) {
    int col = -1;
    for (size_t i = 0; i < r.take.marker_names.size(); ++i)
      if (r.take.marker_names[i] == markers[static_cast<size_t>(p)]) col = static_cast<int>(i);
    const int y0 = top + p * panel_h, y1 = y0 + panel_h - 8;
    cv::rectangle(img, cv::Point(left, y0), cv::Point(right, y1), kGrey, 1);
    cv::putText(img, markers[static_cast<size_t>(p)], cv::Point(8, (y0 + y1) / 2), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                kBlack, 1, cv::LINE_AA);
    if (col < 0) continue;
    double lo = 1e300, hi = -1e300;
    double mean[3] = {0, 0, 0};
    int64_t n = 0;
    for (int64_t f = 0; f < r.frames(); ++f) {
      const float* v = r.take.markers.at(f, col);
      if (!std::isfinite(v[0])) continue;
      for (int c = 0; c < 3; ++c) mean[c] += v[c];
      ++n;
    }
    if (n == 0) continue;
    for (double& m : mean) m /= static_cast<double>(n);
    for (int64_t f = 0; f < r.frames(); ++f) {
      const float* v = r.take.markers.at(f, col);
      if (!std::isfinite(v[0])) continue;
      for (int c = 0; c < 3; ++c) {
        lo = std::min(lo, v[c] - mean[c]);
        hi = std::max(hi, v[c] - mean[c]);
      }
    }
    double span = std::max(hi - lo, 1.0);
    auto ty = [&](double v) { return static_cast<int>(std::lround(y1 - 4 - (y1 - y0 - 8) * (v - lo) / span)); };
    char range[48];
    std::snprintf(range, sizeof range, "%.0f mm", span);
    cv::putText(img, range, cv::Point(8, (y0 + y1) / 2 + 18), cv::FONT_HERSHEY_SIMPLEX, 0.4, kGrey, 1, cv::LINE_AA);
    for (int c = 0; c < 3; ++c) {
      cv::Point prev;
      bool have = false;
      for (int64_t f = 0; f < r.frames(); ++f) {
        const float* v = r.take.markers.at(f, col);
        if (!std::isfinite(v[0])) {
          have = false;
          continue;
        }
        cv::Point pt(tx(r.Time(f)), ty(v[c] - mean[c]));
        if (have) cv::line(img, prev, pt, axis_colour[c], 1, cv::LINE_AA);
        prev = pt;
        have = true;
      }
    }
  }
  // Phone tier and key codes.
  const int ty0 = plot_bottom + 4, ty1 = plot_bottom + tier_h / 2;
  cv::putText(img, "phones", cv::Point(8, ty1 - 10), cv::FONT_HERSHEY_SIMPLEX, 0.5, kBlack, 1, cv::LINE_AA);
  cv::putText(img, "keys", cv::Point(8, ty1 + 28), cv::FONT_HERSHEY_SIMPLEX, 0.5, kBlack, 1, cv::LINE_AA);
  for (const Phone& ph : r.utterance.phones) {
    int x0 = tx(ph.start_s), x1 = tx(ph.end_s);
    cv::rectangle(img, cv::Point(x0, ty0), cv::Point(x1, ty1), kGrey, 1);
    std::string label = IsAscii(ph.ipa) ? ph.ipa : ph.espeak;
    if (!label.empty() && label != "_")
      cv::putText(img, label, cv::Point(x0 + 2, ty1 - 10), cv::FONT_HERSHEY_SIMPLEX, 0.45, kBlack, 1, cv::LINE_AA);
  }
  for (const GestureTruth& g : r.keys) {
    int x = tx(g.timing.shape_target_s);
    cv::putText(img, g.key.Code(), cv::Point(x - 8, ty1 + 28), cv::FONT_HERSHEY_SIMPLEX, 0.45, kRed, 1, cv::LINE_AA);
  }
  // Time axis.
  const int ya = height - 14;
  cv::line(img, cv::Point(left, ya - 10), cv::Point(right, ya - 10), kBlack, 1);
  for (int s = 0; s <= static_cast<int>(t_end); ++s) {
    cv::line(img, cv::Point(tx(s), ya - 14), cv::Point(tx(s), ya - 6), kBlack, 1);
    cv::putText(img, std::to_string(s) + " s", cv::Point(tx(s) - 8, ya + 6), cv::FONT_HERSHEY_SIMPLEX, 0.4, kBlack, 1,
                cv::LINE_AA);
  }
  cv::putText(img, "x (red)  y (green)  z (blue), mean removed; grey lines: shape targets", cv::Point(left, 20),
              cv::FONT_HERSHEY_SIMPLEX, 0.45, kBlack, 1, cv::LINE_AA);
  Write(path, img);
}

}  // namespace csw

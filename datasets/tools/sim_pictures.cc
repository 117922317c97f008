// Draws the pictures of docs/virtual-cuer.md: every hand shape, every
// placement, and a sentence's marker trajectories with its phone tier.
//   csw_sim_pictures OUT_DIR
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "datasets/render.h"
#include "datasets/virtual_cuer.h"

namespace {

cv::Mat Grid(const std::vector<std::string>& files, int columns) {
  std::vector<cv::Mat> rows, row;
  for (size_t i = 0; i < files.size(); ++i) {
    row.push_back(cv::imread(files[i]));
    if (static_cast<int>(row.size()) == columns || i + 1 == files.size()) {
      while (static_cast<int>(row.size()) < columns)
        row.push_back(cv::Mat(row[0].size(), row[0].type(), cv::Scalar(255, 255, 255)));
      cv::Mat r;
      cv::hconcat(row, r);
      rows.push_back(r);
      row.clear();
    }
  }
  cv::Mat out;
  cv::vconcat(rows, out);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 1;
  }
  namespace fs = std::filesystem;
  const fs::path out = argv[1];
  try {
    fs::create_directories(out);
    const fs::path tmp = out / "sim_tmp";
    fs::create_directories(tmp);
    csw::SimulateOptions options;
    csw::VirtualCuer cuer(options);
    const std::vector<std::string> names = cuer.AllMarkerNames();
    auto sticks = cuer.MakeMarkerSet().sticks;
    // Hand shapes, hand alone in free space.
    std::vector<std::string> files;
    for (int shape = 0; shape <= 8; ++shape) {
      Eigen::Matrix3Xd all = cuer.KeyFrame(csw::kFreeSpacePlacement, shape);
      Eigen::Matrix3Xd hand = Eigen::Matrix3Xd::Constant(3, all.cols(), std::nan(""));
      hand.rightCols(cuer.hand().num_markers()) = all.rightCols(cuer.hand().num_markers());
      csw::FrameRenderOptions ro;
      ro.width = 260;
      ro.height = 300;
      ro.mm_per_pixel = 0.9;
      ro.centre = hand.rightCols(cuer.hand().num_markers()).rowwise().mean() + Eigen::Vector3d(0, 0, 30);
      ro.title = shape == 0 ? "rest (0)" : "shape " + std::to_string(shape);
      std::string f = (tmp / ("shape" + std::to_string(shape) + ".png")).string();
      csw::RenderFramePng(f, hand, names, sticks, ro);
      files.push_back(f);
    }
    cv::imwrite((out / "sim_shapes.png").string(), Grid(files, 3));
    // Placements with shape 5 (1 for the side, as in a lone consonant "1S").
    files.clear();
    const char* pname[] = {"rest", "side", "cheekbone", "mouth corner", "chin", "throat"};
    for (int p = 0; p <= 5; ++p) {
      Eigen::Matrix3Xd all = cuer.KeyFrame(p, p == 0 ? 0 : 5);
      csw::FrameRenderOptions ro;
      ro.width = 360;
      ro.height = 460;
      ro.mm_per_pixel = 1.35;
      ro.centre = Eigen::Vector3d(-60.0, 0.0, 1140.0);
      ro.title = std::to_string(p) + " " + pname[p];
      std::string f = (tmp / ("place" + std::to_string(p) + ".png")).string();
      csw::RenderFramePng(f, all, names, sticks, ro);
      files.push_back(f);
    }
    cv::imwrite((out / "sim_placements.png").string(), Grid(files, 3));
    // Side view of the mouth-corner placement.
    {
      csw::FrameRenderOptions ro;
      ro.view = csw::FrameRenderOptions::View::kSide;
      ro.centre = Eigen::Vector3d(0.0, 60.0, 1180.0);
      ro.mm_per_pixel = 1.0;
      ro.title = "3 mouth corner, side view";
      csw::RenderFramePng((out / "sim_side_mouth.png").string(), cuer.KeyFrame(3, 5), names, sticks, ro);
    }
    // A sentence: one frame and the trajectories.
    const std::vector<std::string> sentences = csw::ShippedSentences();
    csw::SimulationResult r = cuer.SimulateSentence("sentence_001", sentences.at(0));
    csw::RenderTrajectoryPlotPng((out / "sim_trajectories.png").string(), r,
                                 {"MTIP", "ITIP", "FA1", "LLM", "ULM", "THR08"});
    int64_t mid = r.frames() / 2;
    Eigen::Matrix3Xd frame(3, r.take.markers.markers());
    for (int64_t m = 0; m < frame.cols(); ++m)
      for (int c = 0; c < 3; ++c) frame(c, m) = r.take.markers.at(mid, m)[c];
    csw::FrameRenderOptions ro;
    ro.centre = Eigen::Vector3d(-40.0, 0.0, 1180.0);
    ro.mm_per_pixel = 1.0;
    ro.title = "frame " + std::to_string(mid) + " as captured";
    csw::RenderFramePng((out / "sim_frame.png").string(), frame, r.take.marker_names, sticks, ro);
    fs::remove_all(tmp);
    std::printf("%s: %s\n", "sentence", sentences.at(0).c_str());
  } catch (const csw::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}

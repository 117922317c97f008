#pragma once
// Small offscreen pictures of simulated takes (OpenCV): a frame of markers and
// sticks in orthographic front or side view, and a plot of marker trajectories
// over time with the phone and key tiers. Used for docs/virtual-cuer.md.
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace csw {

struct SimulationResult;

struct FrameRenderOptions {
  enum class View { kFront, kSide };
  View view = View::kFront;  // front: looking at the cuer's face (cuer's right hand on the image's left)
  int width = 480;
  int height = 560;
  double mm_per_pixel = 0.75;
  Eigen::Vector3d centre = Eigen::Vector3d(0.0, 0.0, 1200.0);  // lab point at the image centre
  std::string title;
};

// Draws markers (columns of `positions`, NaN = missing; markers whose name is
// in `highlight` drawn larger and in red) and sticks, and writes a PNG.
// Throws IoError when the file cannot be written.
void RenderFramePng(const std::string& path, const Eigen::Matrix3Xd& positions, const std::vector<std::string>& names,
                    const std::vector<std::pair<std::string, std::string>>& sticks, const FrameRenderOptions& options,
                    const std::vector<std::string>& highlight = {});

// Plots the x, y, z coordinates (mean removed) of the named markers of a take
// against time, above its phone tier and key targets, and writes a PNG.
void RenderTrajectoryPlotPng(const std::string& path, const SimulationResult& result,
                             const std::vector<std::string>& markers, int width = 1100, int height = 620);

}  // namespace csw

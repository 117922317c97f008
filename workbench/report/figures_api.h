#pragma once
// The entry points of the figures module (libcsw_figures.so): csw_report's
// Save* functions behind a table of plain function pointers, so that programs
// that draw figures only on request (`csw fit/invert --figures`) load Qt at
// run time with dlopen instead of linking it (workbench/jobs/figures.h).
// Each function returns "" on success, else the error message (exceptions do
// not cross the module boundary). Plain types only: no Qt in this header.
#include <string>
#include <utility>
#include <vector>

#include "workbench/report/analysis_figures.h"
#include "workbench/report/report.h"

namespace csw::report {

inline constexpr int kFiguresApiVersion = 4;

struct FiguresApi {
  int version = kFiguresApiVersion;
  std::string (*save_error_bars)(const std::string& path, const std::string& title, const std::vector<ErrorBar>& bars,
                                 double target_mm) = nullptr;
  std::string (*save_variance_explained)(const std::string& path, const std::string& title,
                                         const std::vector<std::string>& names,
                                         const std::vector<double>& fractions) = nullptr;
  std::string (*save_parameter_effects)(const std::string& path, const std::string& title,
                                        const Eigen::Matrix3Xd& neutral, const std::vector<ParameterEffect>& effects,
                                        const std::vector<std::pair<int, int>>& sticks) = nullptr;
  // Version 2: the cleaning figures.
  std::string (*save_gap_map)(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                              const std::vector<std::vector<std::pair<int64_t, int64_t>>>& gaps, int64_t frames,
                              double rate_hz) = nullptr;
  std::string (*save_gap_fill)(const std::string& path, const std::string& title, const std::vector<double>& time_s,
                               const Eigen::Matrix3Xd& measured, const Eigen::Matrix3Xd& truth,
                               const std::vector<FillSeries>& fills, double gap_start_s, double gap_end_s) = nullptr;
  // Version 3: the key-recognition and phasing figures (analysis_figures.h).
  std::string (*save_gestural_score)(const std::string& path, const std::string& title, const std::vector<float>& audio,
                                     double audio_rate_hz, double audio_start_s,
                                     const std::vector<PosteriorLane>& lanes, double frame_rate_hz,
                                     const std::vector<LabelTier>& tiers, double start_s, double end_s) = nullptr;
  std::string (*save_histograms)(const std::string& path, const std::string& title,
                                 const std::vector<HistogramPanel>& panels, double bin_ms,
                                 const std::string& x_label) = nullptr;
  std::string (*save_confusion_matrix)(const std::string& path, const std::string& title,
                                       const std::vector<std::string>& labels,
                                       const std::vector<std::vector<int>>& counts, const std::string& true_axis,
                                       const std::string& recognised_axis) = nullptr;
  // Version 4: x-y panels (analysis_figures.h, SavePlots).
  std::string (*save_plots)(const std::string& path, const std::string& title, const std::vector<PlotPanel>& panels,
                            int columns) = nullptr;
};

}  // namespace csw::report

// The module's one exported symbol.
#define CSW_FIGURES_ENTRY_POINT "csw_figures_api"
extern "C" const csw::report::FiguresApi* csw_figures_api();

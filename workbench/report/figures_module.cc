// libcsw_figures.so: csw_report's figures for programs that load them with
// dlopen (workbench/jobs/figures.cc). Exceptions become error messages.
#include <exception>

#include "workbench/report/analysis_figures.h"
#include "workbench/report/figures_api.h"
#include "workbench/report/report.h"

namespace {

template <typename F>
std::string Guarded(F&& f) {
  try {
    f();
    return "";
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "unknown error while drawing a figure";
  }
}

std::string SaveErrorBars(const std::string& path, const std::string& title,
                          const std::vector<csw::report::ErrorBar>& bars, double target_mm) {
  return Guarded([&] { csw::report::SaveErrorBars(path, title, bars, target_mm); });
}

std::string SaveVarianceExplained(const std::string& path, const std::string& title,
                                  const std::vector<std::string>& names, const std::vector<double>& fractions) {
  return Guarded([&] { csw::report::SaveVarianceExplained(path, title, names, fractions); });
}

std::string SaveParameterEffects(const std::string& path, const std::string& title, const Eigen::Matrix3Xd& neutral,
                                 const std::vector<csw::report::ParameterEffect>& effects,
                                 const std::vector<std::pair<int, int>>& sticks) {
  return Guarded([&] { csw::report::SaveParameterEffects(path, title, neutral, effects, sticks); });
}

std::string SaveGapMap(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                       const std::vector<std::vector<std::pair<int64_t, int64_t>>>& gaps, int64_t frames,
                       double rate_hz) {
  return Guarded([&] { csw::report::SaveGapMap(path, title, names, gaps, frames, rate_hz); });
}

std::string SaveGapFill(const std::string& path, const std::string& title, const std::vector<double>& time_s,
                        const Eigen::Matrix3Xd& measured, const Eigen::Matrix3Xd& truth,
                        const std::vector<csw::report::FillSeries>& fills, double gap_start_s, double gap_end_s) {
  return Guarded(
      [&] { csw::report::SaveGapFill(path, title, time_s, measured, truth, fills, gap_start_s, gap_end_s); });
}

std::string SaveGesturalScore(const std::string& path, const std::string& title, const std::vector<float>& audio,
                              double audio_rate_hz, double audio_start_s,
                              const std::vector<csw::report::PosteriorLane>& lanes, double frame_rate_hz,
                              const std::vector<csw::LabelTier>& tiers, double start_s, double end_s) {
  return Guarded([&] {
    csw::report::SaveGesturalScore(path, title, audio, audio_rate_hz, audio_start_s, lanes, frame_rate_hz, tiers,
                                   start_s, end_s);
  });
}

std::string SaveHistograms(const std::string& path, const std::string& title,
                           const std::vector<csw::report::HistogramPanel>& panels, double bin_ms,
                           const std::string& x_label) {
  return Guarded([&] { csw::report::SaveHistograms(path, title, panels, bin_ms, x_label); });
}

std::string SaveConfusionMatrix(const std::string& path, const std::string& title,
                                const std::vector<std::string>& labels, const std::vector<std::vector<int>>& counts,
                                const std::string& true_axis, const std::string& recognised_axis) {
  return Guarded([&] { csw::report::SaveConfusionMatrix(path, title, labels, counts, true_axis, recognised_axis); });
}

std::string SavePlots(const std::string& path, const std::string& title,
                      const std::vector<csw::report::PlotPanel>& panels, int columns) {
  return Guarded([&] { csw::report::SavePlots(path, title, panels, columns); });
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const csw::report::FiguresApi* csw_figures_api() {
  static const csw::report::FiguresApi api{csw::report::kFiguresApiVersion,
                                           &SaveErrorBars,
                                           &SaveVarianceExplained,
                                           &SaveParameterEffects,
                                           &SaveGapMap,
                                           &SaveGapFill,
                                           &SaveGesturalScore,
                                           &SaveHistograms,
                                           &SaveConfusionMatrix,
                                           &SavePlots};
  return &api;
}

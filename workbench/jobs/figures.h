#pragma once
// Figures for the jobs, drawn by the figures module (libcsw_figures.so,
// workbench/report/figures_api.h) loaded with dlopen on first use, so that
// programs linking csw_jobs (the csw CLI) do not load Qt unless asked for
// figures. The module is looked for in $CSW_FIGURES_MODULE (a file; when set,
// the only place looked at), else in order: next to the running program, in
// <program dir>/../lib/csw/, and where the build wrote it (a path compiled
// in). Each Save* throws InvalidInput naming the paths tried when the module
// cannot be loaded, and InvalidInput with the module's message (naming the
// file) when drawing fails.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "workbench/report/analysis_figures.h"
#include "workbench/report/report.h"

namespace csw::jobs::figures {

// Loads the module (once); throws InvalidInput when it cannot.
void Require();

void SaveErrorBars(const std::string& path, const std::string& title, const std::vector<report::ErrorBar>& bars,
                   double target_mm);
void SaveVarianceExplained(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                           const std::vector<double>& fractions);
void SaveParameterEffects(const std::string& path, const std::string& title, const Eigen::Matrix3Xd& neutral,
                          const std::vector<report::ParameterEffect>& effects,
                          const std::vector<std::pair<int, int>>& sticks);
void SaveGapMap(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                const std::vector<std::vector<std::pair<int64_t, int64_t>>>& gaps, int64_t frames, double rate_hz);
void SaveGapFill(const std::string& path, const std::string& title, const std::vector<double>& time_s,
                 const Eigen::Matrix3Xd& measured, const Eigen::Matrix3Xd& truth,
                 const std::vector<report::FillSeries>& fills, double gap_start_s, double gap_end_s);
// The analysis figures (workbench/report/analysis_figures.h).
void SaveGesturalScore(const std::string& path, const std::string& title, const std::vector<float>& audio,
                       double audio_rate_hz, double audio_start_s, const std::vector<report::PosteriorLane>& lanes,
                       double frame_rate_hz, const std::vector<LabelTier>& tiers, double start_s, double end_s);
void SaveHistograms(const std::string& path, const std::string& title,
                    const std::vector<report::HistogramPanel>& panels, double bin_ms, const std::string& x_label);
void SaveConfusionMatrix(const std::string& path, const std::string& title, const std::vector<std::string>& labels,
                         const std::vector<std::vector<int>>& counts, const std::string& true_axis = "true class",
                         const std::string& recognised_axis = "recognised class");

void SavePlots(const std::string& path, const std::string& title, const std::vector<report::PlotPanel>& panels,
               int columns = 0);

}  // namespace csw::jobs::figures

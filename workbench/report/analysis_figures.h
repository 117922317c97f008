#pragma once
// Figures of the key-recognition and phasing analyses (docs/analysis.md): the
// gestural score of an utterance (the seed's Figure 4), histograms of gesture
// times (its Figure 5, one panel per key type and landmark) and confusion
// matrices. Plain data in, a PNG, SVG or PDF file out, with the conventions of
// report.h: chosen by the extension, written under a temporary name and renamed
// into place, drawn offscreen on the thread of the QApplication.
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "core/take.h"

namespace csw::report {

// One lane of per-frame class probabilities (posteriors) of the gestural score.
struct PosteriorLane {
  std::string name;                  // e.g. "hand shape"
  std::vector<std::string> classes;  // one name per column, e.g. "0" ... "8"
  Eigen::MatrixXd posteriors;        // frames × classes in [0, 1]; NaN = frame not scored
};

// The gestural score between start_s and end_s: the waveform on top (audio
// samples at audio_rate_hz, the first one at audio_start_s; empty = no
// waveform panel), then one panel per label tier (intervals with their
// boundaries and texts, points as ticks with their texts), then one panel per
// posterior lane (one coloured line per class with a legend; the frame f is at
// f / frame_rate_hz). Every panel shares the time axis. InvalidInput: an empty
// or reversed time range, rates <= 0, a lane whose class count differs from its
// columns, a probability outside [0, 1] (beyond 1e-6), nothing to draw.
void SaveGesturalScore(const std::string& path, const std::string& title, const std::vector<float>& audio,
                       double audio_rate_hz, double audio_start_s, const std::vector<PosteriorLane>& lanes,
                       double frame_rate_hz, const std::vector<LabelTier>& tiers, double start_s, double end_s);

// One histogram panel: values in milliseconds, with an optional reference
// value (e.g. the simulated truth or a published mean) drawn as a dashed red
// line; the panel's mean is a solid blue line and its header gives n, mean and sd.
struct HistogramPanel {
  std::string title;  // e.g. "CV placement onset"
  std::vector<double> values_ms;
  double reference_ms = std::numeric_limits<double>::quiet_NaN();
  std::string reference_name;  // legend of the reference, e.g. "Attina 2005"
};

// A grid of histograms (up to four per row) sharing one bin width and one x
// range, so panels compare at a glance; x_label names the measure. Panels with
// no value are drawn empty with "no data". NaN values are left out.
// InvalidInput: no panels, bin_ms <= 0 or not finite, an infinite value.
void SaveHistograms(const std::string& path, const std::string& title, const std::vector<HistogramPanel>& panels,
                    double bin_ms, const std::string& x_label);

// A confusion matrix: rows are the true classes, columns the recognised ones,
// counts[i][j] = how many frames (or keys) of class i were recognised as j.
// Cells are shaded by the row's fraction (white 0 → dark blue 1) and show the
// count; the row's accuracy is written at its right. InvalidInput: no labels,
// a matrix that is not labels × labels, a negative count.
void SaveConfusionMatrix(const std::string& path, const std::string& title, const std::vector<std::string>& labels,
                         const std::vector<std::vector<int>>& counts, const std::string& true_axis = "true class",
                         const std::string& recognised_axis = "recognised class");

// One series of an x-y panel: a line, dashed line or points, with its legend
// name ("" = not in the legend). Points with a NaN coordinate are left out
// (lines break there).
struct PlotSeries {
  enum class Style { kLine, kDashed, kPoints };
  std::string name;
  std::vector<double> x, y;
  Style style = Style::kLine;
  int colour = -1;  // index in the qualitative palette; -1 = the series' order in its panel
};

// One panel of SavePlots: series, optional vertical marks (thin dashed grey
// lines at these x, e.g. boundaries), axis labels.
struct PlotPanel {
  std::string title;
  std::string x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<double> vertical_marks;
  // The y range; NaN (default) = from the data.
  double y_min = std::numeric_limits<double>::quiet_NaN();
  double y_max = std::numeric_limits<double>::quiet_NaN();
};

// A grid of x-y panels (`columns` per row; 0 = up to two) with one legend of
// every named series. InvalidInput: no panel, a series whose x and y differ in
// length, an infinite coordinate, a panel with no finite point, a given y
// range with y_max <= y_min.
void SavePlots(const std::string& path, const std::string& title, const std::vector<PlotPanel>& panels,
               int columns = 0);

}  // namespace csw::report

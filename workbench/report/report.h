#pragma once
// Report figures for the CLI (issue 4 §7): reconstruction error per utterance,
// variance explained per parameter, and each parameter's effect on the shape.
// Plain data in, a PNG, SVG or PDF file out (chosen by the extension; anything
// else throws csw::InvalidInput naming the path). Files are written under a
// temporary name and renamed into place; a write failure throws csw::IoError
// naming the path. Drawn with QCustomPlot offscreen: every Save* function
// calls EnsureGuiApplication() first and must run on the main thread.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace csw::report {

// Creates the process's QApplication once if there is none (never destroyed).
// Without a display (DISPLAY and WAYLAND_DISPLAY unset) or when QT_QPA_PLATFORM
// is unset, Qt's "offscreen" platform is used, so the CLI works headless and
// draws the same pixels everywhere. Safe to call repeatedly. Throws
// csw::InvalidInput when a QCoreApplication that is not a QApplication exists,
// or when called from a thread other than the application's.
void EnsureGuiApplication();

// Colours of the figures, shared with tests and docs.
struct Rgb {
  int r, g, b;
};
inline constexpr Rgb kTrainingColour{40, 110, 180};  // training utterances; variance bars
inline constexpr Rgb kHeldOutColour{235, 130, 30};   // held-out utterances
inline constexpr Rgb kLowColour{30, 80, 220};        // parameter at its low extreme (−2 sd)
inline constexpr Rgb kHighColour{215, 40, 40};       // parameter at its high extreme (+2 sd)
inline constexpr Rgb kNeutralColour{145, 145, 160};  // the neutral (mean) shape; a tinted grey, so
                                                     // antialiased black text never matches it

// Pixel size of the PNG written by SaveErrorBars and SaveVarianceExplained.
inline constexpr int kFigureWidth = 1200;
inline constexpr int kFigureHeight = 700;

// One utterance's reconstruction error in mm.
struct ErrorBar {
  std::string label;  // utterance name, shown under its bar
  double mean = 0;    // mean absolute error
  double sd = 0;      // its standard deviation (whisker: mean ± sd, cut at 0)
  double max = 0;     // largest error (a small cross; ▲ at the top when off the scale)
  bool held_out = false;
};

// One bar per utterance in the given order, training and held-out in two
// colours with a legend, sd whiskers, the maxima, and a dashed line at
// target_mm (0 = none). Labels are rotated when there are many and thinned when
// they would overlap. InvalidInput: no bars, or a negative / non-finite number.
void SaveErrorBars(const std::string& path, const std::string& title, const std::vector<ErrorBar>& bars,
                   double target_mm);

// Bars: the fraction of variance each parameter explains (in %, left axis);
// line: the cumulative fraction (in %, right axis). fractions are 0..1.
// InvalidInput: sizes differ, empty, or a fraction outside [0, 1].
void SaveVarianceExplained(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                           const std::vector<double>& fractions);

// A parameter's effect: all markers (model frame, mm) with that parameter at
// its low (−2 sd) and high (+2 sd) value, every other parameter at 0.
struct ParameterEffect {
  std::string name;
  Eigen::Matrix3Xd low, high;
};

// A grid with one panel per parameter, each showing the low (blue) and high
// (red) extremes with the neutral shape (grey) drawn over them, so that what a
// parameter leaves in place shows grey: markers as dots, sticks as lines
// (pairs of marker indices). Front view: the model frame's x to the
// right and z up, equal aspect and the same scale in every panel. Markers with
// a NaN coordinate are left out with their sticks. InvalidInput: no effects,
// matrices whose column counts differ from neutral's, a stick index out of range.
void SaveParameterEffects(const std::string& path, const std::string& title, const Eigen::Matrix3Xd& neutral,
                          const std::vector<ParameterEffect>& effects, const std::vector<std::pair<int, int>>& sticks);

// The PNG size SaveParameterEffects writes for `parameters` panels: up to four
// panels of 300 × 360 pixels per row, at least 600 pixels wide, plus a header.
std::pair<int, int> ParameterEffectsSize(int parameters);

// Gap map of a take (docs/cleaning.md): one row per marker (names as tick
// labels, thinned when many), time in seconds across, each cell coloured by
// the fraction of its frames missing (white = all seen, dark red = all
// missing). gaps[m] lists marker m's gaps as (first frame, length).
// InvalidInput: names and gaps differ in size, no markers, frames or rate <= 0,
// a gap outside [0, frames).
void SaveGapMap(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                const std::vector<std::vector<std::pair<int64_t, int64_t>>>& gaps, int64_t frames, double rate_hz);

// One filled gap, before and after: three stacked panels (x, y, z in mm)
// against time (s) around the gap; the measured samples as black dots, the
// truth (when given) as a grey line, and each method's fill over the gap as a
// coloured line, with the gap shaded. Series are 3 × n (NaN = not drawn).
struct FillSeries {
  std::string name;      // legend entry, e.g. "spline (smoothing, GCV)"
  Eigen::Matrix3Xd xyz;  // 3 × n
};
void SaveGapFill(const std::string& path, const std::string& title, const std::vector<double>& time_s,
                 const Eigen::Matrix3Xd& measured, const Eigen::Matrix3Xd& truth, const std::vector<FillSeries>& fills,
                 double gap_start_s, double gap_end_s);

}  // namespace csw::report

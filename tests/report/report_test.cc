// Report figures written to PNG, SVG and PDF and checked in the files: sizes,
// the colours of the bars and shapes where the data put them (bar heights in
// proportion to the values, extremes moved the way the effect moves them, equal
// aspect), the labels as text in the SVG, and the errors for bad paths and
// data. No QApplication is made here: the library makes its own (offscreen when
// there is no display), which is part of what is tested.
#include "workbench/report/report.h"

#include <gtest/gtest.h>

#include <QCoreApplication>
#include <QFile>
#include <QGuiApplication>
#include <QImage>
#include <QXmlStreamReader>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "tests/report/report_testing.h"
#include "tests/testing/testing.h"

// Qt and fontconfig keep process-lifetime caches that LeakSanitizer reports at
// exit (the library's QApplication, never destroyed, stays reachable through qApp).
extern "C" const char* __lsan_default_suppressions() {
  return "leak:libfontconfig.so\nleak:libdbus-1.so\nleak:libQt6DBus.so\n";
}

namespace csw::report {
namespace {

namespace fs = std::filesystem;

// The environment before the library touched it (read before main runs).
const QByteArray kInitialPlatform = qgetenv("QT_QPA_PLATFORM");
const bool kInitialDisplay = !qEnvironmentVariableIsEmpty("DISPLAY") || !qEnvironmentVariableIsEmpty("WAYLAND_DISPLAY");

// Rows of the title and the legend (whose symbols have the figures' colours).
constexpr int kHeader = 80;

bool Is(QRgb p, Rgb c) { return qRed(p) == c.r && qGreen(p) == c.g && qBlue(p) == c.b; }

// Pixels of exactly colour c inside [x0, x1) × [y0, y1).
struct Box {
  int count = 0;
  int left = 1 << 30, right = -1, top = 1 << 30, bottom = -1;
  int width() const { return right - left + 1; }
  int height() const { return bottom - top + 1; }
};
Box Find(const QImage& image, Rgb c, int x0, int x1, int y0, int y1) {
  Box b;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      if (Is(image.pixel(x, y), c)) {
        ++b.count;
        b.left = std::min(b.left, x);
        b.right = std::max(b.right, x);
        b.top = std::min(b.top, y);
        b.bottom = std::max(b.bottom, y);
      }
  return b;
}

// Runs of columns holding colour c below row y0, left to right: one per bar,
// with the bar's height in pixels (its tallest column).
std::vector<int> BarHeights(const QImage& image, Rgb c, int y0) {
  std::vector<int> heights;
  bool in_run = false;
  for (int x = 0; x < image.width(); ++x) {
    int top = -1, bottom = -1;
    for (int y = y0; y < image.height(); ++y)
      if (Is(image.pixel(x, y), c)) {
        if (top < 0) top = y;
        bottom = y;
      }
    if (top >= 0) {
      if (!in_run) heights.push_back(0);
      heights.back() = std::max(heights.back(), bottom - top + 1);
      in_run = true;
    } else {
      in_run = false;
    }
  }
  return heights;
}

std::vector<std::string> Listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

template <typename F>
std::string ThrownMessage(F f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(ReportApplication, MadeOnceOffscreenWithoutADisplay) {
  EnsureGuiApplication();
  QCoreApplication* app = QCoreApplication::instance();
  ASSERT_NE(app, nullptr);
  EnsureGuiApplication();
  EXPECT_EQ(QCoreApplication::instance(), app);
  bool needs_display = kInitialPlatform.startsWith("xcb") || kInitialPlatform.startsWith("wayland");
  if (kInitialPlatform.isEmpty() || (needs_display && !kInitialDisplay))
    EXPECT_EQ(QGuiApplication::platformName(), QStringLiteral("offscreen"));
  else
    EXPECT_EQ(QGuiApplication::platformName().toUtf8(), kInitialPlatform);
}

TEST(ErrorBars, BarHeightsFollowTheMeansInTwoColours) {
  testing::TempDir dir;
  std::vector<ErrorBar> bars = {{"take_one", 3.0, 0.4, 4.0, false}, {"take_two", 1.0, 0.2, 1.5, true}};
  SaveErrorBars((dir / "e.png").string(), "Face model", bars, 2.0);
  SaveErrorBars((dir / "e.svg").string(), "Face model", bars, 2.0);
  SaveErrorBars((dir / "e.pdf").string(), "Face model", bars, 2.0);
  EXPECT_EQ(Listing(dir.path()), (std::vector<std::string>{"e.pdf", "e.png", "e.svg"}));  // no part files left

  QImage image = LoadPng(dir / "e.png");
  ASSERT_FALSE(image.isNull());
  EXPECT_EQ(image.size(), QSize(kFigureWidth, kFigureHeight));
  // Below the title and legend rows: one bar of each colour.
  std::vector<int> training = BarHeights(image, kTrainingColour, kHeader);
  std::vector<int> held_out = BarHeights(image, kHeldOutColour, kHeader);
  ASSERT_EQ(training.size(), 1u);
  ASSERT_EQ(held_out.size(), 1u);
  EXPECT_GT(held_out[0], 50);
  // Bars start at 0: heights in the ratio of the means, 3 : 1 (to a pixel or two).
  EXPECT_NEAR(training[0] / static_cast<double>(held_out[0]), 3.0, 0.08);
  Box t = Find(image, kTrainingColour, 0, image.width(), kHeader, image.height());
  Box h = Find(image, kHeldOutColour, 0, image.width(), kHeader, image.height());
  EXPECT_LT(t.right, h.left);  // in the given order
  EXPECT_NEAR(t.width(), h.width(), 1);
  EXPECT_GT(t.count, 2.5 * h.count);

  QString svg = SvgText(dir / "e.svg");
  for (const char* s : {"Face model", "take_one", "take_two", "training", "held out", "mean absolute error (mm)",
                        "target 2 mm", "maximum"})
    EXPECT_TRUE(svg.contains(QString::fromUtf8(s))) << s;
  QFile pdf(QString::fromStdString((dir / "e.pdf").string()));
  ASSERT_TRUE(pdf.open(QIODevice::ReadOnly));
  EXPECT_EQ(pdf.read(5), QByteArray("%PDF-"));
}

TEST(ErrorBars, ManyUtterancesAreEachABarInOrder) {
  testing::TempDir dir;
  std::vector<ErrorBar> bars;
  for (int i = 0; i < 30; ++i) {
    char label[32];
    std::snprintf(label, sizeof label, "sentence_%03d", i);
    bars.push_back({label, 0.5 + 0.1 * i, 0.05, 0.6 + 0.1 * i, i >= 10});
  }
  // One maximum far above the rest is drawn at the top, not allowed to squash the bars.
  bars[3].max = 40;
  SaveErrorBars((dir / "many.png").string(), "Hand model", bars, 1.0);
  SaveErrorBars((dir / "many.svg").string(), "Hand model", bars, 1.0);
  QImage image = LoadPng(dir / "many.png");
  ASSERT_EQ(image.size(), QSize(kFigureWidth, kFigureHeight));
  std::vector<int> training = BarHeights(image, kTrainingColour, kHeader);
  std::vector<int> held_out = BarHeights(image, kHeldOutColour, kHeader);
  ASSERT_EQ(training.size(), 10u);
  ASSERT_EQ(held_out.size(), 20u);
  std::vector<int> all = training;
  all.insert(all.end(), held_out.begin(), held_out.end());
  for (size_t i = 1; i < all.size(); ++i) EXPECT_GT(all[i], all[i - 1]) << i;
  // Heights are linear in the mean: (3.4 − 0.5) / (1.4 − 0.5) between the last and the 10th.
  EXPECT_NEAR((all[29] - all[0]) / static_cast<double>(all[9] - all[0]), 29.0 / 9.0, 0.1);
  QString svg = SvgText(dir / "many.svg");
  EXPECT_TRUE(svg.contains("sentence_000"));
  EXPECT_TRUE(svg.contains("maximum off the scale"));
}

TEST(VarianceExplained, BarsInProportionAndTheCumulativeCurve) {
  testing::TempDir dir;
  std::vector<std::string> names = {"jaw", "lips rounding", "lip raise", "throat"};
  std::vector<double> fractions = {0.5, 0.25, 0.15, 0.05};
  SaveVarianceExplained((dir / "v.png").string(), "Face parameters", names, fractions);
  SaveVarianceExplained((dir / "v.svg").string(), "Face parameters", names, fractions);
  QImage image = LoadPng(dir / "v.png");
  ASSERT_EQ(image.size(), QSize(kFigureWidth, kFigureHeight));
  std::vector<int> heights = BarHeights(image, kTrainingColour, kHeader);
  ASSERT_EQ(heights.size(), 4u);
  EXPECT_NEAR(heights[0] / static_cast<double>(heights[1]), 2.0, 0.05);
  EXPECT_NEAR(heights[0] / static_cast<double>(heights[2]), 0.5 / 0.15, 0.08);
  EXPECT_NEAR(heights[0] / static_cast<double>(heights[3]), 10.0, 0.6);
  QString svg = SvgText(dir / "v.svg");
  for (const char* s : {"Face parameters", "jaw", "lips rounding", "throat", "variance explained (%)",
                        "cumulative variance explained (%)", "50.0", "15.0"})
    EXPECT_TRUE(svg.contains(QString::fromUtf8(s))) << s;
}

TEST(VarianceExplained, RefusesBadFractions) {
  testing::TempDir dir;
  std::string path = (dir / "v.png").string();
  EXPECT_THROW(SaveVarianceExplained(path, "t", {"a", "b"}, {0.5}), InvalidInput);
  EXPECT_THROW(SaveVarianceExplained(path, "t", {"a"}, {1.5}), InvalidInput);
  EXPECT_THROW(SaveVarianceExplained(path, "t", {"a"}, {NAN}), InvalidInput);
  EXPECT_THROW(SaveVarianceExplained(path, "t", {}, {}), InvalidInput);
  EXPECT_TRUE(Listing(dir.path()).empty());
}

// A 40 mm square (x −20..20, z −20..20) with a marker in the middle.
Eigen::Matrix3Xd Square() {
  Eigen::Matrix3Xd s(3, 5);
  s << -20, 20, 20, -20, 0,  //
      0, 0, 0, 0, 0,         //
      -20, -20, 20, 20, 0;
  return s;
}
Eigen::Matrix3Xd Shifted(double dx, double dz) {
  Eigen::Matrix3Xd s = Square();
  s.row(0).array() += dx;
  s.row(2).array() += dz;
  return s;
}

TEST(ParameterEffects, ExtremesMoveWhereTheEffectPutsThemAtEqualAspect) {
  testing::TempDir dir;
  std::vector<ParameterEffect> effects = {{"jaw opening", Shifted(0, -10), Shifted(0, 10)},
                                          {"lip spreading", Shifted(-5, 0), Shifted(5, 0)}};
  std::vector<std::pair<int, int>> sticks = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
  SaveParameterEffects((dir / "p.png").string(), "Face model: parameter effects", Square(), effects, sticks);
  SaveParameterEffects((dir / "p.svg").string(), "Face model: parameter effects", Square(), effects, sticks);
  auto [width, height] = ParameterEffectsSize(2);
  EXPECT_EQ(width, 600);
  EXPECT_EQ(height, 450);
  QImage image = LoadPng(dir / "p.png");
  ASSERT_EQ(image.size(), QSize(width, height));

  // Panel 1 (left half): the low square 10 mm down, the high one 10 mm up.
  int mid = width / 2;
  Box grey = Find(image, kNeutralColour, 0, mid, kHeader, height);
  Box low = Find(image, kLowColour, 0, mid, kHeader, height);
  Box high = Find(image, kHighColour, 0, mid, kHeader, height);
  ASSERT_GT(grey.count, 100);
  ASSERT_GT(low.count, 100);
  ASSERT_GT(high.count, 100);
  // Horizontal sides of all three squares are visible: the low and high boxes
  // are 40 mm squares (equal aspect), 20 mm apart; the px per mm from the width.
  double px_per_mm = (high.width() - 5) / 40.0;
  EXPECT_GT(px_per_mm, 2.0);
  EXPECT_NEAR(high.height(), high.width(), 2);
  EXPECT_NEAR(low.height(), low.width(), 2);
  EXPECT_NEAR(low.top - high.top, 20 * px_per_mm, 2);
  EXPECT_NEAR(low.left, high.left, 1);
  EXPECT_NEAR(grey.top - high.top, 10 * px_per_mm, 2);

  // Panel 2 (right half): the same scale, low 5 mm left, high 5 mm right.
  Box low2 = Find(image, kLowColour, mid, width, kHeader, height);
  Box high2 = Find(image, kHighColour, mid, width, kHeader, height);
  EXPECT_NEAR(high2.width(), high.width(), 2);
  EXPECT_NEAR(high2.left - low2.left, 10 * px_per_mm, 2);
  EXPECT_NEAR(high2.top, low2.top, 1);

  QString svg = SvgText(dir / "p.svg");
  for (const char* s :
       {"Face model: parameter effects", "jaw opening", "lip spreading", "x (mm)", "z (mm)", "neutral (mean)", "+2 sd"})
    EXPECT_TRUE(svg.contains(QString::fromUtf8(s))) << s;
}

TEST(ParameterEffects, MissingMarkersAreLeftOutAndBadInputRefused) {
  testing::TempDir dir;
  Eigen::Matrix3Xd neutral = Square();
  neutral(1, 4) = NAN;  // the middle marker is missing
  std::vector<ParameterEffect> effects = {{"a", Shifted(0, -10), Shifted(0, 10)}};
  effects[0].low(0, 4) = NAN;
  effects[0].high(0, 4) = NAN;
  std::string path = (dir / "p.png").string();
  SaveParameterEffects(path, "t", neutral, effects, {{0, 4}, {0, 1}});
  auto [width, height] = ParameterEffectsSize(1);
  QImage image = LoadPng(dir / "p.png");
  ASSERT_EQ(image.size(), QSize(width, height));
  // Four corner dots, one stick (the bottom side; the stick to the missing
  // marker is not drawn) and no dot in the middle: between the corners only one horizontal line is red.
  Box high = Find(image, kHighColour, 0, width, kHeader, height);
  ASSERT_GT(high.count, 50);
  EXPECT_NEAR(high.height(), high.width(), 2);
  Box middle = Find(image, kHighColour, high.left + high.width() / 4, high.right - high.width() / 4, kHeader, height);
  EXPECT_GT(middle.count, 20);
  EXPECT_LT(middle.height(), 4);
  EXPECT_GT(middle.top, high.bottom - 5);

  EXPECT_THROW(SaveParameterEffects(path, "t", neutral, {}, {}), InvalidInput);
  EXPECT_THROW(SaveParameterEffects(path, "t", neutral, effects, {{0, 5}}), InvalidInput);
  EXPECT_THROW(SaveParameterEffects(path, "t", neutral, effects, {{-1, 2}}), InvalidInput);
  std::vector<ParameterEffect> short_effect = {{"b", Eigen::Matrix3Xd::Zero(3, 4), Eigen::Matrix3Xd::Zero(3, 5)}};
  std::string message = ThrownMessage([&] { SaveParameterEffects(path, "t", neutral, short_effect, {}); });
  EXPECT_NE(message.find("parameter b"), std::string::npos) << message;
  Eigen::Matrix3Xd nowhere = Eigen::Matrix3Xd::Constant(3, 5, NAN);
  std::vector<ParameterEffect> nowhere_effect = {{"c", nowhere, nowhere}};
  EXPECT_THROW(SaveParameterEffects(path, "t", nowhere, nowhere_effect, {}), InvalidInput);
}

TEST(FigureFiles, UnknownExtensionIsInvalidInputNamingThePath) {
  testing::TempDir dir;
  std::vector<ErrorBar> bars = {{"u", 1, 0.1, 1.2, false}};
  for (const char* name : {"e.bmp", "e.txt", "e"}) {
    std::string path = (dir / name).string();
    EXPECT_THROW(SaveErrorBars(path, "t", bars, 0), InvalidInput);
    std::string message = ThrownMessage([&] { SaveErrorBars(path, "t", bars, 0); });
    EXPECT_NE(message.find(path), std::string::npos) << message;
  }
  EXPECT_THROW(SaveVarianceExplained((dir / "v.jpg").string(), "t", {"a"}, {0.5}), InvalidInput);
  EXPECT_THROW(SaveParameterEffects((dir / "p.gif").string(), "t", Square(), {{"a", Square(), Square()}}, {}),
               InvalidInput);
  EXPECT_TRUE(Listing(dir.path()).empty());
}

TEST(FigureFiles, UnwritablePathIsIoErrorNamingThePath) {
  testing::TempDir dir;
  std::ofstream(dir / "plain_file") << "not a folder";
  std::vector<ErrorBar> bars = {{"u", 1, 0.1, 1.2, false}};
  for (const fs::path& path : {dir / "plain_file" / "e.png", dir / "no_such_folder" / "e.svg"}) {
    std::string message = ThrownMessage([&] { SaveErrorBars(path.string(), "t", bars, 0); });
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_THROW(SaveErrorBars(path.string(), "t", bars, 0), IoError);
  }
  // A folder where the file should go: written beside it, then the rename fails.
  fs::create_directory(dir / "taken.png");
  std::ofstream(dir / "taken.png" / "inside") << "x";
  EXPECT_THROW(SaveErrorBars((dir / "taken.png").string(), "t", bars, 0), IoError);
  EXPECT_EQ(Listing(dir.path()), (std::vector<std::string>{"plain_file", "taken.png"}));  // no part file left
}

TEST(FigureFiles, AnExistingFigureIsReplaced) {
  testing::TempDir dir;
  fs::path path = dir / "e.png";
  std::ofstream(path) << "old contents";
  SaveErrorBars(path.string(), "t", {{"u", 1, 0.1, 1.2, true}}, 0);
  QImage image = LoadPng(path);
  EXPECT_EQ(image.size(), QSize(kFigureWidth, kFigureHeight));
  EXPECT_GT(Find(image, kHeldOutColour, 0, image.width(), kHeader, image.height()).count, 1000);
  EXPECT_EQ(Find(image, kTrainingColour, 0, image.width(), 0, image.height()).count, 0);
}

TEST(ErrorBars, RefusesBadNumbers) {
  testing::TempDir dir;
  std::string path = (dir / "e.png").string();
  EXPECT_THROW(SaveErrorBars(path, "t", {}, 0), InvalidInput);
  EXPECT_THROW(SaveErrorBars(path, "t", {{"u", -1, 0.1, 1, false}}, 0), InvalidInput);
  EXPECT_THROW(SaveErrorBars(path, "t", {{"u", 1, NAN, 1, false}}, 0), InvalidInput);
  EXPECT_THROW(SaveErrorBars(path, "t", {{"u", 1, 0.1, 1, false}}, INFINITY), InvalidInput);
  std::string message = ThrownMessage([&] { SaveErrorBars(path, "t", {{"utt7", -1, 0, 0, false}}, 0); });
  EXPECT_NE(message.find("utt7"), std::string::npos) << message;
  EXPECT_TRUE(Listing(dir.path()).empty());
}

}  // namespace
}  // namespace csw::report

namespace csw::report {
namespace {

constexpr Rgb kAllMissing{150, 20, 20};  // SaveGapMap's colour of a cell whose frames are all missing
constexpr Rgb kFirstFill{215, 40, 40};   // SaveGapFill's colour of the first fill

TEST(GapMap, FullyMissingCellsSitInTheMarkersRowAndTimeSpan) {
  testing::TempDir dir;
  // 4 markers, 10 s at 100 Hz; marker "B" misses 2-4 s, marker "D" 8-10 s.
  const std::vector<std::string> names = {"A", "B", "C", "D"};
  const std::vector<std::vector<std::pair<int64_t, int64_t>>> gaps = {{}, {{200, 200}}, {}, {{800, 200}}};
  SaveGapMap((dir / "g.png").string(), "Gaps of take t", names, gaps, 1000, 100.0);
  SaveGapMap((dir / "g.svg").string(), "Gaps of take t", names, gaps, 1000, 100.0);
  const QImage image = LoadPng(dir / "g.png");
  ASSERT_EQ(image.width(), kFigureWidth);
  const Box all = Find(image, kAllMissing, 0, image.width(), kHeader, image.height());
  ASSERT_GT(all.count, 0);
  // Two blocks: B's (starts at 20 % of the time axis) above D's (ends at 100 %).
  const int mid = (all.top + all.bottom) / 2;
  const Box b = Find(image, kAllMissing, 0, image.width(), all.top, mid);
  const Box d = Find(image, kAllMissing, 0, image.width(), mid + 1, all.bottom + 1);
  ASSERT_GT(b.count, 0);
  ASSERT_GT(d.count, 0);
  EXPECT_LT(b.bottom, d.top) << "B's row is above D's";
  // D's block spans 8-10 s and B's 2-4 s: the same width, D's ending at the axis end.
  EXPECT_NEAR(b.width(), d.width(), 3);
  const double axis_px = d.right - b.left;  // from 2 s to 10 s = 8 s
  EXPECT_NEAR(b.width() / axis_px, 2.0 / 8.0, 0.02);
  // One row each; C's row (no gap) lies between them, as tall as theirs.
  EXPECT_NEAR(d.top - b.bottom - 1, b.height(), 3);
  const QString svg = SvgText(dir / "g.svg");
  for (const char* s : {"Gaps of take t", "A", "B", "D", "time (s)", "fraction of frames missing"})
    EXPECT_TRUE(svg.contains(QString::fromUtf8(s))) << s;
}

TEST(GapMap, RefusesBadInputNamingTheFile) {
  testing::TempDir dir;
  const std::string path = (dir / "g.png").string();
  EXPECT_THROW(SaveGapMap(path, "t", {}, {}, 10, 100), InvalidInput);
  EXPECT_THROW(SaveGapMap(path, "t", {"A"}, {}, 10, 100), InvalidInput);
  EXPECT_THROW(SaveGapMap(path, "t", {"A"}, {{}}, 0, 100), InvalidInput);
  const std::string outside = ThrownMessage([&] { SaveGapMap(path, "t", {"A"}, {{{8, 5}}}, 10, 100); });
  EXPECT_NE(outside.find(path), std::string::npos) << outside;
  EXPECT_NE(outside.find("marker A"), std::string::npos) << outside;
  EXPECT_TRUE(Listing(dir.path()).empty());
}

TEST(GapFill, TheFillIsDrawnOnlyOverTheShadedGap) {
  testing::TempDir dir;
  const int n = 101;  // 1 s at 100 Hz; the gap is 0.4-0.6 s
  std::vector<double> t(n);
  Eigen::Matrix3Xd measured(3, n), truth(3, n), fill(3, n);
  for (int i = 0; i < n; ++i) {
    t[static_cast<size_t>(i)] = i / 100.0;
    for (int c = 0; c < 3; ++c) truth(c, i) = 10 * std::sin(6.283 * t[static_cast<size_t>(i)] + c);
    measured.col(i) = truth.col(i);
    fill.col(i) = truth.col(i).array() + 0.5;
    if (i > 40 && i < 60) measured.col(i).setConstant(NAN);
  }
  SaveGapFill((dir / "f.png").string(), "Marker X", t, measured, truth, {{"spline fill", fill}}, 0.40, 0.60);
  SaveGapFill((dir / "f.svg").string(), "Marker X", t, measured, truth, {{"spline fill", fill}}, 0.40, 0.60);
  const QImage image = LoadPng(dir / "f.png");
  ASSERT_EQ(image.size(), QSize(kFigureWidth, 900));
  // The fill's colour below the legend: only over a fifth of the time axis, in the middle.
  const int below_legend = 130;
  const Box f = Find(image, kFirstFill, 0, image.width(), below_legend, image.height());
  ASSERT_GT(f.count, 0);
  const Box dots = Find(image, Rgb{20, 20, 20}, 0, image.width(), below_legend, image.height());
  ASSERT_GT(dots.count, 0);
  const double axis_px = dots.right - dots.left;  // the measured samples span 0-1 s
  EXPECT_NEAR(f.width() / axis_px, 0.2, 0.03);
  EXPECT_NEAR((f.left - dots.left) / axis_px, 0.4, 0.03);
  const QString svg = SvgText(dir / "f.svg");
  for (const char* s : {"Marker X", "spline fill", "truth (clean capture)", "measured", "x (mm)", "z (mm)"})
    EXPECT_TRUE(svg.contains(QString::fromUtf8(s))) << s;
  EXPECT_THROW(SaveGapFill((dir / "bad.png").string(), "t", t, measured.leftCols(5), truth, {}, 0, 1), InvalidInput);
}

}  // namespace
}  // namespace csw::report

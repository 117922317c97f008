// The analysis figures (gestural score, histograms, confusion matrix) written to
// PNG and SVG and checked in the files: sizes, the shaded cells where the counts
// put them, the statistics each histogram panel prints (computed here by hand),
// and one clear error for bad data.
#include "workbench/report/analysis_figures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "tests/report/report_testing.h"
#include "tests/testing/testing.h"
#include "workbench/report/report.h"

namespace csw::report {
namespace {

// The darkest colour of the confusion matrix's gradient (a row fraction of 1).
constexpr Rgb kFullCell{20, 50, 140};

int CountColour(const QImage& image, Rgb c) {
  int n = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      const QRgb p = image.pixel(x, y);
      if (qRed(p) == c.r && qGreen(p) == c.g && qBlue(p) == c.b) ++n;
    }
  return n;
}

TEST(ConfusionMatrix, FullRowsAreShadedAndCountsAndAccuraciesPrinted) {
  testing::TempDir dir;
  const std::vector<std::string> labels{"1", "2", "3"};
  // Rows: class 1 always right (10), class 2 always taken for 3 (4), class 3 split 3/1.
  const std::vector<std::vector<int>> counts{{10, 0, 0}, {0, 0, 4}, {0, 1, 3}};
  SaveConfusionMatrix((dir / "c.png").string(), "shapes", labels, counts);
  const QImage image = LoadPng(dir / "c.png");
  // 3 classes: the plot is max(300, 60·3) + 260 wide and + 170 high.
  EXPECT_EQ(image.width(), 560);
  EXPECT_EQ(image.height(), 470);
  // Two cells hold a whole row (1→1 and 2→3): each a third of the ~400 × 380 px
  // plot area in each direction (about 130 px square), less its printed count.
  const int full = CountColour(image, kFullCell);
  EXPECT_GT(full, 2 * 100 * 100);
  EXPECT_LT(full, 2 * 150 * 150);

  SaveConfusionMatrix((dir / "c.svg").string(), "shapes", labels, counts);
  const QString text = SvgText(dir / "c.svg");
  EXPECT_TRUE(text.contains(QStringLiteral("100.0 % of 10"))) << text.toStdString();
  EXPECT_TRUE(text.contains(QStringLiteral("0.0 % of 4"))) << text.toStdString();
  EXPECT_TRUE(text.contains(QStringLiteral("75.0 % of 4"))) << text.toStdString();

  // No count at all: no cell is shaded.
  SaveConfusionMatrix((dir / "z.png").string(), "none", labels, {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}});
  EXPECT_EQ(CountColour(LoadPng(dir / "z.png"), kFullCell), 0);
}

TEST(ConfusionMatrix, RefusesBadShapesAndCountsNamingTheFile) {
  testing::TempDir dir;
  const std::string path = (dir / "bad.png").string();
  EXPECT_THROW(SaveConfusionMatrix(path, "t", {}, {}), InvalidInput);
  try {
    SaveConfusionMatrix(path, "t", {"a", "b"}, {{1, 2}, {3}});
    FAIL() << "a ragged matrix was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("row b"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SaveConfusionMatrix(path, "t", {"a"}, {{-1}}), InvalidInput);
}

TEST(Histograms, EachPanelPrintsItsCountMeanAndSd) {
  testing::TempDir dir;
  // Panel A: 10, 20, 30, 40 -> mean 25, sample sd sqrt(500/3) = 12.9.
  // Panel B: -100, -80 and a NaN left out -> mean -90, sd 14.1.
  std::vector<HistogramPanel> panels(3);
  panels[0].title = "CV placement onset";
  panels[0].values_ms = {10, 20, 30, 40};
  panels[0].reference_ms = 37;
  panels[0].reference_name = "Attina 2005";
  panels[1].title = "CV shape onset";
  panels[1].values_ms = {-100, -80, std::nan("")};
  panels[2].title = "V shape target";
  SaveHistograms((dir / "h.svg").string(), "phasing", panels, 10, "time from A1 (ms)");
  const QString text = SvgText(dir / "h.svg");
  EXPECT_TRUE(text.contains(QStringLiteral("n = 4, mean 25.0 ms, sd 12.9 ms"))) << text.toStdString();
  EXPECT_TRUE(text.contains(QStringLiteral("n = 2, mean -90.0 ms, sd 14.1 ms"))) << text.toStdString();
  EXPECT_TRUE(text.contains(QStringLiteral("no data"))) << text.toStdString();
  EXPECT_TRUE(text.contains(QStringLiteral("Attina 2005"))) << text.toStdString();

  SaveHistograms((dir / "h.png").string(), "phasing", panels, 10, "time from A1 (ms)");
  const QImage image = LoadPng(dir / "h.png");
  // Three panels in one row: 320 px each (at least 700), one row of 300 px + 90.
  EXPECT_EQ(image.width(), 960);
  EXPECT_EQ(image.height(), 390);
  EXPECT_GT(CountColour(image, {215, 40, 40}), 20);  // the reference line is drawn

  EXPECT_THROW(SaveHistograms((dir / "x.png").string(), "t", {}, 10, "ms"), InvalidInput);
  EXPECT_THROW(SaveHistograms((dir / "x.png").string(), "t", panels, 0, "ms"), InvalidInput);
  panels[0].values_ms.push_back(INFINITY);
  EXPECT_THROW(SaveHistograms((dir / "x.png").string(), "t", panels, 10, "ms"), InvalidInput);
}

TEST(GesturalScore, LanesTiersAndWaveformShareTheTimeAxis) {
  testing::TempDir dir;
  // 2 s at 100 Hz: class 0 dominates the first second, class 1 the second.
  PosteriorLane lane;
  lane.name = "hand shape";
  lane.classes = {"0", "1"};
  lane.posteriors.resize(200, 2);
  for (int f = 0; f < 200; ++f) {
    lane.posteriors(f, 0) = f < 100 ? 0.9 : 0.1;
    lane.posteriors(f, 1) = 1 - lane.posteriors(f, 0);
  }
  std::vector<float> audio(16000);
  for (size_t i = 0; i < audio.size(); ++i) audio[i] = 0.5f * static_cast<float>(std::sin(0.05 * i));
  LabelTier phones{"phones", LabelTier::Kind::kInterval, 0, 2, {{0.2, 0.9, "b"}, {0.9, 1.6, "on"}}};
  LabelTier keys{"keys", LabelTier::Kind::kPoint, 0, 2, {{0.8, 0.8, "24"}}};
  SaveGesturalScore((dir / "g.png").string(), "score", audio, 8000, 0.0, {lane}, 100, {phones, keys}, 0, 2);
  const QImage image = LoadPng(dir / "g.png");
  // 110 + waveform 130 + 2 tiers × 48 + 1 lane × 190.
  EXPECT_EQ(image.width(), kFigureWidth);
  EXPECT_EQ(image.height(), 110 + 130 + 96 + 190);
  // Both class lines are drawn in their palette colours (tab10 blue and orange).
  EXPECT_GT(CountColour(image, {31, 119, 180}), 200);
  EXPECT_GT(CountColour(image, {255, 127, 14}), 200);

  SaveGesturalScore((dir / "g.svg").string(), "score", audio, 8000, 0.0, {lane}, 100, {phones, keys}, 0, 2);
  const QString text = SvgText(dir / "g.svg");
  for (const char* s : {"on", "24", "phones", "keys", "time (s)"})
    EXPECT_TRUE(text.contains(QString::fromUtf8(s))) << s;

  PosteriorLane bad = lane;
  bad.posteriors(5, 1) = 1.5;
  EXPECT_THROW(SaveGesturalScore((dir / "b.png").string(), "t", {}, 0, 0, {bad}, 100, {}, 0, 2), InvalidInput);
  bad = lane;
  bad.classes.pop_back();
  EXPECT_THROW(SaveGesturalScore((dir / "b.png").string(), "t", {}, 0, 0, {bad}, 100, {}, 0, 2), InvalidInput);
  EXPECT_THROW(SaveGesturalScore((dir / "b.png").string(), "t", {}, 0, 0, {lane}, 100, {}, 2, 1), InvalidInput);
  EXPECT_THROW(SaveGesturalScore((dir / "b.png").string(), "t", {}, 0, 0, {}, 100, {}, 0, 1), InvalidInput);
}

}  // namespace
}  // namespace csw::report

// The workbench driven through its real widgets, offscreen: a corpus made here
// with known marker paths, tiers and audio; keyboard stepping, marker picking,
// plot zoom, figure export, background import with Cancel, damaged files and
// the remembered layout. Every check compares with the values written.
#include <gtest/gtest.h>
#include <qcustomplot.h>

#include <QApplication>
#include <QDockWidget>
#include <QFile>
#include <QImage>
#include <QProgressBar>
#include <QProgressDialog>
#include <QPushButton>
#include <QSignalSpy>
#include <QStatusBar>
#include <QTest>
#include <QTimer>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <semaphore>

#include "core/markerset.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "tests/gui/take_wait.h"
#include "tests/testing/testing.h"
#include "workbench/gui/corpus_browser.h"
#include "workbench/gui/import_runner.h"
#include "workbench/gui/job_runner.h"
#include "workbench/gui/log_panel.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/marker_view.h"
#include "workbench/gui/playback.h"
#include "workbench/gui/timeseries_panel.h"

namespace csw::gui {
namespace {

namespace fs = std::filesystem;
constexpr double kRate = 100.0;
constexpr int kFrames = 50;

// Known paths: m0 moves at (1, 2, 2) mm per frame (speed 300 mm/s at 100 Hz);
// m1 circles; m2 is missing in frames 10-14 and 30-31 (two gaps).
std::array<float, 3> Expected(int marker, int frame) {
  switch (marker) {
    case 0:
      return {10.0f + frame, 20.0f + 2.0f * frame, 30.0f + 2.0f * frame};
    case 1:
      return {static_cast<float>(100 * std::cos(frame * 0.1)), static_cast<float>(100 * std::sin(frame * 0.1)), 50.0f};
    default:
      return {-40.0f, 5.0f * frame, 80.0f};
  }
}
bool Missing(int marker, int frame) {
  return marker == 2 && ((frame >= 10 && frame <= 14) || frame == 30 || frame == 31);
}

Take MakeAlpha() {
  Take t;
  t.name = "alpha";
  t.rate_hz = kRate;
  t.marker_names = {"m0", "m1", "m2"};
  t.markers.Resize(kFrames, 3);
  for (int f = 0; f < kFrames; ++f) {
    for (int k = 0; k < 3; ++k) {
      if (Missing(k, f)) continue;
      auto p = Expected(k, f);
      std::copy(p.begin(), p.end(), t.markers.at(f, k));
    }
  }
  LabelTier words{
      "words", LabelTier::Kind::kInterval, 0.0, 0.5, {{0.0, 0.1, ""}, {0.1, 0.3, "hello"}, {0.3, 0.5, "world"}}};
  LabelTier cues{"cues", LabelTier::Kind::kPoint, 0.0, 0.5, {{0.05, 0.05, "side"}, {0.25, 0.25, "chin"}}};
  t.tiers = {words, cues};
  t.audio.rate_hz = 8000;
  t.audio.channels = 1;
  for (int i = 0; i < 4000; ++i)
    t.audio.samples.push_back(static_cast<float>(0.5 * std::sin(2 * M_PI * 200 * i / 8000.0)));
  return t;
}

Take MakeBeta() {
  Take t;
  t.name = "beta";
  t.rate_hz = 60;
  t.marker_names = {"a", "b"};
  t.markers.Resize(30, 2);
  for (int f = 0; f < 30; ++f)
    for (int k = 0; k < 2; ++k) {
      float* p = t.markers.at(f, k);
      p[0] = static_cast<float>(k * 10);
      p[1] = static_cast<float>(f);
      p[2] = 0;
    }
  return t;
}

class ViewerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    corpus_ = (dir_ / "corpus.h5").string();
    CorpusTransaction tx(corpus_);
    tx.WriteTake(MakeAlpha());
    tx.WriteTake(MakeBeta());
    tx.Commit();
  }

  // A shown, active window (keyboard shortcuts need an active window).
  std::unique_ptr<MainWindow> OpenWindow() {
    auto w = std::make_unique<MainWindow>(QString::fromStdString((dir_ / "settings.ini").string()));
    w->playback()->SetAudioEnabled(false);
    w->resize(1200, 800);
    w->show();
    QApplication::setActiveWindow(w.get());
    EXPECT_TRUE(QTest::qWaitForWindowActive(w.get()));
    return w;
  }

  std::vector<std::string> TakeNames() const {
    std::vector<std::string> names;
    for (const auto& s : Corpus::Open(corpus_).Takes()) names.push_back(s.name);
    return names;
  }

  testing::TempDir dir_;
  std::string corpus_;
};

TEST_F(ViewerTest, OpenCorpusListsTakesWithTheirFacts) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  CorpusBrowser* b = w->browser();
  ASSERT_EQ(b->take_count(), 2);
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kName), "alpha");
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kDuration), "0:00.5");
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kRate), "100");
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kFrames), "50");
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kMarkers), "3");
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kGaps), "2");
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kTiers), "words, cues");
  EXPECT_EQ(b->Cell(0, CorpusBrowser::kAudio), "yes");
  EXPECT_EQ(b->Cell(1, CorpusBrowser::kName), "beta");
  EXPECT_EQ(b->Cell(1, CorpusBrowser::kGaps), "0");
  EXPECT_EQ(b->Cell(1, CorpusBrowser::kAudio), "no");
  // The first take is shown at once: audio + two tiers + the first marker's lane.
  ASSERT_TRUE(w->take());
  EXPECT_EQ(w->take()->name, "alpha");
  ASSERT_EQ(w->plots()->lane_count(), 4);
  EXPECT_EQ(w->plots()->lane_kind(0), TimeSeriesPanel::LaneKind::kAudio);
  EXPECT_EQ(w->plots()->lane_name(1), "words");
  EXPECT_EQ(w->plots()->lane_name(2), "cues");
  EXPECT_EQ(w->plots()->lane_kind(3), TimeSeriesPanel::LaneKind::kMarker);
  // Selecting the other take through the browser shows it when it has loaded (off the GUI thread).
  QSignalSpy shown(w.get(), &MainWindow::TakeShown);
  b->setCurrentItem(b->topLevelItem(1));
  EXPECT_TRUE(w->take_loading());
  EXPECT_EQ(w->loading_take(), "beta");
  ASSERT_TRUE(shown.wait(kHangGuardMs));
  EXPECT_EQ(shown.at(0).at(0).toString(), "beta");
  EXPECT_FALSE(w->take_loading());
  ASSERT_TRUE(w->take());
  EXPECT_EQ(w->take()->name, "beta");
  EXPECT_EQ(w->marker_view()->DrawnMarkerCount(), 2);
  EXPECT_EQ(w->recent_files().value(0), QFileInfo(QString::fromStdString(corpus_)).absoluteFilePath());
}

TEST_F(ViewerTest, KeyboardStepsKeepViewAndPlotsOnTheSameFrame) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  ASSERT_TRUE(SelectAndWait(w.get(), "alpha"));
  w->quantity_combo()->setCurrentIndex(2);  // z
  w->plots()->SetMarkerSeries(0, MarkerQuantity::kZ);
  MarkerView* view = w->marker_view();
  TimeSeriesPanel* plots = w->plots();

  auto check_frame = [&](int f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    EXPECT_EQ(w->playback()->frame(), f);
    EXPECT_EQ(view->frame(), f);
    EXPECT_DOUBLE_EQ(plots->cursor_time(), f / kRate);
    for (int lane = 0; lane < plots->lane_count(); ++lane) EXPECT_DOUBLE_EQ(plots->LaneCursorTime(lane), f / kRate);
    // The 3D view draws each visible marker where the camera projects its known position.
    int visible = 0;
    for (int k = 0; k < 3; ++k) {
      auto pos = view->MarkerScreenPos(k);
      if (Missing(k, f)) {
        EXPECT_FALSE(pos.has_value()) << "marker " << k << " is missing and must not be drawn";
        continue;
      }
      ++visible;
      auto e = Expected(k, f);
      auto want = Project(view->camera(), QSizeF(view->size()), {e[0], e[1], e[2]});
      ASSERT_TRUE(pos && want);
      EXPECT_NEAR(pos->x(), want->pos.x(), 1e-6);
      EXPECT_NEAR(pos->y(), want->pos.y(), 1e-6);
    }
    EXPECT_EQ(view->DrawnMarkerCount(), visible);
    // The marker lane's readout is m0's z at this frame.
    EXPECT_EQ(plots->LaneReadout(3), QString("m0 z: %1 mm").arg(30.0 + 2.0 * f, 0, 'f', 2));
    // Tier readouts follow the cursor.
    double t = f / kRate;
    QString word = t < 0.1 ? "" : t < 0.3 ? "hello" : "world";
    EXPECT_EQ(plots->LaneReadout(1), "words: " + word);
  };

  check_frame(0);
  QTest::keyClick(w.get(), Qt::Key_Right);
  QTest::keyClick(w.get(), Qt::Key_Right);
  QTest::keyClick(w.get(), Qt::Key_Right);
  check_frame(3);
  QTest::keyClick(w.get(), Qt::Key_Right, Qt::ShiftModifier);
  check_frame(13);  // m2 is missing here
  QTest::keyClick(w.get(), Qt::Key_Left);
  check_frame(12);
  QTest::keyClick(w.get(), Qt::Key_End);
  check_frame(kFrames - 1);
  QTest::keyClick(w.get(), Qt::Key_Right);  // clamps at the last frame
  check_frame(kFrames - 1);
  QTest::keyClick(w.get(), Qt::Key_Home);
  check_frame(0);
  // Clicking a time in the plots seeks there (scrubbing).
  QCustomPlot* plot = plots->plot();
  QCPAxis* x = plot->axisRects().back()->axis(QCPAxis::atBottom);
  double y = plot->axisRects().back()->rect().center().y();
  QTest::mouseClick(plot, Qt::LeftButton, {},
                    QPoint(static_cast<int>(std::lround(x->coordToPixel(0.205))), static_cast<int>(y)));
  int f = w->playback()->frame();
  EXPECT_NEAR(f, 20, 1);
  check_frame(f);
}

TEST_F(ViewerTest, PlaybackRunsAtTheCaptureRateAndStopsAtTheEnd) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  QElapsedTimer clock;
  clock.start();
  QTest::keyClick(w.get(), Qt::Key_Space);
  EXPECT_TRUE(w->playback()->playing());
  QTest::qWait(150);
  qint64 frame = w->playback()->frame();
  double elapsed = clock.nsecsElapsed() * 1e-9;
  EXPECT_GT(frame, 0);
  EXPECT_LE(frame, elapsed * kRate + 1);  // never ahead of the clock
  EXPECT_EQ(w->marker_view()->frame(), frame);
  QTest::keyClick(w.get(), Qt::Key_Space);
  EXPECT_FALSE(w->playback()->playing());
  QTest::keyClick(w.get(), Qt::Key_Space);
  EXPECT_TRUE(QTest::qWaitFor([&] { return !w->playback()->playing(); }, 3000));
  EXPECT_EQ(w->playback()->frame(), kFrames - 1);
  EXPECT_EQ(w->marker_view()->frame(), kFrames - 1);
}

// Regression (found by the screenshot tour): switching takes used the previous
// take's frame for the new take's cursor and paged the plots off the start.
TEST_F(ViewerTest, SwitchingTakesRewindsAndShowsTheWholeNewTake) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  w->playback()->Seek(45);
  w->plots()->SetTimeRange(0.3, 0.5);
  ASSERT_TRUE(SelectAndWait(w.get(), "beta"));
  EXPECT_EQ(w->playback()->frame(), 0);
  EXPECT_EQ(w->marker_view()->frame(), 0);
  EXPECT_DOUBLE_EQ(w->plots()->cursor_time(), 0.0);
  EXPECT_DOUBLE_EQ(w->plots()->view_start(), 0.0);
  EXPECT_DOUBLE_EQ(w->plots()->view_end(), 0.5);  // 30 frames at 60 Hz
}

// Issue 16: the GUI thread never waits on HDF5. A take chosen in the browser
// loads on a worker thread, held here before it reads the corpus: meanwhile the
// event loop runs (a timer ticks, the 3D view repaints, a key steps the shown
// take) and the status bar shows the load as busy; released, the take shows.
// A later selection supersedes a load still running (its take is never
// shown); a take that cannot be loaded is logged, without a modal dialog.
TEST_F(ViewerTest, ATakeLoadsOffTheGuiThreadWhileTheWindowKeepsRunning) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  ASSERT_EQ(w->take()->name, "alpha");

  // Holds the loader's worker before it reads the corpus, once, until released.
  struct Hold {
    std::atomic<bool> reached{false};
    std::atomic<bool> done{false};
    std::binary_semaphore resume{0};
    bool given = false;
    void Release() {
      if (given) return;
      given = true;
      resume.release();
    }
  };
  auto hold = std::make_shared<Hold>();
  struct Guard {
    std::shared_ptr<Hold> hold;
    ~Guard() {
      if (hold->reached.load()) hold->Release();
    }
  } guard{hold};
  w->take_loader()->SetWorkerHook([hold](const std::string& stage, double fraction) {
    if (hold->done.load() || stage != "loading take" || fraction != 0.0) return;
    hold->reached = true;
    hold->resume.acquire();
    hold->done = true;
  });

  // Event-loop witnesses: a 5 ms timer (the longest gap between its ticks) and the 3D view's paints.
  struct Paints : QObject {
    int count = 0;
    bool eventFilter(QObject*, QEvent* e) override {
      count += e->type() == QEvent::Paint;
      return false;
    }
  } paints;
  w->marker_view()->installEventFilter(&paints);
  QElapsedTimer clock;
  qint64 last_tick = 0, max_gap_ms = 0;
  int ticks = 0;
  QTimer timer;
  timer.setInterval(5);
  QObject::connect(&timer, &QTimer::timeout, [&] {
    const qint64 now = clock.elapsed();
    max_gap_ms = std::max(max_gap_ms, now - last_tick);
    last_tick = now;
    ++ticks;
  });
  clock.start();
  timer.start();

  QSignalSpy shown(w.get(), &MainWindow::TakeShown);
  CorpusBrowser* b = w->browser();
  b->setCurrentItem(b->topLevelItem(1));  // beta
  EXPECT_TRUE(w->take_loading());
  EXPECT_EQ(w->loading_take(), "beta");
  auto* busy = w->findChild<QProgressBar*>("takeLoadBusy");
  ASSERT_NE(busy, nullptr);
  EXPECT_TRUE(busy->isVisible());
  EXPECT_TRUE(w->statusBar()->currentMessage().contains("Loading take beta"))
      << w->statusBar()->currentMessage().toStdString();
  ASSERT_TRUE(QTest::qWaitFor([&] { return hold->reached.load(); }, kHangGuardMs));
  // Held: the loop keeps running and the window keeps working on the shown take.
  const int ticks_before = ticks, paints_before = paints.count;
  w->marker_view()->update();
  EXPECT_TRUE(QTest::qWaitFor([&] { return ticks >= ticks_before + 10 && paints.count > paints_before; }, 5000))
      << ticks - ticks_before << " ticks, " << paints.count - paints_before << " paints";
  QTest::keyClick(w.get(), Qt::Key_Right);
  EXPECT_EQ(w->marker_view()->frame(), 1);
  ASSERT_EQ(w->take()->name, "alpha");  // not shown before it has loaded
  EXPECT_EQ(shown.count(), 0);
  EXPECT_TRUE(w->take_loading());
  // Released: beta shows, rewound, and the busy indication goes.
  hold->Release();
  ASSERT_TRUE(shown.wait(kHangGuardMs));
  EXPECT_EQ(shown.at(0).at(0).toString(), "beta");
  EXPECT_EQ(w->take()->name, "beta");
  EXPECT_EQ(w->marker_view()->DrawnMarkerCount(), 2);
  EXPECT_EQ(w->marker_view()->frame(), 0);
  EXPECT_FALSE(w->take_loading());
  EXPECT_FALSE(busy->isVisible());
  EXPECT_GE(ticks, ticks_before + 10);
  // A loose bound (offscreen, on a loaded machine): the loop never stalled for long.
  EXPECT_LT(max_gap_ms, 1000);

  // A later selection supersedes an earlier one still loading: alpha's load
  // is held, beta (shown) is chosen again, then alpha is released: alpha is
  // never shown.
  shown.clear();
  hold = std::make_shared<Hold>();
  guard.hold = hold;
  w->take_loader()->SetWorkerHook([hold](const std::string& stage, double fraction) {
    if (hold->done.load() || stage != "loading take" || fraction != 0.0) return;
    hold->reached = true;
    hold->resume.acquire();
    hold->done = true;
  });
  ASSERT_TRUE(w->SelectTake("alpha"));
  ASSERT_TRUE(QTest::qWaitFor([&] { return hold->reached.load(); }, kHangGuardMs));
  ASSERT_TRUE(w->SelectTake("beta"));
  EXPECT_FALSE(w->take_loading());
  hold->Release();
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w->take_loader()->running(); }, kHangGuardMs));
  QTest::qWait(0);  // the loader's end is a queued call
  QCoreApplication::processEvents();
  EXPECT_EQ(shown.count(), 0);
  EXPECT_EQ(w->take()->name, "beta");
  EXPECT_EQ(b->current_take(), "beta");
  // Then alpha, chosen twice in a row, loads once and shows.
  w->take_loader()->SetWorkerHook(nullptr);
  ASSERT_TRUE(w->SelectTake("alpha"));
  ASSERT_TRUE(w->SelectTake("alpha"));
  ASSERT_TRUE(WaitForTake(w.get(), "alpha"));
  EXPECT_EQ(shown.count(), 1);

  // A take that cannot be loaded: an error in the log and the status line, no modal dialog, alpha stays.
  QSignalSpy failed(w.get(), &MainWindow::TakeLoadFailed);
  const int errors = w->log()->CountLevel(LogPanel::Level::kError);
  ASSERT_TRUE(w->SelectTake("no_such_take"));
  ASSERT_TRUE(failed.wait(kHangGuardMs));
  EXPECT_EQ(failed.at(0).at(0).toString(), "no_such_take");
  EXPECT_EQ(w->log()->CountLevel(LogPanel::Level::kError), errors + 1);
  EXPECT_TRUE(w->log()->entries().back().contains("no_such_take"));
  EXPECT_TRUE(w->statusBar()->currentMessage().contains("Cannot load take no_such_take"));
  EXPECT_EQ(QApplication::activeModalWidget(), nullptr);
  EXPECT_EQ(w->take()->name, "alpha");
  EXPECT_FALSE(w->take_loading());
  w->marker_view()->removeEventFilter(&paints);
}

TEST_F(ViewerTest, ClickingAMarkerShowsItsNameAndCoordinates) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  w->playback()->Seek(7);
  MarkerView* view = w->marker_view();
  auto pos = view->MarkerScreenPos(1);
  ASSERT_TRUE(pos);
  QTest::mouseClick(view, Qt::LeftButton, {}, pos->toPoint());
  EXPECT_EQ(view->selected_marker(), 1);
  auto e = Expected(1, 7);
  EXPECT_EQ(view->SelectionText(),
            QString("m1: %1, %2, %3 mm").arg(e[0], 0, 'f', 2).arg(e[1], 0, 'f', 2).arg(e[2], 0, 'f', 2));
  EXPECT_EQ(w->plots()->marker(), 1);  // the plots follow the pick
  EXPECT_TRUE(w->log()->entries().back().startsWith("m1: "));
  // A missing marker says so instead of showing stale coordinates.
  view->SelectMarker(2);
  w->playback()->Seek(12);
  EXPECT_EQ(view->SelectionText(), "m2: missing at frame 13");
  // Dragging orbits instead of picking.
  double yaw = view->camera().yaw_deg;
  QTest::mousePress(view, Qt::LeftButton, {}, QPoint(100, 100));
  QMouseEvent move(QEvent::MouseMove, QPointF(160, 100), view->mapToGlobal(QPointF(160, 100)), Qt::NoButton,
                   Qt::LeftButton, Qt::NoModifier);
  QApplication::sendEvent(view, &move);
  QTest::mouseRelease(view, Qt::LeftButton, {}, QPoint(160, 100));
  EXPECT_NEAR(view->camera().yaw_deg, yaw - 0.4 * 60, 1e-9);
  EXPECT_EQ(view->selected_marker(), 2);
}

TEST_F(ViewerTest, SticksAndClusterFramesFromTheMarkerSet) {
  MarkerSet set;
  set.name = "test";
  set.head_cluster = {"m0", "m1", "m2"};
  set.sticks = {{"m0", "m1"}, {"m1", "m2"}};
  fs::path set_path = dir_ / "set.json";
  std::ofstream(set_path) << MarkerSetToJson(set);
  auto w = OpenWindow();
  ASSERT_TRUE(w->LoadMarkerSetFile(QString::fromStdString(set_path.string())));
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  w->playback()->Seek(5);
  EXPECT_EQ(w->marker_view()->DrawnStickCount(), 2);
  EXPECT_EQ(w->marker_view()->DrawnClusterFrameCount(), 1);
  w->playback()->Seek(11);  // m2 missing: one stick, and too few markers for a frame
  EXPECT_EQ(w->marker_view()->DrawnStickCount(), 1);
  EXPECT_EQ(w->marker_view()->DrawnClusterFrameCount(), 0);
}

TEST(ClusterFrame, KnownAxes) {
  MarkerArray m(1, 3);
  const float pts[3][3] = {{0, 0, 0}, {10, 0, 0}, {0, 5, 0}};
  for (int k = 0; k < 3; ++k) std::copy(pts[k], pts[k] + 3, m.at(0, k));
  auto f = ComputeClusterFrame(m, 0, {0, 1, 2});
  ASSERT_TRUE(f);
  EXPECT_NEAR(f->origin[0], 10.0 / 3, 1e-12);
  EXPECT_NEAR(f->origin[1], 5.0 / 3, 1e-12);
  EXPECT_EQ(f->axes[0], (std::array<double, 3>{1, 0, 0}));
  EXPECT_EQ(f->axes[1], (std::array<double, 3>{0, 1, 0}));
  EXPECT_EQ(f->axes[2], (std::array<double, 3>{0, 0, 1}));
  const float line[3] = {20, 0, 0};  // collinear: no frame
  std::copy(line, line + 3, m.at(0, 2));
  EXPECT_FALSE(ComputeClusterFrame(m, 0, {0, 1, 2}));
}

TEST(MarkerSeriesTest, SpeedOfAConstantVelocityMarker) {
  Take t = MakeAlpha();
  auto speed = MarkerSeries(t, 0, MarkerQuantity::kSpeed);
  ASSERT_EQ(speed.size(), static_cast<size_t>(kFrames));
  for (float v : speed) EXPECT_NEAR(v, 300.0, 1e-3);  // |(1, 2, 2)| mm per frame × 100 Hz
  auto gaps = MarkerSeries(t, 2, MarkerQuantity::kY);
  EXPECT_TRUE(std::isnan(gaps[10]));
  EXPECT_EQ(gaps[9], 45.0f);
  auto gap_speed = MarkerSeries(t, 2, MarkerQuantity::kSpeed);
  EXPECT_TRUE(std::isnan(gap_speed[12]));
  EXPECT_NEAR(gap_speed[9], 500.0, 1e-3);  // one-sided next to the gap: 5 mm per frame
}

TEST_F(ViewerTest, ZoomIsSharedByAllLanes) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  TimeSeriesPanel* plots = w->plots();
  ASSERT_GE(plots->lane_count(), 3);
  EXPECT_DOUBLE_EQ(plots->view_start(), 0.0);
  EXPECT_DOUBLE_EQ(plots->view_end(), 0.5);
  plots->ZoomTime(0.5, 0.25);
  for (int lane = 0; lane < plots->lane_count(); ++lane) {
    EXPECT_DOUBLE_EQ(plots->LaneViewStart(lane), 0.125);
    EXPECT_DOUBLE_EQ(plots->LaneViewEnd(lane), 0.375);
  }
  // The mouse wheel over one lane zooms every lane together.
  QCustomPlot* plot = plots->plot();
  QPoint at = plot->axisRects().front()->rect().center();
  QWheelEvent wheel(QPointF(at), plot->mapToGlobal(QPointF(at)), QPoint(), QPoint(0, 120), Qt::NoButton, Qt::NoModifier,
                    Qt::NoScrollPhase, false);
  QApplication::sendEvent(plot, &wheel);
  double width = plots->view_end() - plots->view_start();
  EXPECT_LT(width, 0.25 - 1e-6);
  for (int lane = 0; lane < plots->lane_count(); ++lane) {
    EXPECT_DOUBLE_EQ(plots->LaneViewStart(lane), plots->view_start());
    EXPECT_DOUBLE_EQ(plots->LaneViewEnd(lane), plots->view_end());
  }
  // Zoomed in far enough, the audio lane shows the samples themselves.
  plots->SetTimeRange(0.1, 0.15);
  auto samples = static_cast<int>(std::ceil(0.15 * 8000) - std::floor(0.1 * 8000)) + 1;  // both ends included
  EXPECT_EQ(plots->LanePointCount(0), samples);
  // Zoomed out, it is decimated to at most two points per pixel column.
  plots->ShowAll();
  EXPECT_LE(plots->LanePointCount(0), 2 * plot->axisRects().front()->width() + 2);
  EXPECT_GT(plots->LanePointCount(0), 100);
}

TEST_F(ViewerTest, FiguresExportAsPngSvgAndPdf) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  QString png = QString::fromStdString((dir_ / "plots.png").string());
  QString svg = QString::fromStdString((dir_ / "plots.svg").string());
  QString pdf = QString::fromStdString((dir_ / "plots.pdf").string());
  QString view_png = QString::fromStdString((dir_ / "view.png").string());
  QString view_svg = QString::fromStdString((dir_ / "view.svg").string());
  ASSERT_TRUE(w->ExportPlot(png, 800, 400));
  ASSERT_TRUE(w->ExportPlot(svg, 800, 400));
  ASSERT_TRUE(w->ExportPlot(pdf, 800, 400));
  ASSERT_TRUE(w->Export3dView(view_png));
  ASSERT_TRUE(w->Export3dView(view_svg));
  QImage image(png);
  ASSERT_FALSE(image.isNull());
  EXPECT_EQ(image.size(), QSize(800, 400));
  // The figure is not blank: the waveform is drawn in the plot's blue.
  int blue = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) blue += image.pixelColor(x, y) == QColor(40, 90, 160);
  EXPECT_GT(blue, 100);
  QFile s(svg);
  ASSERT_TRUE(s.open(QIODevice::ReadOnly));
  QByteArray svg_text = s.readAll();
  EXPECT_TRUE(svg_text.contains("<svg"));
  EXPECT_TRUE(svg_text.contains("hello"));  // the tier's label is text in the drawing
  QFile p(pdf);
  ASSERT_TRUE(p.open(QIODevice::ReadOnly));
  EXPECT_TRUE(p.read(5) == "%PDF-");
  EXPECT_EQ(QImage(view_png).size(), w->marker_view()->size());
  QFile vs(view_svg);
  ASSERT_TRUE(vs.open(QIODevice::ReadOnly));
  EXPECT_TRUE(vs.readAll().contains("alpha"));
  // An unknown format is refused with a log line, not a crash.
  EXPECT_FALSE(w->ExportPlot(QString::fromStdString((dir_ / "plots.bmpx").string())));
  EXPECT_TRUE(w->log()->entries().back().startsWith("error: Figure not saved"));
}

TEST_F(ViewerTest, CancellingABackgroundImportMidwayLeavesTheCorpusUnchanged) {
  // Two captures big enough to be mid-import when the second one starts.
  std::vector<std::string> files;
  for (const char* name : {"gamma", "delta"}) {
    Take t = MakeBeta();
    t.name = name;
    t.rate_hz = 120;
    t.marker_names.clear();
    for (int k = 0; k < 40; ++k) t.marker_names.push_back("mk" + std::to_string(k));
    t.markers.Resize(3000, 40);
    for (int64_t f = 0; f < 3000; ++f)
      for (int k = 0; k < 40; ++k) {
        float* p = t.markers.at(f, k);
        p[0] = static_cast<float>(k);
        p[1] = static_cast<float>(f);
        p[2] = 1.0f;
      }
    files.push_back((dir_ / (std::string(name) + ".c3d")).string());
    WriteC3d(files.back(), t);
  }
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  std::atomic<bool> reached{false};
  std::atomic<double> reached_fraction{0};
  std::binary_semaphore resume(0);
  w->import_runner()->SetWorkerHook([&](const std::string& stage, double fraction) {
    if (reached.load() || stage.find("delta") == std::string::npos || fraction <= 0.0) return;
    reached_fraction = fraction;
    reached = true;
    resume.acquire();  // hold the worker until the user has pressed Cancel
  });
  QSignalSpy finished(w.get(), &MainWindow::ImportFinished);
  jobs::ImportOptions options;
  options.files = files;
  options.corpus = corpus_;
  ASSERT_TRUE(w->StartImport(options));
  ASSERT_TRUE(w->import_progress() != nullptr);
  EXPECT_TRUE(w->import_progress()->isVisible());
  ASSERT_TRUE(QTest::qWaitFor([&] { return reached.load(); }, kHangGuardMs));
  EXPECT_GT(reached_fraction.load(), 0.0);
  EXPECT_LT(reached_fraction.load(), 1.0);
  // The GUI stays responsive while the job runs: back in the main window, step a frame.
  QApplication::setActiveWindow(w.get());
  ASSERT_TRUE(QTest::qWaitForWindowActive(w.get()));
  QTest::keyClick(w.get(), Qt::Key_Right);
  EXPECT_EQ(w->playback()->frame(), 1);
  QPushButton* cancel = w->import_progress()->findChild<QPushButton*>();
  ASSERT_TRUE(cancel != nullptr);
  QTest::mouseClick(cancel, Qt::LeftButton);
  resume.release();
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  EXPECT_FALSE(w->import_runner()->running());
  EXPECT_EQ(w->import_progress(), nullptr);
  EXPECT_TRUE(w->log()->entries().back().startsWith("Import cancelled"));
  EXPECT_EQ(TakeNames(), (std::vector<std::string>{"alpha", "beta"}));
  EXPECT_FALSE(fs::exists(CorpusTransaction::TempPath(corpus_)));
  // The same import, not cancelled, lands both takes.
  w->import_runner()->SetWorkerHook(nullptr);
  ASSERT_TRUE(w->StartImport(options));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  EXPECT_EQ(TakeNames(), (std::vector<std::string>{"alpha", "beta", "delta", "gamma"}));
  EXPECT_EQ(w->browser()->take_count(), 4);
}

TEST_F(ViewerTest, DamagedOrForeignFilesAreLoggedAndTheAppStaysUsable) {
  auto w = OpenWindow();
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  fs::path foreign = dir_ / "notes.h5";
  std::ofstream(foreign) << "this is a text file, not HDF5\n";
  // The open runs off the GUI thread; its failure arrives as a signal.
  QSignalSpy open_failed(w.get(), &MainWindow::CorpusOpenFailed);
  ASSERT_TRUE(w->OpenCorpus(QString::fromStdString(foreign.string())));
  EXPECT_TRUE(w->corpus_opening());
  ASSERT_TRUE(open_failed.wait(kHangGuardMs));
  EXPECT_TRUE(open_failed.at(0).at(1).toString().contains("notes.h5"))
      << open_failed.at(0).at(1).toString().toStdString();
  EXPECT_FALSE(w->corpus_opening());
  EXPECT_EQ(w->log()->CountLevel(LogPanel::Level::kError), 1);
  EXPECT_TRUE(w->log()->entries().back().contains("notes.h5"));
  // Still on the previous corpus, still working.
  EXPECT_EQ(w->corpus_path().toStdString(), corpus_);
  EXPECT_TRUE(SelectAndWait(w.get(), "beta"));
  QTest::keyClick(w.get(), Qt::Key_Right);
  EXPECT_EQ(w->marker_view()->frame(), 1);

  // A damaged capture: the import fails, the error names the file, nothing changes.
  Take t = MakeBeta();
  fs::path c3d = dir_ / "broken.c3d";
  WriteC3d(c3d.string(), t);
  {
    // Point the header's parameter-section pointer past the end of the file.
    std::fstream f(c3d, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(0);
    f.put(static_cast<char>(200));
  }
  QSignalSpy finished(w.get(), &MainWindow::ImportFinished);
  jobs::ImportOptions options;
  options.files = {c3d.string()};
  options.corpus = corpus_;
  ASSERT_TRUE(w->StartImport(options));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  EXPECT_EQ(w->log()->CountLevel(LogPanel::Level::kError), 2);
  EXPECT_TRUE(w->log()->entries().back().startsWith("error: Import failed:"));
  EXPECT_TRUE(w->log()->entries().back().contains("broken.c3d"));
  EXPECT_EQ(TakeNames(), (std::vector<std::string>{"alpha", "beta"}));
  EXPECT_TRUE(SelectAndWait(w.get(), "alpha"));
}

TEST_F(ViewerTest, LayoutAndRecentFilesAreRemembered) {
  {
    auto w = OpenWindow();
    ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
    w->log_dock()->hide();
    w->close();
  }
  auto w = OpenWindow();
  EXPECT_FALSE(w->log_dock()->isVisible());
  EXPECT_TRUE(w->plots_dock()->isVisible());
  EXPECT_EQ(w->recent_files(), QStringList{QFileInfo(QString::fromStdString(corpus_)).absoluteFilePath()});
}

}  // namespace
}  // namespace csw::gui

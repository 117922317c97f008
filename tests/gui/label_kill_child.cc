// Test-only child of label_kill_test.cc: a labelling session that the test
// kills with SIGKILL. It opens the real MainWindow (offscreen) on a corpus,
// labels the tier `kill_keys` of its first take and then, every PERIOD_MS, puts
// the cursor on a new frame (1, 3, 5, ...) and types a two-digit code into the
// key-label lane, as a user would. Each edit, once it is in the lane's model,
// is written to stdout and flushed before the event loop runs again:
//   ready <t_ns>
//   edit <frame> <code> <t_ns>
//   saved <t_ns> <commit_ms>        (an autosave reached the corpus)
// t_ns is std::chrono::steady_clock (CLOCK_MONOTONIC on Linux: the same clock in
// every process of the machine). Exit status 2 for a bad command line, 3 when
// the corpus or the tier cannot be opened.
//
// usage: label_kill_child CORPUS SETTINGS.ini AUTOSAVE_MS PERIOD_MS
#include <QApplication>
#include <QTest>
#include <QTimer>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "workbench/gui/label_lane.h"
#include "workbench/gui/label_session.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/playback.h"

namespace {

long long NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The code of the i-th edit: placements 1-5 and shapes 1-8 in turn.
std::string Code(int i) { return std::to_string(1 + i % 5) + std::to_string(1 + i % 8); }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s CORPUS SETTINGS.ini AUTOSAVE_MS PERIOD_MS\n", argv[0]);
    return 2;
  }
  if (qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM")) qputenv("QT_QPA_PLATFORM", "offscreen");
  const QString corpus = QString::fromLocal8Bit(argv[1]);
  const QString settings = QString::fromLocal8Bit(argv[2]);
  const int autosave_ms = std::atoi(argv[3]);
  const int period_ms = std::atoi(argv[4]);
  QApplication app(argc, argv);

  csw::gui::MainWindow w(settings);
  w.playback()->SetAudioEnabled(false);
  w.resize(1000, 700);
  w.show();
  csw::gui::LabelSession* labels = w.labels();
  QObject::connect(labels, &csw::gui::LabelSession::Saved, [](const QString&, double ms) {
    std::printf("saved %lld %.1f\n", NowNs(), ms);
    std::fflush(stdout);
  });

  int edits = 0;
  QTimer timer;
  timer.setInterval(period_ms);
  QObject::connect(&timer, &QTimer::timeout, [&] {
    const int64_t frame = 1 + 2 * static_cast<int64_t>(edits);
    if (frame >= labels->frames()) {
      timer.stop();
      return;
    }
    w.playback()->Seek(frame);
    const std::string code = Code(edits);
    for (char c : code) QTest::keyClick(w.label_lane(), static_cast<Qt::Key>(Qt::Key_0 + (c - '0')));
    const long at = labels->LabelAtFrame(frame);
    if (at < 0 || labels->model()->at(static_cast<size_t>(at)).text != code) {
      std::printf("error no label %s at frame %lld\n", code.c_str(), static_cast<long long>(frame));
      std::fflush(stdout);
      return;
    }
    std::printf("edit %lld %s %lld\n", static_cast<long long>(frame), code.c_str(), NowNs());
    std::fflush(stdout);
    ++edits;
  });
  QObject::connect(&w, &csw::gui::MainWindow::TakeShown, [&](const QString&) {
    if (timer.isActive()) return;
    if (!w.SetLabelTier(QStringLiteral("kill_keys"))) {
      std::printf("error cannot label tier kill_keys\n");
      std::fflush(stdout);
      QApplication::exit(3);
      return;
    }
    labels->SetAutosaveDelay(autosave_ms);
    w.label_lane()->setFocus();
    std::printf("ready %lld\n", NowNs());
    std::fflush(stdout);
    timer.start();
  });
  if (!w.OpenCorpus(corpus)) return 3;
  return QApplication::exec();
}

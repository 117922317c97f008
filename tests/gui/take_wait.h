#pragma once
// MainWindow::SelectTake loads a take off the GUI thread: the GUI tests wait
// for it by running the event loop (never by sleeping), as a user would.
#include <QTest>
#include <string>

#include "workbench/gui/main_window.h"

namespace csw::gui {

// How long a GUI test waits for background work (a take, a job, a save)
// before calling it hung. A guard against hangs, not a speed check (speed is
// measured in bench/): CI hosts have run the suite up to 8x slower than a
// developer's machine, and a test then waited 195 s for a 27 s job.
inline constexpr int kHangGuardMs = 900000;

// Runs the event loop until `w` shows the take `name` (any take when empty)
// and loads none; false after `timeout_ms`.
inline bool WaitForTake(MainWindow* w, const std::string& name = {}, int timeout_ms = kHangGuardMs) {
  return QTest::qWaitFor([&] { return !w->take_loading() && w->take() && (name.empty() || w->take()->name == name); },
                         timeout_ms);
}

// Opens a corpus and waits until its first take is shown.
inline bool OpenAndWait(MainWindow* w, const std::string& corpus) {
  return w->OpenCorpus(QString::fromStdString(corpus)) && WaitForTake(w);
}

// Selects a take and waits until it is shown.
inline bool SelectAndWait(MainWindow* w, const std::string& take) {
  return w->SelectTake(QString::fromStdString(take)) && WaitForTake(w, take);
}

}  // namespace csw::gui

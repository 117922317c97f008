#pragma once
// MainWindow::SelectTake loads a take off the GUI thread: the GUI tests wait
// for it by running the event loop (never by sleeping), as a user would.
#include <QTest>
#include <string>

#include "workbench/gui/main_window.h"

namespace csw::gui {

// Runs the event loop until `w` shows the take `name` (any take when empty)
// and loads none; false after `timeout_ms`.
inline bool WaitForTake(MainWindow* w, const std::string& name = {}, int timeout_ms = 30000) {
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

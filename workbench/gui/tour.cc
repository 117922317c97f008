#include "workbench/gui/tour.h"

#include <qcustomplot.h>

#include <QApplication>
#include <QDir>
#include <QDockWidget>
#include <QEventLoop>
#include <QFile>
#include <QTimer>
#include <fstream>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "workbench/gui/corpus_browser.h"
#include "workbench/gui/demo_take.h"
#include "workbench/gui/import_runner.h"
#include "workbench/gui/label_lane.h"
#include "workbench/gui/label_session.h"
#include "workbench/gui/log_panel.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/marker_view.h"
#include "workbench/gui/playback.h"
#include "workbench/gui/timeseries_panel.h"

namespace csw::gui {

namespace {

// Lets layouts, queued replots and paints settle before a screenshot (tour only).
void Settle(int ms = 150) {
  QEventLoop loop;
  QTimer::singleShot(ms, &loop, &QEventLoop::quit);
  loop.exec();
}

QString Shot(QWidget* widget, const QString& dir, const QString& name) {
  Settle();
  QString path = QDir(dir).filePath(name);
  if (!widget->grab().save(path, "PNG")) throw IoError(path.toStdString(), "cannot write screenshot");
  return path;
}

}  // namespace

QStringList RunTour(const TourOptions& options) {
  QDir().mkpath(options.out_dir);
  QDir().mkpath(options.work_dir);
  QString corpus = QDir(options.work_dir).filePath("demo.h5");
  QFile::remove(corpus);

  // 1. The virtual cuer's demo take (one sentence), written straight into a new corpus.
  DemoTakeOptions demo;
  const SimulationResult sim = SimulateDemoTake(demo);
  {
    CorpusTransaction tx(corpus.toStdString());
    tx.WriteTake(sim.take);
    tx.Commit();
  }
  // The middle key of the sentence: the fingertip reaches its placement here.
  if (sim.keys.empty()) throw Error("tour: the demo take has no cue keys");
  const double key_s = sim.keys[sim.keys.size() / 2].timing.placement_target_s;
  QString set_path = QDir(options.work_dir).filePath("synthetic-cuer.json");
  {
    std::ofstream out(set_path.toStdString());
    out << MarkerSetToJson(DemoMarkerSet());
  }

  QStringList written;
  MainWindow window(QDir(options.work_dir).filePath("tour-settings.ini"));
  window.resize(1600, 1100);
  window.show();
  window.resizeDocks({window.plots_dock()}, {470}, Qt::Vertical);
  window.playback()->SetAudioEnabled(false);
  window.LoadMarkerSetFile(set_path);
  if (!window.OpenCorpus(corpus)) throw Error("tour: cannot open the demo corpus");

  // 2. Captures through the background import job (File > Import does the same).
  QStringList imported;
  if (!options.captures.isEmpty()) {
    jobs::ImportOptions import;
    for (const QString& c : options.captures) import.files.push_back(c.toStdString());
    import.corpus = corpus.toStdString();
    QEventLoop loop;
    QObject::connect(&window, &MainWindow::ImportFinished, &loop, &QEventLoop::quit);
    QObject::connect(window.import_runner(), &ImportRunner::Succeeded, &loop,
                     [&imported](const QStringList& takes, const QStringList&) { imported = takes; });
    if (window.StartImport(import)) loop.exec();
  }

  // 3. The main window on the demo take: the picked index fingertip, its speed,
  // at the middle key's placement target.
  window.browser()->SelectTake(QString::fromStdString(demo.name));
  std::shared_ptr<const Take> take = window.take();
  if (!take) throw Error("tour: the demo take did not load");
  int tip = static_cast<int>(take->MarkerIndex("ITIP"));
  if (tip < 0) throw Error("tour: the demo take has no ITIP marker");
  window.marker_view()->Zoom(2.0);
  window.playback()->Seek(static_cast<int64_t>(key_s * take->rate_hz));
  window.marker_view()->SelectMarker(tip);
  window.marker_combo()->setCurrentIndex(tip + 1);
  window.quantity_combo()->setCurrentIndex(3);  // speed
  window.plots()->SetMarkerSeries(tip, MarkerQuantity::kSpeed);
  window.plots()->SetTimeRange(0.0, take->duration_s());
  window.plots()->SetCursorTime(key_s);
  written << Shot(&window, options.out_dir, "01-main-window.png");

  // 4. Zoomed plots: phones, keys and the hand leading the voice.
  window.plots()->SetTimeRange(key_s - 0.75, key_s + 0.75);
  window.plots()->SetCursorTime(key_s);
  written << Shot(window.plots_dock(), options.out_dir, "02-plots-zoomed.png");

  // 5. The 3D view alone, orbited: face, throat, forearm and hand markers with their sticks.
  window.marker_view()->Orbit(-60, 10);
  window.marker_view()->Zoom(1.25);
  window.marker_view()->Pan(0, 110);
  written << Shot(window.marker_view(), options.out_dir, "03-3d-view.png");

  // 5b. The key-label lane under the plots, on the demo take's `keys` tier: the
  // cursor put on the key target nearest that placement target (the selected
  // label, orange), as the lane's Ctrl+Right / Ctrl+Left jumps would.
  if (!window.SetLabelTier(QStringLiteral("keys")) || window.labels()->model()->size() == 0)
    throw Error("tour: the demo take's keys tier cannot be labelled");
  {
    const LabelModel& model = *window.labels()->model();
    const long near = model.Find(key_s, 1.0);
    if (near >= 0) window.playback()->Seek(window.labels()->TimeFrame(model.at(static_cast<size_t>(near)).start_s));
  }
  window.label_lane()->setFocus();
  written << Shot(window.plots_dock(), options.out_dir, "label-lane.png");

  // 6. The imported captures: the demo corpus's first take, then a real face capture.
  if (!options.markerset.isEmpty()) window.LoadMarkerSetFile(options.markerset);
  int shot = 4;
  for (const QString& name : {imported.value(0), QStringLiteral("Facial-Sing")}) {
    if (name.isEmpty() || !imported.contains(name) || !window.browser()->SelectTake(name)) continue;
    bool y_up = name == "Facial-Sing";  // NaturalPoint Motive exports are Y-up
    window.marker_view()->SetYUp(y_up);
    window.marker_view()->ResetView();
    window.marker_view()->Orbit(y_up ? 90 : -70, 0);
    window.marker_view()->Zoom(1.8);
    window.playback()->Seek(window.playback()->frames() / 3);
    written << Shot(
        &window, options.out_dir,
        QStringLiteral("%1-%2.png").arg(shot++, 2, 10, QChar('0')).arg(y_up ? "real-face-capture" : "imported-take"));
    window.marker_view()->SetYUp(false);
    if (y_up) break;
  }

  // 7. A damaged file: the error lands in the log and the window stays usable.
  QString damaged = options.damaged_file;
  if (damaged.isEmpty()) {
    damaged = QDir(options.work_dir).filePath("damaged.h5");
    QFile f(damaged);
    if (f.open(QIODevice::WriteOnly)) f.write("\x89HDF\r\n\x1a\nthis corpus was cut off here");
  }
  window.OpenCorpus(damaged);
  window.browser()->SelectTake(QString::fromStdString(demo.name));
  written << Shot(&window, options.out_dir, QStringLiteral("%1-damaged-file.png").arg(shot, 2, 10, QChar('0')));
  window.close();
  return written;
}

}  // namespace csw::gui

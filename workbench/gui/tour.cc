#include "workbench/gui/tour.h"

#include <qcustomplot.h>

#include <QApplication>
#include <QDir>
#include <QDockWidget>
#include <QEventLoop>
#include <QFile>
#include <QLabel>
#include <QTabWidget>
#include <QTimer>
#include <atomic>
#include <fstream>
#include <memory>
#include <semaphore>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "workbench/gui/corpus_browser.h"
#include "workbench/gui/demo_take.h"
#include "workbench/gui/error_inspector.h"
#include "workbench/gui/fit_dialog.h"
#include "workbench/gui/import_runner.h"
#include "workbench/gui/job_dialog.h"
#include "workbench/gui/job_runner.h"
#include "workbench/gui/label_lane.h"
#include "workbench/gui/label_session.h"
#include "workbench/gui/log_panel.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/marker_view.h"
#include "workbench/gui/phasing_view.h"
#include "workbench/gui/playback.h"
#include "workbench/gui/score_lanes.h"
#include "workbench/gui/timeseries_panel.h"
#include "workbench/jobs/keys_job.h"

namespace csw::gui {

namespace {

// Runs the event loop until the window's take selection is shown (or failed):
// the window loads takes off the GUI thread.
void WaitForTake(MainWindow& window, int timeout_ms = 60000) {
  if (!window.take_loading()) return;
  QEventLoop loop;
  QTimer timeout;
  timeout.setSingleShot(true);
  QObject::connect(&timeout, &QTimer::timeout, &loop, &QEventLoop::quit);
  QObject::connect(&window, &MainWindow::TakeShown, &loop, [&] {
    if (!window.take_loading()) loop.quit();
  });
  QObject::connect(&window, &MainWindow::TakeLoadFailed, &loop, [&] {
    if (!window.take_loading()) loop.quit();
  });
  // A corpus that failed to open (or holds no take) shows no new take.
  QObject::connect(&window, &MainWindow::CorpusOpenFailed, &loop, [&] {
    if (!window.take_loading()) loop.quit();
  });
  QObject::connect(&window, &MainWindow::CorpusOpened, &loop, [&] {
    if (!window.take_loading()) loop.quit();
  });
  timeout.start(timeout_ms);
  loop.exec();
}

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
  WaitForTake(window);

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
  WaitForTake(window);
  window.browser()->SelectTake(QString::fromStdString(demo.name));
  WaitForTake(window);
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
    WaitForTake(window);
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
  WaitForTake(window);
  written << Shot(&window, options.out_dir, QStringLiteral("%1-damaged-file.png").arg(shot, 2, 10, QChar('0')));
  // 8. Models > Fit Model...: a face model fitted in the background on the
  // virtual cuer's takes (the synthetic one and the imported sentences but the
  // last, which is held out), shot while the fit runs; then the
  // reconstruction-error inspector on the corpus, its worst utterance
  // clicked, and the 3D view with observed and reconstructed markers.
  QStringList cuer_takes{QString::fromStdString(demo.name)};
  for (const QString& t : imported)
    if (t.startsWith(QStringLiteral("sentence_"))) cuer_takes << t;
  if (cuer_takes.size() >= 3) {
    const QString models = QDir(options.work_dir).filePath("demo.models.h5");
    QFile::remove(models);
    FitDialog* fit = window.ShowFitDialog();
    fit->SetKind(QStringLiteral("face"));
    fit->SetOutput(models);
    fit->SetCheckedTakes(cuer_takes.mid(0, cuer_takes.size() - 1));
    fit->move(window.geometry().center() - QPoint(fit->width() / 2, fit->height() / 2));
    // Hold the worker once, a quarter into the fit proper, for the picture.
    struct Hold {
      std::atomic<bool> held{false}, done{false};
      std::binary_semaphore resume{0};
    };
    auto hold = std::make_shared<Hold>();
    fit->runner()->SetWorkerHook([hold](const std::string& stage, double fraction) {
      if (hold->done.load() || stage == "loading takes" || fraction < 0.25 || fraction >= 1.0) return;
      hold->done = true;
      hold->held = true;
      hold->resume.acquire();
    });
    QString outcome;
    QEventLoop loop;
    auto finished = QObject::connect(fit, &FitDialog::FitFinished, &loop, [&](const QString& o) {
      outcome = o;
      loop.quit();
    });
    if (!fit->StartFit()) throw Error("tour: the fit did not start: " + fit->status_label()->text().toStdString());
    QTimer poll;
    QObject::connect(&poll, &QTimer::timeout, &loop, [&] {
      if (hold->held.load()) loop.quit();
    });
    poll.start(20);
    loop.exec();
    poll.stop();
    if (hold->held.load()) {
      Settle(300);  // the queued progress reaches the dialog
      written << Shot(fit, options.out_dir, QStringLiteral("fit-dialog.png"));
      hold->resume.release();
      if (outcome.isEmpty()) loop.exec();
    } else {
      written << Shot(fit, options.out_dir, QStringLiteral("fit-dialog.png"));
    }
    QObject::disconnect(finished);
    fit->runner()->SetWorkerHook(nullptr);
    if (outcome != QStringLiteral("succeeded")) throw Error("tour: the face fit " + outcome.toStdString());
    fit->hide();

    ErrorInspector* inspector = window.error_inspector();
    QString inspected;
    QObject::connect(inspector, &ErrorInspector::Finished, &loop, [&](const QString& o) {
      inspected = o;
      loop.quit();
    });
    window.browser()->SelectTake(cuer_takes.front());  // a take the model's markers bind
    WaitForTake(window);
    window.resizeDocks({window.errors_dock()}, {620}, Qt::Horizontal);
    // Every take: Facial-Sing, which lacks the model's markers, is left out (and named in the log).
    if (!window.InspectErrors(models)) throw Error("tour: the error inspection did not start");
    loop.exec();
    if (inspected != QStringLiteral("succeeded")) throw Error("tour: the error inspection " + inspected.toStdString());
    const ModelErrors* errors = inspector->shown();
    if (errors == nullptr || errors->utterances.empty()) throw Error("tour: no reconstruction errors to show");
    size_t worst = 0;
    for (size_t i = 1; i < errors->utterances.size(); ++i)
      if (errors->utterances[i].mean_mm > errors->utterances[worst].mean_mm) worst = i;
    const QString worst_take = QString::fromStdString(errors->utterances[worst].take);
    inspector->ChooseUtterance(static_cast<int>(worst));
    WaitForTake(window);
    QTimer timeout;
    timeout.setSingleShot(true);
    QObject::connect(&timeout, &QTimer::timeout, &loop, &QEventLoop::quit);
    QObject::connect(inspector, &ErrorInspector::ReconstructionReady, &loop, [&](const QString& take) {
      if (take == worst_take) loop.quit();
    });
    timeout.start(120000);
    if (!window.marker_view()->has_reconstruction()) loop.exec();
    MarkerView* view = window.marker_view();
    view->SetYUp(false);
    view->ResetView();  // facing the talker
    view->Zoom(2.0);
    written << Shot(&window, options.out_dir, QStringLiteral("error-inspector.png"));
    // The face close up at the frame of that take where the model fills the
    // most missing markers, so that both reconstructed styles show.
    const std::shared_ptr<const Take> shown = window.take();
    const std::shared_ptr<const MarkerArray> recon = inspector->reconstruction();
    if (shown && recon && recon->frames() == shown->frames() && recon->markers() == shown->markers.markers()) {
      int64_t best = -1;
      int most = 0;
      for (int64_t f = 0; f < shown->frames(); ++f) {
        int n = 0;
        for (int64_t k = 0; k < shown->markers.markers(); ++k)
          n += !shown->markers.Visible(f, k) && !IsMissing(recon->at(f, k)[0]);
        if (n > most) {
          most = n;
          best = f;
        }
      }
      if (best >= 0) window.playback()->Seek(best);
    }
    view->ResetView();
    view->Orbit(-30, 5);
    view->Zoom(2.6);
    const int chin = shown ? static_cast<int>(shown->MarkerIndex("CHIN")) : -1;
    if (chin >= 0) {
      if (auto pos = view->MarkerScreenPos(chin))
        view->Pan(view->width() / 2.0 - pos->x(), view->height() / 2.0 - 60 - pos->y());
    }
    written << Shot(view, options.out_dir, QStringLiteral("reconstruction-3d.png"));
    window.errors_dock()->hide();

    // 9. Analysis > Suggest Target Frames on the virtual cuer's takes: the
    // dialog with the job's text output, then the corpus reopened on its take.
    JobDialog* suggest = window.ShowJobDialog(QStringLiteral("keys-suggest"));
    if (suggest == nullptr) throw Error("tour: no keys-suggest job");
    // The imported sentences (the synthetic take has no phone tier); the
    // marker set is the one loaded with File > Load Marker Set (filled in).
    suggest->SetValue(QStringLiteral("takes"), cuer_takes.mid(1).join(QStringLiteral(", ")));
    suggest->move(window.geometry().center() - QPoint(suggest->width() / 2, suggest->height() / 2));
    QString job_outcome;
    auto job_finished = QObject::connect(suggest, &JobDialog::JobFinished, &loop, [&](const QString& o) {
      job_outcome = o;
      loop.quit();
    });
    if (!suggest->Start())
      throw Error("tour: keys suggest did not start: " + suggest->status_label()->text().toStdString());
    loop.exec();
    QObject::disconnect(job_finished);
    if (job_outcome != QStringLiteral("succeeded"))
      throw Error("tour: keys suggest " + job_outcome.toStdString() + ": " +
                  suggest->status_label()->text().toStdString());
    WaitForTake(window);
    Settle(300);
    written << Shot(suggest, options.out_dir, QStringLiteral("analysis-job.png"));
    suggest->hide();
  }

  // 9. The gestural score and the phasing and confusion views: a key
  // recogniser trained on the virtual cuer's takes and scored on them (as
  // `csw keys train` and `csw keys score` do), then Models > Phasing and
  // Confusion run in the background on the corpus with it.
  {
    QStringList takes{QString::fromStdString(demo.name)};
    for (const QString& t : imported)
      if (t.startsWith(QStringLiteral("sentence_"))) takes << t;
    const QString keys = QDir(options.work_dir).filePath("demo.keys.h5");
    QFile::remove(keys);
    Progress quiet;
    jobs::KeysTrainOptions train;
    train.corpus = corpus.toStdString();
    for (const QString& t : takes) train.takes.push_back(t.toStdString());
    train.markerset = set_path.toStdString();
    train.output = keys.toStdString();
    jobs::KeysTrain(train, quiet);
    jobs::KeysScoreOptions score;
    score.corpus = corpus.toStdString();
    score.keys = keys.toStdString();
    score.takes = train.takes;
    score.markerset = set_path.toStdString();
    jobs::KeysScore(score, quiet);
    window.LoadMarkerSetFile(set_path);
    if (!window.OpenCorpus(corpus)) throw Error("tour: cannot reopen the demo corpus");
    WaitForTake(window);
    window.browser()->SelectTake(QString::fromStdString(demo.name));
    WaitForTake(window);
    if (!window.score_lanes()->has_scores()) throw Error("tour: the demo take shows no gestural score");
    window.resizeDocks({window.plots_dock()}, {640}, Qt::Vertical);
    window.plots()->SetTimeRange(key_s - 1.2, key_s + 1.2);
    window.playback()->Seek(static_cast<int64_t>(key_s * window.take()->rate_hz));
    written << Shot(window.score_lanes(), options.out_dir, QStringLiteral("gestural-score.png"));

    PhasingView* view = window.phasing_view();
    QString outcome;
    QEventLoop loop;
    auto finished = QObject::connect(view, &PhasingView::Finished, &loop, [&](const QString& o) {
      outcome = o;
      loop.quit();
    });
    window.errors_dock()->hide();
    if (!window.ShowPhasing(keys)) throw Error("tour: the phasing analysis did not start");
    loop.exec();
    QObject::disconnect(finished);
    if (outcome != QStringLiteral("succeeded"))
      throw Error("tour: the phasing analysis " + outcome.toStdString() + ": " +
                  view->status_label()->text().toStdString());
    window.phasing_dock()->setFloating(true);
    window.phasing_dock()->resize(1100, 720);
    view->tabs()->setCurrentIndex(0);
    written << Shot(window.phasing_dock(), options.out_dir, QStringLiteral("phasing-view.png"));
    view->tabs()->setCurrentIndex(1);
    written << Shot(window.phasing_dock(), options.out_dir, QStringLiteral("confusion-view.png"));
    window.phasing_dock()->hide();
  }

  window.close();
  return written;
}

}  // namespace csw::gui

#include "workbench/gui/main_window.h"

#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QCloseEvent>
#include <QComboBox>
#include <QDialog>
#include <QDialogButtonBox>
#include <QDir>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QListWidget>
#include <QMenuBar>
#include <QProgressBar>
#include <QProgressDialog>
#include <QPushButton>
#include <QSettings>
#include <QStatusBar>
#include <QThreadPool>
#include <QToolButton>
#include <QUndoStack>
#include <QVBoxLayout>
#include <cmath>
#include <cstdio>
#include <string_view>

#include "core/error.h"
#include "workbench/gui/corpus_browser.h"
#include "workbench/gui/error_inspector.h"
#include "workbench/gui/export_files.h"
#include "workbench/gui/figure_export.h"
#include "workbench/gui/fit_dialog.h"
#include "workbench/gui/import_runner.h"
#include "workbench/gui/job_dialog.h"
#include "workbench/gui/job_runner.h"
#include "workbench/gui/label_counts.h"
#include "workbench/gui/label_lane.h"
#include "workbench/gui/label_session.h"
#include "workbench/gui/log_panel.h"
#include "workbench/gui/marker_view.h"
#include "workbench/gui/phasing_view.h"
#include "workbench/gui/playback.h"
#include "workbench/gui/score_lanes.h"
#include "workbench/gui/timeseries_panel.h"

namespace csw::gui {

namespace {
constexpr int kMaxRecent = 8;
const char* kFigureFilter = "PNG image (*.png);;SVG drawing (*.svg);;PDF document (*.pdf)";

// Drops `take` on a pool thread when that is its last holder: freeing a long
// take (a 10-minute one holds ~170 MB) costs the GUI thread tens of ms.
void ReleaseOffTheGuiThread(std::shared_ptr<const Take> take) {
  if (!take) return;
  QThreadPool::globalInstance()->start([take = std::move(take)]() mutable { take.reset(); });
}

bool SameTiers(const std::vector<LabelTier>& a, const std::vector<LabelTier>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const LabelTier& x = a[i];
    const LabelTier& y = b[i];
    if (x.name != y.name || x.kind != y.kind || x.start_s != y.start_s || x.end_s != y.end_s ||
        x.labels.size() != y.labels.size())
      return false;
    for (size_t k = 0; k < x.labels.size(); ++k) {
      if (x.labels[k].start_s != y.labels[k].start_s || x.labels[k].end_s != y.labels[k].end_s ||
          x.labels[k].text != y.labels[k].text)
        return false;
    }
  }
  return true;
}
}  // namespace

MainWindow::MainWindow(const QString& settings_path, QWidget* parent) : QMainWindow(parent) {
  setObjectName("mainWindow");
  settings_ = settings_path.isEmpty() ? std::make_unique<QSettings>("csw", "csw-workbench")
                                      : std::make_unique<QSettings>(settings_path, QSettings::IniFormat);
  setDockOptions(QMainWindow::AnimatedDocks | QMainWindow::AllowTabbedDocks | QMainWindow::AllowNestedDocks);

  marker_view_ = new MarkerView(this);
  marker_view_->setObjectName("markerView");
  setCentralWidget(marker_view_);

  browser_ = new CorpusBrowser(this);
  takes_dock_ = new QDockWidget(tr("Takes"), this);
  takes_dock_->setObjectName("takesDock");
  takes_dock_->setWidget(browser_);
  addDockWidget(Qt::LeftDockWidgetArea, takes_dock_);

  // The time-series dock: a small bar choosing the marker lane, then the plots.
  auto* plots_box = new QWidget(this);
  auto* plots_layout = new QVBoxLayout(plots_box);
  plots_layout->setContentsMargins(2, 2, 2, 2);
  auto* bar = new QHBoxLayout();
  marker_combo_ = new QComboBox(plots_box);
  marker_combo_->setObjectName("markerCombo");
  marker_combo_->setMinimumContentsLength(14);
  marker_combo_->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
  quantity_combo_ = new QComboBox(plots_box);
  quantity_combo_->setObjectName("quantityCombo");
  for (auto q : {MarkerQuantity::kX, MarkerQuantity::kY, MarkerQuantity::kZ, MarkerQuantity::kSpeed})
    quantity_combo_->addItem(QuantityName(q), static_cast<int>(q));
  quantity_combo_->setCurrentIndex(2);
  auto* show_all = new QToolButton(plots_box);
  show_all->setText(tr("Show all"));
  label_tier_combo_ = new QComboBox(plots_box);
  label_tier_combo_->setObjectName("labelTierCombo");
  label_tier_combo_->setEditable(true);
  label_tier_combo_->setMinimumContentsLength(12);
  label_tier_combo_->addItem(QStringLiteral("keys"));
  label_tier_combo_->setToolTip(tr("The point tier of key targets the label lane edits (a new name makes a new tier)"));
  bar->addWidget(new QLabel(tr("Marker:"), plots_box));
  bar->addWidget(marker_combo_);
  bar->addWidget(quantity_combo_);
  bar->addStretch(1);
  bar->addWidget(new QLabel(tr("Key tier:"), plots_box));
  bar->addWidget(label_tier_combo_);
  bar->addWidget(show_all);
  plots_layout->addLayout(bar);
  plots_ = new TimeSeriesPanel(plots_box);
  plots_layout->addWidget(plots_, 1);
  log_ = new LogPanel(this);
  labels_ = new LabelSession(log_, this);
  label_lane_ = new LabelLane(labels_, plots_box);
  label_lane_->AlignWith(plots_->plot());
  plots_layout->addWidget(label_lane_);
  score_lanes_ = new ScoreLanes(plots_box);  // shown when the take has a gestural score
  score_lanes_->AlignWith(plots_->plot());
  plots_layout->addWidget(score_lanes_);
  plots_dock_ = new QDockWidget(tr("Time series"), this);
  plots_dock_->setObjectName("plotsDock");
  plots_dock_->setWidget(plots_box);
  addDockWidget(Qt::BottomDockWidgetArea, plots_dock_);

  log_dock_ = new QDockWidget(tr("Log"), this);
  log_dock_->setObjectName("logDock");
  log_dock_->setWidget(log_);
  addDockWidget(Qt::BottomDockWidgetArea, log_dock_);
  splitDockWidget(plots_dock_, log_dock_, Qt::Vertical);
  label_counts_ = new LabelCountsPanel(this);
  counts_dock_ = new QDockWidget(tr("Label counts"), this);
  counts_dock_->setObjectName("countsDock");
  counts_dock_->setWidget(label_counts_);
  addDockWidget(Qt::LeftDockWidgetArea, counts_dock_);
  splitDockWidget(takes_dock_, counts_dock_, Qt::Vertical);
  connect(labels_, &LabelSession::LabelsChanged, this,
          [this] { label_counts_->Refresh(labels_->has_take() ? labels_->model() : nullptr); });
  resizeDocks({plots_dock_, log_dock_}, {380, 90}, Qt::Vertical);
  resizeDocks({takes_dock_}, {430}, Qt::Horizontal);
  resizeDocks({takes_dock_, counts_dock_}, {520, 180}, Qt::Vertical);

  error_inspector_ = new ErrorInspector(log_, this);
  errors_dock_ = new QDockWidget(tr("Reconstruction errors"), this);
  errors_dock_->setObjectName("errorsDock");
  errors_dock_->setWidget(error_inspector_);
  addDockWidget(Qt::RightDockWidgetArea, errors_dock_);
  errors_dock_->hide();
  connect(error_inspector_, &ErrorInspector::UtteranceChosen, this, &MainWindow::OnUtteranceChosen);
  connect(error_inspector_, &ErrorInspector::Finished, this, [this](const QString& outcome) {
    if (outcome == QStringLiteral("succeeded") && take_) error_inspector_->ReconstructTake(take_);
  });
  connect(error_inspector_, &ErrorInspector::ReconstructionReady, this, [this](const QString& take) {
    if (take_ && QString::fromStdString(take_->name) == take)
      marker_view_->SetReconstruction(error_inspector_->reconstruction());
  });
  connect(this, &MainWindow::TakeShown, this, [this] {
    if (!error_inspector_->results().empty()) error_inspector_->ReconstructTake(take_);
  });

  phasing_view_ = new PhasingView(log_, this);
  phasing_dock_ = new QDockWidget(tr("Phasing and confusion"), this);
  phasing_dock_->setObjectName("phasingDock");
  phasing_dock_->setWidget(phasing_view_);
  addDockWidget(Qt::RightDockWidgetArea, phasing_dock_);
  phasing_dock_->hide();
  exporter_ = new ExportRunner(log_, this, this);

  playback_ = new Playback(this);
  import_runner_ = new ImportRunner(this);
  frame_label_ = new QLabel(this);
  // Busy while a selected take loads (SelectTake); the window stays usable.
  auto* busy = new QProgressBar(this);
  busy->setObjectName("takeLoadBusy");
  busy->setRange(0, 0);
  busy->setMaximumWidth(120);
  busy->setTextVisible(false);
  busy->hide();
  take_busy_ = busy;
  statusBar()->addPermanentWidget(take_busy_);
  statusBar()->addPermanentWidget(frame_label_);
  take_loader_ = new JobRunner(QStringLiteral("csw-take-load"), this);
  connect(take_loader_, &JobRunner::Succeeded, this, [this] { OnTakeLoadEnded(true, QString()); });
  connect(take_loader_, &JobRunner::Failed, this, [this](const QString& message) { OnTakeLoadEnded(false, message); });
  connect(take_loader_, &JobRunner::Canceled, this, [this] {
    // Only a superseded load is cancelled: its take is dropped, the latest selection loads.
    loading_result_.reset();
    loading_name_.clear();
    StartTakeLoad();
    UpdateTakeBusy();
  });

  corpus_opener_ = new JobRunner(QStringLiteral("csw-corpus-open"), this);
  connect(corpus_opener_, &JobRunner::Succeeded, this, [this] { OnCorpusOpenEnded(true, QString()); });
  connect(corpus_opener_, &JobRunner::Failed, this,
          [this](const QString& message) { OnCorpusOpenEnded(false, message); });
  connect(corpus_opener_, &JobRunner::Canceled, this, [this] { OnCorpusOpenEnded(false, tr("cancelled")); });
  // After an import the corpus reopens; ImportFinished says both are over.
  auto import_reopened = [this] {
    if (!import_reopen_pending_ || corpus_opener_->running()) return;
    import_reopen_pending_ = false;
    emit ImportFinished();
  };
  connect(this, &MainWindow::CorpusOpened, this, import_reopened);
  connect(this, &MainWindow::CorpusOpenFailed, this, import_reopened);

  connect(browser_, &CorpusBrowser::TakeSelected, this, [this](const QString& name) { SelectTake(name); });
  connect(playback_, &Playback::FrameChanged, this, &MainWindow::OnFrameChanged);
  connect(playback_, &Playback::Note, log_, &LogPanel::Info);
  connect(plots_, &TimeSeriesPanel::TimeClicked, playback_, &Playback::SeekTime);
  connect(marker_view_, &MarkerView::MarkerPicked, this, &MainWindow::OnMarkerPicked);
  connect(marker_combo_, qOverload<int>(&QComboBox::activated), this, [this](int) { OnMarkerSeriesChosen(); });
  connect(quantity_combo_, qOverload<int>(&QComboBox::activated), this, [this](int) { OnMarkerSeriesChosen(); });
  connect(show_all, &QToolButton::clicked, plots_, &TimeSeriesPanel::ShowAll);
  connect(plots_, &TimeSeriesPanel::TimeRangeChanged, label_lane_, &LabelLane::SetTimeRange);
  connect(plots_, &TimeSeriesPanel::TimeRangeChanged, score_lanes_, &ScoreLanes::SetTimeRange);
  connect(score_lanes_, &ScoreLanes::TimeClicked, playback_, &Playback::SeekTime);
  connect(label_lane_, &LabelLane::SeekRequested, playback_, &Playback::Seek);
  connect(label_lane_, &LabelLane::SnapRequested, this, [this] { SnapLabelToSpeedMinimum(); });
  connect(label_tier_combo_, qOverload<int>(&QComboBox::activated), this,
          [this](int) { SetLabelTier(label_tier_combo_->currentText()); });
  connect(labels_, &LabelSession::Saved, this, [this](const QString& take, double ms) {
    statusBar()->showMessage(tr("Labels of %1 saved (%2 ms)").arg(take).arg(ms, 0, 'f', 0), 3000);
  });

  connect(import_runner_, &ImportRunner::ProgressChanged, this, [this](const QString& stage, double fraction) {
    if (import_progress_ == nullptr) return;
    import_progress_->setLabelText(stage);
    import_progress_->setValue(static_cast<int>(std::lround(fraction * 1000)));
  });
  auto finish = [this] {
    if (import_progress_ != nullptr) {
      import_progress_->hide();
      import_progress_->deleteLater();
      import_progress_ = nullptr;
    }
  };
  connect(import_runner_, &ImportRunner::Succeeded, this,
          [this, finish](const QStringList& takes, const QStringList& warnings) {
            finish();
            for (const QString& w : warnings) log_->Warning(w);
            QString corpus = QString::fromStdString(import_runner_->options().corpus);
            log_->Info(tr("Imported %n take(s) into %1: %2", nullptr, static_cast<int>(takes.size()))
                           .arg(corpus, takes.join(", ")));
            // The corpus reopens off the GUI thread; ImportFinished follows its end.
            if (OpenCorpus(corpus, takes.isEmpty() ? QString() : takes.front())) {
              import_reopen_pending_ = true;
            } else {
              emit ImportFinished();
            }
          });
  connect(import_runner_, &ImportRunner::Canceled, this, [this, finish] {
    finish();
    log_->Info(
        tr("Import cancelled: %1 was left unchanged.").arg(QString::fromStdString(import_runner_->options().corpus)));
    emit ImportFinished();
  });
  connect(import_runner_, &ImportRunner::Failed, this, [this, finish](const QString& message) {
    finish();
    log_->Error(tr("Import failed: %1").arg(message));
    statusBar()->showMessage(tr("Import failed — see the log"), 8000);
    emit ImportFinished();
  });

  BuildMenus();
  RestoreLayout();
  UpdateTitle();
  OnFrameChanged(0);
}

MainWindow::~MainWindow() = default;

void MainWindow::BuildMenus() {
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("&Open Corpus…"), QKeySequence::Open, this, &MainWindow::ChooseAndOpen);
  recent_menu_ = file->addMenu(tr("Open &Recent"));
  file->addAction(tr("&Import…"), QKeySequence(Qt::CTRL | Qt::Key_I), this, &MainWindow::ShowImportDialog);
  file->addAction(tr("Load &Marker Set…"), this, &MainWindow::ChooseMarkerSet);
  file->addSeparator();
  file->addAction(tr("&Export Plot Figure…"), QKeySequence(Qt::CTRL | Qt::Key_E), this,
                  &MainWindow::ChooseAndExportPlot);
  file->addAction(tr("Export &3D View Figure…"), this, &MainWindow::ChooseAndExport3d);
  QMenu* export_menu = file->addMenu(tr("E&xport"));
  export_menu->setObjectName("exportMenu");
  export_menu->addAction(tr("Label Tiers as &TextGrid…"), this,
                         [this] { ChooseAndExportLabels(QStringLiteral("TextGrid")); });
  export_menu->addAction(tr("Label Tiers as &EAF…"), this, [this] { ChooseAndExportLabels(QStringLiteral("eaf")); });
  export_menu->addAction(tr("&Models, Key Recogniser or Dictionary File…"), this,
                         &MainWindow::ChooseAndExportModelFile);
  export_menu->addSeparator();
  export_menu->addAction(tr("&Shape Posterior Lane…"), this, [this] { ChooseAndExportScoreLane(0); });
  export_menu->addAction(tr("&Placement Posterior Lane…"), this, [this] { ChooseAndExportScoreLane(1); });
  export_menu->addAction(tr("&Key Tiers Lane…"), this, [this] { ChooseAndExportScoreLane(2); });
  file->addSeparator();
  file->addAction(tr("&Quit"), QKeySequence::Quit, this, &QWidget::close);
  UpdateRecentMenu();

  QMenu* edit = menuBar()->addMenu(tr("&Edit"));
  undo_action_ = labels_->undo_stack()->createUndoAction(this, tr("&Undo"));
  undo_action_->setShortcuts({QKeySequence(Qt::CTRL | Qt::Key_Z)});
  redo_action_ = labels_->undo_stack()->createRedoAction(this, tr("&Redo"));
  redo_action_->setShortcuts({QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z), QKeySequence(Qt::CTRL | Qt::Key_Y)});
  edit->addAction(undo_action_);
  edit->addAction(redo_action_);
  edit->addSeparator();
  edit->addAction(tr("&Label Lane"), QKeySequence(Qt::CTRL | Qt::Key_L), this, [this] { label_lane_->setFocus(); });

  QMenu* models = menuBar()->addMenu(tr("&Models"));
  models->addAction(tr("&Fit Model…"), QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_F), this,
                    [this] { ShowFitDialog(); });
  models->addAction(tr("&Inspect Reconstruction Errors…"), this, &MainWindow::ChooseAndInspectErrors);
  models->addAction(tr("&Phasing and Confusion…"), this, [this] { ShowPhasing(); });

  QMenu* analysis = menuBar()->addMenu(tr("&Analysis"));
  for (const JobSpec& spec : AnalysisJobs()) {
    const QString id = spec.id;
    analysis->addAction(spec.title + QStringLiteral("…"), this, [this, id] { ShowJobDialog(id); });
  }

  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(takes_dock_->toggleViewAction());
  view->addAction(errors_dock_->toggleViewAction());
  view->addAction(phasing_dock_->toggleViewAction());
  view->addAction(plots_dock_->toggleViewAction());
  view->addAction(log_dock_->toggleViewAction());
  view->addAction(counts_dock_->toggleViewAction());
  view->addSeparator();
  QAction* perspective = view->addAction(tr("&Perspective"));
  perspective->setCheckable(true);
  perspective->setChecked(marker_view_->camera().perspective);
  connect(perspective, &QAction::toggled, marker_view_, &MarkerView::SetPerspective);
  QAction* y_up = view->addAction(tr("Lab vertical is +&Y"));
  y_up->setCheckable(true);
  y_up->setChecked(settings_->value("view/yUp", false).toBool());
  marker_view_->SetYUp(y_up->isChecked());
  connect(y_up, &QAction::toggled, this, [this](bool on) {
    marker_view_->SetYUp(on);
    marker_view_->ResetView();
    settings_->setValue("view/yUp", on);
  });
  view->addAction(tr("&Reset 3D View"), QKeySequence(Qt::Key_R), marker_view_, &MarkerView::ResetView);
  view->addSeparator();
  view->addAction(tr("Zoom Plots &In"), QKeySequence::ZoomIn, this,
                  [this] { plots_->ZoomTime(0.5, plots_->cursor_time()); });
  view->addAction(tr("Zoom Plots &Out"), QKeySequence::ZoomOut, this,
                  [this] { plots_->ZoomTime(2.0, plots_->cursor_time()); });
  view->addAction(tr("Show &Whole Take"), QKeySequence(Qt::CTRL | Qt::Key_0), plots_, &TimeSeriesPanel::ShowAll);

  QMenu* play = menuBar()->addMenu(tr("&Playback"));
  play_action_ = play->addAction(tr("&Play / Pause"), QKeySequence(Qt::Key_Space), playback_, &Playback::Toggle);
  play->addAction(tr("Step &Forward"), QKeySequence(Qt::Key_Right), this, [this] { playback_->Step(1); });
  play->addAction(tr("Step &Back"), QKeySequence(Qt::Key_Left), this, [this] { playback_->Step(-1); });
  play->addAction(tr("Forward 10 Frames"), QKeySequence(Qt::SHIFT | Qt::Key_Right), this,
                  [this] { playback_->Step(10); });
  play->addAction(tr("Back 10 Frames"), QKeySequence(Qt::SHIFT | Qt::Key_Left), this, [this] { playback_->Step(-10); });
  play->addAction(tr("To &Start"), QKeySequence(Qt::Key_Home), this, [this] { playback_->Step(-playback_->frames()); });
  play->addAction(tr("To &End"), QKeySequence(Qt::Key_End), this, [this] { playback_->Step(playback_->frames()); });
}

void MainWindow::RestoreLayout() {
  QByteArray geometry = settings_->value("window/geometry").toByteArray();
  if (!geometry.isEmpty()) {
    restoreGeometry(geometry);
  } else {
    resize(1400, 900);
  }
  QByteArray state = settings_->value("window/state").toByteArray();
  if (!state.isEmpty()) restoreState(state);
  QString set = settings_->value("markerSet").toString();
  if (!set.isEmpty() && QFileInfo::exists(set)) LoadMarkerSetFile(set);
}

void MainWindow::SaveLayout() {
  settings_->setValue("window/geometry", saveGeometry());
  settings_->setValue("window/state", saveState());
  settings_->sync();
}

void MainWindow::closeEvent(QCloseEvent* event) {
  playback_->Pause();
  // Unsaved labels are saved first; the window closes when they are written. A
  // second close while they still wait (another writer holds the corpus) closes
  // anyway, after saying so in the log and on stderr.
  if (labels_->HasUnsavedEdits() && !close_requested_) {
    close_requested_ = true;
    labels_->SaveNow();
    log_->Info(tr("Saving labels before closing…"));
    connect(labels_, &LabelSession::Saved, this, [this] {
      if (close_requested_ && !labels_->HasUnsavedEdits()) close();
    });
    event->ignore();
    return;
  }
  if (labels_->HasUnsavedEdits()) {
    const QString m = tr("Closing with label edits not yet saved to %1 (retried once more on exit)").arg(corpus_path());
    log_->Warning(m);
    std::fprintf(stderr, "csw-workbench: %s\n", qPrintable(m));
  }
  import_runner_->Cancel();
  corpus_opener_->Cancel();
  take_loader_->Cancel();
  if (fit_dialog_ != nullptr) fit_dialog_->CancelFit();
  for (auto& [id, dialog] : job_dialogs_) dialog->Cancel();
  error_inspector_->Cancel();
  phasing_view_->Cancel();
  SaveLayout();
  event->accept();
}

QStringList MainWindow::recent_files() const { return settings_->value("recentFiles").toStringList(); }

void MainWindow::AddRecent(const QString& path) {
  QString abs = QFileInfo(path).absoluteFilePath();
  QStringList list = recent_files();
  list.removeAll(abs);
  list.prepend(abs);
  while (list.size() > kMaxRecent) list.removeLast();
  settings_->setValue("recentFiles", list);
  UpdateRecentMenu();
}

void MainWindow::UpdateRecentMenu() {
  if (recent_menu_ == nullptr) return;
  recent_menu_->clear();
  const QStringList list = recent_files();
  for (const QString& path : list) {
    recent_menu_->addAction(path, this, [this, path] { OpenCorpus(path); });
  }
  recent_menu_->setEnabled(!list.isEmpty());
}

QString MainWindow::corpus_path() const { return corpus_ ? QString::fromStdString(corpus_->path()) : QString(); }

void MainWindow::UpdateTitle() {
  QString title = QStringLiteral("csw-workbench");
  if (corpus_) title += QStringLiteral(" — ") + QFileInfo(corpus_path()).fileName();
  if (take_) title += QStringLiteral(" — ") + QString::fromStdString(take_->name);
  setWindowTitle(title);
}

// What the corpus opener's worker hands to the GUI thread.
struct MainWindow::OpenedCorpus {
  std::optional<Corpus> corpus;
  std::vector<TakeSummary> takes;
};

bool MainWindow::OpenCorpus(const QString& path, const QString& select) {
  if (path.isEmpty()) return false;
  if (corpus_opener_->running()) {
    // The open running now ends unseen; this one starts when it has.
    next_open_ = path;
    next_open_select_ = select;
    UpdateTakeBusy();
    return true;
  }
  opening_path_ = path;
  opening_select_ = select;
  auto out = std::make_shared<OpenedCorpus>();
  opening_result_ = out;
  const std::string file = path.toStdString();
  corpus_opener_->Start([file, out](Progress& progress) {
    progress.Update("opening corpus", 0.0);
    Corpus corpus = Corpus::Open(file);
    out->takes = corpus.Takes();
    out->corpus = std::move(corpus);
    progress.Update("opening corpus", 1.0);
  });
  UpdateTakeBusy();
  return true;
}

void MainWindow::OnCorpusOpenEnded(bool ok, const QString& message) {
  std::shared_ptr<OpenedCorpus> result = std::move(opening_result_);
  const QString path = opening_path_;
  const QString select = opening_select_;
  opening_path_.clear();
  opening_select_.clear();
  if (!next_open_.isEmpty()) {
    // Superseded by a later open: never shown (its corpus closes with `result`).
    const QString next = next_open_, next_select = next_open_select_;
    next_open_.clear();
    next_open_select_.clear();
    OpenCorpus(next, next_select);
    return;
  }
  UpdateTakeBusy();
  if (!ok || !result || !result->corpus) {
    const QString why = ok ? tr("nothing read") : message;
    log_->Error(tr("Cannot open %1: %2").arg(path, why));
    statusBar()->showMessage(tr("Cannot open %1 — see the log").arg(QFileInfo(path).fileName()), 8000);
    emit CorpusOpenFailed(path, why);
    return;
  }
  ShowOpenedCorpus(path, std::move(*result), select);
  emit CorpusOpened(path);
}

void MainWindow::ShowOpenedCorpus(const QString& path, OpenedCorpus opened, const QString& select) {
  const std::vector<TakeSummary>& takes = opened.takes;
  corpus_ = std::move(opened.corpus);
  std::shared_ptr<const Take> previous = std::move(take_);
  // A take still loading from the corpus shown before ends unseen.
  if (!wanted_take_.isEmpty()) {
    wanted_take_.clear();
    ++wanted_id_;
    take_loader_->Cancel();
    UpdateTakeBusy();
  }
  seek_frame_ = -1;
  labels_->ForgetSaved();
  labels_->SetTake(std::string(), nullptr, label_tier_combo_->currentText().toStdString());
  marker_view_->SetTake(nullptr);
  plots_->SetTake(nullptr);
  score_lanes_->SetTake(std::nullopt, {}, 0.0);
  playback_->SetTake(0, 0, nullptr);
  marker_combo_->clear();
  browser_->SetTakes(takes);
  phasing_view_->SetCorpus(corpus_path());
  AddRecent(path);
  log_->Info(tr("Opened %1 (%n take(s))", nullptr, static_cast<int>(takes.size())).arg(path));
  ReleaseOffTheGuiThread(std::move(previous));  // the views hold it no more
  UpdateTitle();
  if (takes.empty()) return;
  QString first = QString::fromStdString(takes.front().name);
  for (const TakeSummary& t : takes)
    if (QString::fromStdString(t.name) == select) first = select;
  browser_->SelectTake(first);
}

// What the take loader's worker hands to the GUI thread.
struct MainWindow::LoadedTake {
  std::shared_ptr<const Take> take;
  std::optional<MarkerSet> remembered;  // the marker set the take remembers, parsed
  QString remembered_error;             // why it is not usable, "" when fine
  TimeSeriesPanel::Prepared series;     // the plots' audio and first marker lane
  int first_visible = -1;               // FirstVisibleMarker
  std::optional<TakeScores> scores;     // the take's gestural score (ScoreLanes::kScoreSet)
  std::vector<uint8_t> unsure;          // UnsureFrames of those scores, empty when none
  QString scores_error;                 // why they could not be read or used, "" when fine
};

namespace {
// The first marker with data in a take (sampled over 64 frames), -1 when none.
int FirstVisibleMarker(const Take& take) {
  for (int64_t k = 0; k < take.markers.markers(); ++k) {
    for (int64_t f = 0; f < take.frames(); f += std::max<int64_t>(1, take.frames() / 64)) {
      if (take.markers.Visible(f, k)) return static_cast<int>(k);
    }
  }
  return -1;
}
}  // namespace

bool MainWindow::SelectTake(const QString& name) {
  if (!corpus_) return false;
  if (name != seek_take_) seek_frame_ = -1;
  if (take_ && QString::fromStdString(take_->name) == name) {
    // A load still running for another selection is superseded: it ends unseen.
    if (!wanted_take_.isEmpty()) {
      wanted_take_.clear();
      ++wanted_id_;
      take_loader_->Cancel();
      UpdateTakeBusy();
    }
    return true;
  }
  if (take_loader_->running() && loading_name_ == name) {
    // Already loading this very take: it stays the one to show.
    wanted_take_ = name;
    wanted_id_ = loading_id_;
    UpdateTakeBusy();
    return true;
  }
  wanted_take_ = name;
  ++wanted_id_;
  if (take_loader_->running()) {
    take_loader_->Cancel();  // stops it before the read when it has not begun; its end starts this one
  } else {
    StartTakeLoad();
  }
  UpdateTakeBusy();
  return true;
}

void MainWindow::StartTakeLoad() {
  if (wanted_take_.isEmpty() || !corpus_ || take_loader_->running()) return;
  loading_name_ = wanted_take_;
  loading_id_ = wanted_id_;
  auto out = std::make_shared<LoadedTake>();
  loading_result_ = out;
  const Corpus corpus = *corpus_;  // a copy sharing the open file (HDF5 calls are serialized)
  const std::string name = loading_name_.toStdString();
  const bool parse_set = !marker_set_;
  const auto quantity = static_cast<MarkerQuantity>(quantity_combo_->currentData().toInt());
  take_loader_->Start([corpus, name, out, parse_set, quantity](Progress& progress) {
    progress.Update("loading take", 0.0);
    auto take = std::make_shared<const Take>(corpus.LoadTake(name));
    // What grows with the take is prepared here too: the plots' audio and
    // first marker lane (the first marker with data, so the panel shows some motion).
    out->series.audio = TimeSeriesPanel::AudioSeries(*take);
    out->first_visible = FirstVisibleMarker(*take);
    if (out->first_visible >= 0) {
      out->series.marker = out->first_visible;
      out->series.quantity = quantity;
      out->series.series = TimeSeriesPanel::MarkerLaneSeries(*take, out->first_visible, quantity);
    }
    if (parse_set && !take->markerset_json.empty()) {
      try {
        out->remembered = ParseMarkerSet(take->markerset_json, corpus.path() + ": take " + take->name);
      } catch (const std::exception& e) {
        out->remembered_error = QString::fromStdString(e.what());
      }
    }
    // The gestural score (score lanes) and where the key recogniser is unsure (label lane, U).
    static_assert(std::string_view(ScoreLanes::kScoreSet) == LabelSession::kUnsureScores);
    try {
      out->scores = corpus.LoadScores(name, ScoreLanes::kScoreSet);
      if (out->scores)
        out->unsure = UnsureFrames(*out->scores, take->frames(), take->rate_hz, LabelSession::kUnsurePosterior);
    } catch (const std::exception& e) {
      out->scores_error = QString::fromStdString(e.what());
    }
    out->take = std::move(take);
    progress.Update("loading take", 1.0);
  });
  statusBar()->showMessage(tr("Loading take %1…").arg(loading_name_));
}

void MainWindow::OnTakeLoadEnded(bool ok, const QString& message) {
  std::shared_ptr<LoadedTake> result = std::move(loading_result_);
  const QString name = loading_name_;
  const bool current = loading_id_ == wanted_id_ && !wanted_take_.isEmpty();
  loading_name_.clear();
  if (!current) {
    // Superseded: never shown. The latest selection, if any, loads now.
    StartTakeLoad();
    UpdateTakeBusy();
    return;
  }
  wanted_take_.clear();
  UpdateTakeBusy();
  if (!ok || !result || !result->take) {
    const QString why = ok ? tr("no take read") : message;
    log_->Error(tr("Cannot load take %1: %2").arg(name, why));
    statusBar()->showMessage(tr("Cannot load take %1 — see the log").arg(name), 8000);
    seek_frame_ = -1;
    emit TakeLoadFailed(name, why);
    return;
  }
  ShowLoadedTake(std::move(*result));
}

void MainWindow::UpdateTakeBusy() {
  const QString opening = !next_open_.isEmpty() ? next_open_ : opening_path_;
  const bool busy = !wanted_take_.isEmpty() || !opening.isEmpty();
  const QString what = !opening.isEmpty() ? tr("Opening %1…").arg(QFileInfo(opening).fileName())
                                          : tr("Loading take %1…").arg(wanted_take_);
  take_busy_->setVisible(busy);
  take_busy_->setToolTip(busy ? what : QString());
  if (busy) {
    statusBar()->showMessage(what);
  } else if (statusBar()->currentMessage().startsWith(tr("Loading take")) ||
             statusBar()->currentMessage().startsWith(tr("Opening"))) {
    statusBar()->clearMessage();
  }
}

void MainWindow::ShowLoadedTake(LoadedTake loaded) {
  std::shared_ptr<const Take> take = std::move(loaded.take);
  const std::optional<MarkerSet>& remembered = loaded.remembered;
  const QString& remembered_error = loaded.remembered_error;
  const QString name = QString::fromStdString(take->name);
  // Labels this session saved (or is saving) are newer than what the open corpus holds.
  if (auto tiers = labels_->KnownTiers(corpus_->path(), take->name)) {
    auto copy = std::make_shared<Take>(*take);
    copy->tiers = std::move(*tiers);
    take = std::move(copy);
  }
  playback_->Pause();
  std::shared_ptr<const Take> previous = std::move(take_);
  take_ = take;
  // A marker set loaded by the user wins; otherwise the one the take was
  // imported with (the corpus remembers it), so sticks and frames show at once.
  if (!remembered_error.isEmpty() && !marker_set_)
    log_->Warning(tr("Marker set remembered by %1 not usable: %2").arg(name, remembered_error));
  const MarkerSet* set = marker_set_ ? &*marker_set_ : (remembered ? &*remembered : nullptr);
  try {
    marker_view_->SetTake(take_, set);
  } catch (const std::exception& e) {
    log_->Warning(tr("Marker set not applied to %1: %2").arg(name, QString::fromStdString(e.what())));
    marker_view_->SetTake(take_, nullptr);
  }
  plots_->SetHiddenTier(label_tier_combo_->currentText().trimmed());  // drawn by the label lane instead
  plots_->SetTake(take_, std::move(loaded.series));
  if (!loaded.scores_error.isEmpty())
    log_->Warning(tr("Gestural score of %1 not shown: %2").arg(name, loaded.scores_error));
  score_lanes_->SetTake(std::move(loaded.scores), take_->tiers, plots_->view_end());
  playback_->SetTake(take_->frames(), take_->rate_hz, &take_->audio);  // rewinds to frame 0
  marker_combo_->clear();
  marker_combo_->addItem(tr("(none)"), -1);
  for (size_t k = 0; k < take_->marker_names.size(); ++k)
    marker_combo_->addItem(QString::fromStdString(take_->marker_names[k]), static_cast<int>(k));
  // Start with the first marker that has data, so the panel shows some motion.
  const int first_visible = loaded.first_visible;
  if (first_visible >= 0) {
    marker_combo_->setCurrentIndex(first_visible + 1);
    OnMarkerSeriesChosen();
  }
  if (browser_->current_take() != name) {
    browser_->blockSignals(true);
    browser_->SelectTake(name);
    browser_->blockSignals(false);
  }
  SetLabelTier(label_tier_combo_->currentText());
  labels_->SetUnsureFrames(take_->name, std::move(loaded.unsure));
  ReleaseOffTheGuiThread(std::move(previous));  // the views hold it no more
  UpdateTitle();
  OnFrameChanged(playback_->frame());
  if (seek_frame_ >= 0 && seek_take_ == name) {
    const qint64 frame = seek_frame_;
    seek_frame_ = -1;
    playback_->Seek(frame);
    log_->Info(tr("%1: worst frame %2").arg(name).arg(frame + take_->first_frame));
  }
  emit TakeShown(name);
}

bool MainWindow::SetLabelTier(const QString& tier) {
  const QString name = tier.trimmed().isEmpty() ? QStringLiteral("keys") : tier.trimmed();
  if (label_tier_combo_->currentText() != name) label_tier_combo_->setCurrentText(name);
  if (!take_ || !corpus_) {
    labels_->SetTake(std::string(), nullptr, name.toStdString());
    return false;
  }
  try {
    labels_->SetTake(corpus_->path(), take_, name.toStdString());
  } catch (const std::exception& e) {
    log_->Error(tr("Cannot label tier %1: %2").arg(name, QString::fromStdString(e.what())));
    labels_->SetTake(std::string(), nullptr, name.toStdString());
    plots_->SetHiddenTier(QString());
    return false;
  }
  plots_->SetHiddenTier(name);
  // The plots show the tiers as this session last wrote them (e.g. the tier
  // just left, with its edits), not as they were loaded.
  if (auto known = labels_->KnownTiers(corpus_->path(), take_->name); known && !SameTiers(*known, take_->tiers)) {
    auto copy = std::make_shared<Take>(*take_);
    copy->tiers = std::move(*known);
    take_ = copy;
    const double t0 = plots_->view_start(), t1 = plots_->view_end();
    const int marker = plots_->marker();
    const MarkerQuantity quantity = plots_->quantity();
    plots_->SetTake(take_, plots_->Shown());
    plots_->SetMarkerSeries(marker, quantity);
    plots_->SetTimeRange(t0, t1);
    plots_->SetCursorTime(playback_->time_s());
    score_lanes_->SetTiers(take_->tiers);
  }
  label_lane_->SetTimeRange(plots_->view_start(), plots_->view_end());
  label_lane_->SetCursorFrame(playback_->frame());
  return true;
}

bool MainWindow::SnapLabelToSpeedMinimum() {
  if (!take_ || !labels_->has_take()) return false;
  const int64_t frame = playback_->frame();
  const long index = labels_->LabelAtFrame(frame);
  if (index < 0) {
    log_->Info(tr("Snap: no label on frame %1").arg(frame + take_->first_frame));
    return false;
  }
  const int marker = plots_->marker();
  if (marker < 0) {
    log_->Warning(tr("Snap: choose the marker whose speed minima labels snap to (Marker, above the plots)"));
    return false;
  }
  const std::vector<float> speed = MarkerSeries(*take_, marker, MarkerQuantity::kSpeed);
  const auto window = std::max<int64_t>(1, std::llround(kSnapWindowS * take_->rate_hz));
  const int64_t to = NearestSpeedMinimum(speed, frame, window);
  const QString name = QString::fromStdString(take_->marker_names[static_cast<size_t>(marker)]);
  if (to < 0) {
    log_->Info(tr("Snap: %1's speed has no minimum within %2 s of frame %3")
                   .arg(name)
                   .arg(kSnapWindowS)
                   .arg(frame + take_->first_frame));
    return false;
  }
  if (to == frame) return true;
  if (!labels_->MoveLabel(index, to)) return false;
  playback_->Seek(to);
  return true;
}

bool MainWindow::LoadMarkerSetFile(const QString& path) {
  try {
    marker_set_ = LoadMarkerSet(path.toStdString());
  } catch (const std::exception& e) {
    log_->Error(tr("Cannot load marker set %1: %2").arg(path, QString::fromStdString(e.what())));
    return false;
  }
  settings_->setValue("markerSet", QFileInfo(path).absoluteFilePath());
  log_->Info(tr("Marker set %1 loaded").arg(QString::fromStdString(marker_set_->name)));
  if (take_) {
    int64_t frame = playback_->frame();
    try {
      marker_view_->SetTake(take_, &*marker_set_);
    } catch (const std::exception& e) {
      log_->Warning(tr("Marker set not applied: %1").arg(QString::fromStdString(e.what())));
      marker_view_->SetTake(take_, nullptr);
    }
    marker_view_->SetFrame(frame);
  }
  return true;
}

void MainWindow::OnFrameChanged(qint64 frame) {
  marker_view_->SetFrame(frame);
  label_lane_->SetCursorFrame(frame);
  if (take_ && take_->rate_hz > 0) {
    double t = static_cast<double>(frame) / take_->rate_hz;
    plots_->SetCursorTime(t);
    score_lanes_->SetCursorTime(t);
    frame_label_->setText(tr("frame %1  t = %2 s").arg(frame + take_->first_frame).arg(t, 0, 'f', 3));
  } else {
    frame_label_->setText(tr("no take"));
  }
  if (marker_view_->selected_marker() >= 0) statusBar()->showMessage(marker_view_->SelectionText());
}

void MainWindow::OnMarkerPicked(int marker) {
  if (marker < 0) {
    statusBar()->clearMessage();
    return;
  }
  statusBar()->showMessage(marker_view_->SelectionText());
  log_->Info(marker_view_->SelectionText() + tr(" (frame %1)").arg(playback_->frame() + take_->first_frame));
  marker_combo_->setCurrentIndex(marker + 1);
  OnMarkerSeriesChosen();
}

void MainWindow::OnMarkerSeriesChosen() {
  int marker = marker_combo_->currentData().toInt();
  auto q = static_cast<MarkerQuantity>(quantity_combo_->currentData().toInt());
  if (marker == plots_->marker() && q == plots_->quantity()) return;
  plots_->SetMarkerSeries(marker, q);
  if (take_ && take_->rate_hz > 0) plots_->SetCursorTime(static_cast<double>(playback_->frame()) / take_->rate_hz);
}

bool MainWindow::StartImport(const jobs::ImportOptions& options) {
  if (std::string why = options.Check(); !why.empty()) {
    log_->Error(tr("Import not started: %1").arg(QString::fromStdString(why)));
    return false;
  }
  if (!import_runner_->Start(options)) {
    log_->Warning(tr("An import is already running."));
    return false;
  }
  log_->Info(tr("Importing %n file(s) into %1…", nullptr, static_cast<int>(options.files.size()))
                 .arg(QString::fromStdString(options.corpus)));
  import_progress_ = new QProgressDialog(tr("Importing…"), tr("Cancel"), 0, 1000, this);
  import_progress_->setObjectName("importProgress");
  import_progress_->setWindowTitle(tr("Import"));
  // Not modal: browsing and playback go on while the job runs.
  import_progress_->setWindowModality(Qt::NonModal);
  import_progress_->setAutoClose(false);
  import_progress_->setAutoReset(false);
  import_progress_->setMinimumDuration(0);
  connect(import_progress_, &QProgressDialog::canceled, import_runner_, &ImportRunner::Cancel);
  import_progress_->setValue(0);
  import_progress_->show();
  return true;
}

bool MainWindow::ExportPlot(const QString& path, int width, int height) {
  try {
    ExportFigure(plots_->plot(), path, width, height);
  } catch (const std::exception& e) {
    log_->Error(tr("Figure not saved: %1").arg(QString::fromStdString(e.what())));
    return false;
  }
  log_->Info(tr("Figure saved to %1").arg(path));
  return true;
}

bool MainWindow::Export3dView(const QString& path) {
  try {
    ExportPainted([this](QPainter& p, QSize s) { marker_view_->Render(p, s); }, marker_view_->size(), path);
  } catch (const std::exception& e) {
    log_->Error(tr("Figure not saved: %1").arg(QString::fromStdString(e.what())));
    return false;
  }
  log_->Info(tr("Figure saved to %1").arg(path));
  return true;
}

void MainWindow::ChooseAndOpen() {
  QString path = QFileDialog::getOpenFileName(this, tr("Open Corpus"), settings_->value("lastDir").toString(),
                                              tr("csw corpus (*.h5 *.hdf5);;All files (*)"));
  if (path.isEmpty()) return;
  settings_->setValue("lastDir", QFileInfo(path).absolutePath());
  OpenCorpus(path);
}

void MainWindow::ChooseAndExportPlot() {
  QString path = QFileDialog::getSaveFileName(this, tr("Export Plot Figure"), settings_->value("lastDir").toString(),
                                              kFigureFilter);
  if (!path.isEmpty()) ExportPlot(path);
}

void MainWindow::ChooseAndExport3d() {
  QString path = QFileDialog::getSaveFileName(this, tr("Export 3D View Figure"), settings_->value("lastDir").toString(),
                                              kFigureFilter);
  if (!path.isEmpty()) Export3dView(path);
}

void MainWindow::ChooseMarkerSet() {
  QString path = QFileDialog::getOpenFileName(this, tr("Load Marker Set"), settings_->value("lastDir").toString(),
                                              tr("Marker set (*.json);;All files (*)"));
  if (!path.isEmpty()) LoadMarkerSetFile(path);
}

FitDialog* MainWindow::ShowFitDialog() {
  if (fit_dialog_ == nullptr) {
    fit_dialog_ = new FitDialog(log_, this);
    connect(fit_dialog_, &FitDialog::ModelSaved, this, [this](const QString& path) {
      settings_->setValue("lastModelFile", path);
      statusBar()->showMessage(tr("Model saved to %1").arg(path), 5000);
    });
  }
  if (!fit_dialog_->running()) {
    // The takes the browser lists (read when the corpus was opened): no file access here.
    QStringList takes;
    for (int row = 0; row < browser_->take_count(); ++row) takes << browser_->Cell(row, CorpusBrowser::kName);
    fit_dialog_->SetCorpus(corpus_path(), takes);
    if (marker_set_) fit_dialog_->SetMarkerSetFile(settings_->value("markerSet").toString());
  }
  fit_dialog_->show();
  fit_dialog_->raise();
  return fit_dialog_;
}

JobDialog* MainWindow::ShowJobDialog(const QString& id) {
  const JobSpec* spec = FindAnalysisJob(id);
  if (spec == nullptr) return nullptr;
  JobDialog*& dialog = job_dialogs_[id];
  if (dialog == nullptr) {
    dialog = new JobDialog(*spec, log_, this);
    // A job that wrote into the corpus: reopen it (off the GUI thread) on the shown take.
    connect(dialog, &JobDialog::CorpusWritten, this, [this](const QString& corpus) {
      if (corpus != corpus_path()) return;
      OpenCorpus(corpus, take_ ? QString::fromStdString(take_->name) : QString());
    });
  }
  if (!dialog->running()) {
    dialog->SetCorpus(corpus_path());
    // The marker set loaded with File > Load Marker Set, for jobs that read one.
    const QString set = settings_->value("markerSet").toString();
    if (dialog->field(QStringLiteral("markerset")) != nullptr && dialog->Value(QStringLiteral("markerset")).isEmpty() &&
        marker_set_ && !set.isEmpty())
      dialog->SetValue(QStringLiteral("markerset"), set);
  }
  dialog->show();
  dialog->raise();
  return dialog;
}

bool MainWindow::InspectErrors(const QString& model_file, const QStringList& takes) {
  if (!corpus_) {
    log_->Error(tr("Open a corpus before inspecting reconstruction errors."));
    return false;
  }
  marker_view_->SetReconstruction(nullptr);
  if (!error_inspector_->Start(corpus_path(), model_file, takes)) return false;
  errors_dock_->show();
  errors_dock_->raise();
  return true;
}

void MainWindow::ChooseAndInspectErrors() {
  QString start = settings_->value("lastModelFile").toString();
  if (start.isEmpty()) start = settings_->value("lastDir").toString();
  const QString path = QFileDialog::getOpenFileName(this, tr("Inspect Reconstruction Errors of a Model File"), start,
                                                    tr("csw model file (*.h5);;All files (*)"));
  if (path.isEmpty()) return;
  settings_->setValue("lastModelFile", path);
  InspectErrors(path);
}

void MainWindow::OnUtteranceChosen(const QString& take, qint64 frame) {
  playback_->Pause();
  seek_take_ = take;
  if (!SelectTake(take)) return;
  if (take_loading()) {
    seek_frame_ = frame;  // applied when the take is shown
    return;
  }
  seek_frame_ = -1;
  playback_->Seek(frame);
  log_->Info(tr("%1: worst frame %2").arg(take).arg(frame + take_->first_frame));
}

bool MainWindow::ShowPhasing(const QString& keys_file) {
  phasing_view_->SetCorpus(corpus_path());
  phasing_dock_->show();
  phasing_dock_->raise();
  if (keys_file.isEmpty()) return true;
  if (!corpus_) {
    log_->Error(tr("Open a corpus before running the phasing analysis."));
    return false;
  }
  return phasing_view_->Run(corpus_path(), keys_file);
}

bool MainWindow::ExportLabels(const QString& path) {
  if (!take_) {
    log_->Error(tr("No take shown: no labels to export."));
    return false;
  }
  std::vector<LabelTier> tiers = TiersToExport(*take_, labels_, corpus_ ? corpus_->path() : std::string());
  double end = take_->duration_s();
  for (const LabelTier& t : tiers) end = std::max(end, t.end_s);
  if (!exporter_->ExportLabels(path, std::move(tiers), 0.0, end)) {
    log_->Warning(tr("An export is already running."));
    return false;
  }
  return true;
}

bool MainWindow::ExportModelFile(const QString& source, const QString& destination) {
  if (!exporter_->ExportModelFile(source, destination)) {
    log_->Warning(tr("An export is already running."));
    return false;
  }
  return true;
}

void MainWindow::ChooseAndExportLabels(const QString& extension) {
  if (!take_) {
    log_->Error(tr("No take shown: no labels to export."));
    return;
  }
  const QString start =
      QDir(settings_->value("lastDir").toString()).filePath(QString::fromStdString(take_->name) + "." + extension);
  const QString filter =
      extension == QStringLiteral("eaf") ? tr("ELAN annotation (*.eaf)") : tr("Praat TextGrid (*.TextGrid)");
  const QString path = QFileDialog::getSaveFileName(this, tr("Export Label Tiers"), start, filter);
  if (!path.isEmpty()) ExportLabels(path);
}

void MainWindow::ChooseAndExportModelFile() {
  QString start = settings_->value("lastModelFile").toString();
  if (start.isEmpty()) start = settings_->value("lastDir").toString();
  const QString source = QFileDialog::getOpenFileName(this, tr("Export a Models, Key Recogniser or Dictionary File"),
                                                      start, tr("csw HDF5 file (*.h5);;All files (*)"));
  if (source.isEmpty()) return;
  const QString destination = QFileDialog::getSaveFileName(this, tr("Export To"), source, tr("csw HDF5 file (*.h5)"));
  if (!destination.isEmpty()) ExportModelFile(source, destination);
}

void MainWindow::ChooseAndExportScoreLane(int lane) {
  if (!score_lanes_->has_scores()) {
    log_->Error(tr("The shown take has no gestural score (csw keys score writes it)."));
    return;
  }
  const QString path = QFileDialog::getSaveFileName(this, tr("Export Score Lane Figure"),
                                                    settings_->value("lastDir").toString(), kFigureFilter);
  if (path.isEmpty()) return;
  try {
    score_lanes_->ExportLane(lane, path);
    log_->Info(tr("Figure saved to %1").arg(path));
  } catch (const std::exception& e) {
    log_->Error(tr("Figure not saved: %1").arg(QString::fromStdString(e.what())));
  }
}

void MainWindow::ShowImportDialog() {
  QDialog dialog(this);
  dialog.setWindowTitle(tr("Import"));
  auto* form = new QFormLayout(&dialog);
  auto* files = new QListWidget(&dialog);
  auto* add = new QPushButton(tr("Add Files…"), &dialog);
  auto* remove = new QPushButton(tr("Remove"), &dialog);
  auto* file_buttons = new QHBoxLayout();
  file_buttons->addWidget(add);
  file_buttons->addWidget(remove);
  file_buttons->addStretch(1);
  auto* file_box = new QVBoxLayout();
  file_box->addWidget(files);
  file_box->addLayout(file_buttons);
  form->addRow(tr("Files (captures with their\n.TextGrid/.eaf/.wav):"), file_box);
  auto* corpus = new QLineEdit(corpus_path(), &dialog);
  auto* corpus_browse = new QPushButton(tr("…"), &dialog);
  auto* corpus_row = new QHBoxLayout();
  corpus_row->addWidget(corpus);
  corpus_row->addWidget(corpus_browse);
  form->addRow(tr("Into corpus:"), corpus_row);
  auto* markerset = new QLineEdit(settings_->value("markerSet").toString(), &dialog);
  auto* set_browse = new QPushButton(tr("…"), &dialog);
  auto* set_row = new QHBoxLayout();
  set_row->addWidget(markerset);
  set_row->addWidget(set_browse);
  form->addRow(tr("Marker set (optional):"), set_row);
  auto* replace = new QCheckBox(tr("Replace takes that already exist"), &dialog);
  form->addRow(QString(), replace);
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, &dialog);
  buttons->button(QDialogButtonBox::Ok)->setText(tr("Import"));
  form->addRow(buttons);
  connect(buttons, &QDialogButtonBox::accepted, &dialog, &QDialog::accept);
  connect(buttons, &QDialogButtonBox::rejected, &dialog, &QDialog::reject);
  connect(add, &QPushButton::clicked, &dialog, [&] {
    QStringList chosen = QFileDialog::getOpenFileNames(
        &dialog, tr("Add Files"), settings_->value("lastDir").toString(),
        tr("Captures and labels (*.c3d *.trc *.bvh *.TextGrid *.eaf *.wav);;All files (*)"));
    if (!chosen.isEmpty()) settings_->setValue("lastDir", QFileInfo(chosen.front()).absolutePath());
    files->addItems(chosen);
  });
  connect(remove, &QPushButton::clicked, &dialog, [&] { qDeleteAll(files->selectedItems()); });
  connect(corpus_browse, &QPushButton::clicked, &dialog, [&] {
    QString p = QFileDialog::getSaveFileName(&dialog, tr("Corpus"), corpus->text(), tr("csw corpus (*.h5)"), nullptr,
                                             QFileDialog::DontConfirmOverwrite);
    if (!p.isEmpty()) corpus->setText(p);
  });
  connect(set_browse, &QPushButton::clicked, &dialog, [&] {
    QString p = QFileDialog::getOpenFileName(&dialog, tr("Marker set"), markerset->text(), tr("Marker set (*.json)"));
    if (!p.isEmpty()) markerset->setText(p);
  });
  if (dialog.exec() != QDialog::Accepted) return;
  jobs::ImportOptions options;
  for (int i = 0; i < files->count(); ++i) options.files.push_back(files->item(i)->text().toStdString());
  options.corpus = corpus->text().toStdString();
  options.markerset = markerset->text().toStdString();
  options.replace = replace->isChecked();
  StartImport(options);
}

}  // namespace csw::gui

#pragma once
// The workbench's main window: corpus browser, 3D view, time-series panel and
// log as dockable views (layout remembered), recent files, background import
// with progress and Cancel, playback and figure export.
#include <QMainWindow>
#include <map>
#include <memory>
#include <optional>

#include "core/markerset.h"
#include "core/take.h"
#include "io/corpus/corpus.h"
#include "workbench/jobs/jobs.h"

class QAction;
class QComboBox;
class QDockWidget;
class QLabel;
class QMenu;
class QProgressDialog;
class QSettings;

namespace csw::gui {

class CorpusBrowser;
class ErrorInspector;
class ExportRunner;
class FitDialog;
class JobDialog;
class ImportRunner;
class JobRunner;
class LabelCountsPanel;
class LabelLane;
class LabelSession;
class LogPanel;
class MarkerView;
class PhasingView;
class Playback;
class ScoreLanes;
class TimeSeriesPanel;

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  // settings_path: an INI file for layout and recent files; empty = the user's
  // standard settings (QSettings "csw"/"csw-workbench").
  explicit MainWindow(const QString& settings_path = QString(), QWidget* parent = nullptr);
  ~MainWindow() override;

  // Opens a corpus on a worker thread (the GUI thread never waits on HDF5) and,
  // when it is open, shows it: takes listed, `select` (or the first take)
  // selected, CorpusOpened emitted. On failure the error goes to the log and
  // the status line, the current corpus stays, CorpusOpenFailed is emitted.
  // An open requested while another runs supersedes it (the earlier one is
  // never shown). False only for an empty path.
  bool OpenCorpus(const QString& path, const QString& select = QString());
  // A corpus is being opened (OpenCorpus has not ended yet).
  bool corpus_opening() const { return !opening_path_.isEmpty() || !next_open_.isEmpty(); }
  // Shows one take of the open corpus: loads it on a worker thread (the GUI
  // thread never waits on HDF5) with a busy indication in the status bar, and
  // shows it when it arrives (TakeShown). A later selection supersedes one
  // still loading, whose take is then never shown. A failure goes to the log
  // and the status line (TakeLoadFailed), the shown take staying. False when
  // no corpus is open; true at once when the take is already shown.
  bool SelectTake(const QString& name);
  // A selection is loading (or waits for the load it superseded to end).
  // True while a corpus opens too (its first take is shown next).
  bool take_loading() const { return !wanted_take_.isEmpty() || corpus_opening(); }
  // The take being loaded for the latest selection, "" when none.
  QString loading_take() const { return wanted_take_; }
  // The take loader's runner: its worker hook (JobRunner::SetWorkerHook) sees
  // the stage "loading take" at 0 before the corpus is read and at 1 after.
  JobRunner* take_loader() const { return take_loader_; }
  // Loads a marker-set JSON for sticks and cluster frames; false (and a log line) on failure.
  bool LoadMarkerSetFile(const QString& path);
  // Starts the import job in the background (progress dialog with Cancel).
  bool StartImport(const jobs::ImportOptions& options);
  // Saves the time-series panel / the 3D view as PNG, SVG or PDF; false (and a log line) on failure.
  bool ExportPlot(const QString& path, int width = 0, int height = 0);
  bool Export3dView(const QString& path);
  // Labels `tier` (a point tier of key codes; created empty when the take has
  // none) of the shown take in the key-label lane; false (and a log line) when
  // the take's tier of that name cannot be labelled.
  bool SetLabelTier(const QString& tier);
  // Moves the label on the cursor frame to the nearest speed minimum of the
  // marker lane's marker within kSnapWindowS (key S in the label lane); false
  // (and a log line) when there is no label there, no marker lane or no minimum.
  static constexpr double kSnapWindowS = 0.25;
  bool SnapLabelToSpeedMinimum();
  // Shows the model-fit dialog (not modal) for the open corpus's takes.
  FitDialog* ShowFitDialog();
  // Shows the dialog of an Analysis menu job (job_dialog.h: "cue",
  // "keys-suggest", "keys-train", "keys-score", "phasing", "clean",
  // "dict-build") on the open corpus; null for an unknown id. A job that
  // writes into the corpus reopens it when it succeeds, on the shown take.
  JobDialog* ShowJobDialog(const QString& id);
  // Inverts the models of `model_file` on the open corpus in the background and
  // shows the reconstruction-error inspector dock; false (and a log line) when
  // no corpus is open or an inspection runs. Clicking an utterance's bar shows
  // that take at its worst frame; the 3D view then draws the models'
  // reconstruction of the shown take with its observed markers.
  // `takes`: take selections (take_selection.h), empty = every take but
  // generated fill versions.
  bool InspectErrors(const QString& model_file, const QStringList& takes = {});

  // Gestural score and phasing views, export (issue 16, items 4 and 6).
  // Shows the phasing and confusion dock; with a key-recogniser file, runs
  // csw keys score (dry run) and csw phasing on the open corpus in it.
  bool ShowPhasing(const QString& keys_file = QString());
  // Writes the shown take's label tiers (unsaved label edits included) to a
  // .TextGrid or .eaf file on a worker; false when none is shown or an export runs.
  bool ExportLabels(const QString& path);
  // Copies a models / key-recogniser / dictionary file to `destination` on a
  // worker and shows a summary of what it holds.
  bool ExportModelFile(const QString& source, const QString& destination);

  QString corpus_path() const;
  std::shared_ptr<const Take> take() const { return take_; }
  QStringList recent_files() const;

  CorpusBrowser* browser() const { return browser_; }
  MarkerView* marker_view() const { return marker_view_; }
  TimeSeriesPanel* plots() const { return plots_; }
  LogPanel* log() const { return log_; }
  Playback* playback() const { return playback_; }
  ImportRunner* import_runner() const { return import_runner_; }
  QProgressDialog* import_progress() const { return import_progress_; }
  QComboBox* marker_combo() const { return marker_combo_; }
  QComboBox* quantity_combo() const { return quantity_combo_; }
  QComboBox* label_tier_combo() const { return label_tier_combo_; }
  LabelSession* labels() const { return labels_; }
  LabelLane* label_lane() const { return label_lane_; }
  LabelCountsPanel* label_counts() const { return label_counts_; }
  QDockWidget* counts_dock() const { return counts_dock_; }
  QAction* undo_action() const { return undo_action_; }
  QAction* redo_action() const { return redo_action_; }
  QDockWidget* takes_dock() const { return takes_dock_; }
  QDockWidget* plots_dock() const { return plots_dock_; }
  QDockWidget* log_dock() const { return log_dock_; }
  FitDialog* fit_dialog() const { return fit_dialog_; }
  ErrorInspector* error_inspector() const { return error_inspector_; }
  QDockWidget* errors_dock() const { return errors_dock_; }
  ScoreLanes* score_lanes() const { return score_lanes_; }
  PhasingView* phasing_view() const { return phasing_view_; }
  QDockWidget* phasing_dock() const { return phasing_dock_; }
  ExportRunner* exporter() const { return exporter_; }

 signals:
  void CorpusOpened(const QString& path);
  void CorpusOpenFailed(const QString& path, const QString& message);
  void TakeShown(const QString& name);
  void TakeLoadFailed(const QString& name, const QString& message);
  void ImportFinished();

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  void BuildMenus();
  void SaveLayout();
  void RestoreLayout();
  void AddRecent(const QString& path);
  void UpdateRecentMenu();
  void OnFrameChanged(qint64 frame);
  void OnMarkerPicked(int marker);
  void OnMarkerSeriesChosen();
  void ShowImportDialog();
  void ChooseAndOpen();
  void ChooseAndExportPlot();
  void ChooseAndExport3d();
  void ChooseMarkerSet();
  void ChooseAndInspectErrors();
  void ChooseAndExportLabels(const QString& extension);
  void ChooseAndExportModelFile();
  void ChooseAndExportScoreLane(int lane);
  void OnUtteranceChosen(const QString& take, qint64 frame);
  void UpdateTitle();
  void StartTakeLoad();
  void OnTakeLoadEnded(bool ok, const QString& message);
  struct OpenedCorpus;
  void OnCorpusOpenEnded(bool ok, const QString& message);
  void ShowOpenedCorpus(const QString& path, OpenedCorpus opened, const QString& select);
  struct LoadedTake;
  void ShowLoadedTake(LoadedTake loaded);
  void UpdateTakeBusy();

  std::unique_ptr<QSettings> settings_;
  std::optional<Corpus> corpus_;
  std::shared_ptr<const Take> take_;
  std::optional<MarkerSet> marker_set_;

  CorpusBrowser* browser_ = nullptr;
  MarkerView* marker_view_ = nullptr;
  TimeSeriesPanel* plots_ = nullptr;
  LogPanel* log_ = nullptr;
  Playback* playback_ = nullptr;
  ImportRunner* import_runner_ = nullptr;
  QProgressDialog* import_progress_ = nullptr;
  QComboBox* marker_combo_ = nullptr;
  QComboBox* quantity_combo_ = nullptr;
  QComboBox* label_tier_combo_ = nullptr;
  LabelSession* labels_ = nullptr;
  LabelLane* label_lane_ = nullptr;
  LabelCountsPanel* label_counts_ = nullptr;
  QDockWidget* counts_dock_ = nullptr;
  QAction* undo_action_ = nullptr;
  QAction* redo_action_ = nullptr;
  QDockWidget* takes_dock_ = nullptr;
  QDockWidget* plots_dock_ = nullptr;
  QDockWidget* log_dock_ = nullptr;
  FitDialog* fit_dialog_ = nullptr;
  std::map<QString, JobDialog*> job_dialogs_;
  ErrorInspector* error_inspector_ = nullptr;
  QDockWidget* errors_dock_ = nullptr;
  ScoreLanes* score_lanes_ = nullptr;
  PhasingView* phasing_view_ = nullptr;
  QDockWidget* phasing_dock_ = nullptr;
  ExportRunner* exporter_ = nullptr;
  QMenu* recent_menu_ = nullptr;
  QLabel* frame_label_ = nullptr;
  QAction* play_action_ = nullptr;
  // Take loading (SelectTake): one load at a time on take_loader_; the latest
  // selection not yet shown waits in wanted_take_ (request wanted_id_). A
  // load whose request id is no longer wanted_id_ ends unseen.
  JobRunner* take_loader_ = nullptr;
  QWidget* take_busy_ = nullptr;
  QString wanted_take_;
  quint64 wanted_id_ = 0;
  quint64 loading_id_ = 0;
  QString loading_name_;
  std::shared_ptr<LoadedTake> loading_result_;
  // OnUtteranceChosen's frame, applied when its take is shown.
  QString seek_take_;
  qint64 seek_frame_ = -1;
  bool close_requested_ = false;
  // Corpus opening (OpenCorpus): one open at a time on corpus_opener_; a
  // later request waits in next_open_ and supersedes the running one.
  JobRunner* corpus_opener_ = nullptr;
  QString opening_path_;
  QString opening_select_;
  QString next_open_;
  QString next_open_select_;
  std::shared_ptr<OpenedCorpus> opening_result_;
  bool import_reopen_pending_ = false;
};

}  // namespace csw::gui

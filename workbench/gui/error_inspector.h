#pragma once
// The reconstruction-error inspector: inverts a model file's face and hand
// models on the open corpus's takes with jobs::Invert (the job of `csw invert`,
// on a worker thread, with progress and Cancel) and shows, per model, the mean
// and standard deviation of the reconstruction error of the visible shape
// markers for each utterance (take) as bars — the seed's Figure 3 — and a
// per-marker error table. Clicking an utterance's bar asks the window to show
// that take at its worst frame (the frame with the largest visible error of
// the job's per-frame reports, as in `csw invert --frames-csv`). It also
// computes, off the GUI thread, the models' reconstruction of the shown take
// (jobs::ModelReconstruction) for the 3D view.
#include <QString>
#include <QStringList>
#include <QWidget>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/take.h"
#include "workbench/jobs/invert_job.h"

class QCustomPlot;
class QComboBox;
class QLabel;
class QProgressBar;
class QPushButton;
class QTableWidget;

namespace csw::gui {

class JobRunner;
class LogPanel;

// One utterance (take) under one model.
struct UtteranceError {
  std::string take;         // the take's name
  std::string spec;         // its selection spec (the take's name for whole takes)
  std::string role;         // "training" or "held_out" (jobs::Invert)
  int64_t first_frame = 0;  // first frame of the range inverted
  int64_t frames = 0;
  int64_t samples = 0;  // visible shape-marker samples scored
  double mean_mm = 0, sd_mm = 0, max_mm = 0;
  // The frame (0-based, of the take) with the largest max visible error, -1
  // when no frame has one; that error and its marker.
  int64_t worst_frame = -1;
  double worst_time_s = 0;  // its time in the take (the window shows frames as numbered in the source file)
  double worst_frame_error_mm = 0;
  std::string worst_marker;
};

// One marker of one model, pooled over the utterances.
struct MarkerError {
  std::string marker;
  std::string role;  // "cluster" or "shape"
  int64_t count = 0;
  double mean_mm = 0, sd_mm = 0, p99_mm = 0, max_mm = 0;
};

struct ModelErrors {
  std::string kind;  // "face" or "hand"
  double target_mm = 0;
  std::vector<UtteranceError> utterances;  // in selection order
  std::vector<MarkerError> markers;        // in model order
};

// The inspector's data from jobs::Invert's summary and its per-frame reports
// (invert_job.h). Pure; no Qt.
std::vector<ModelErrors> SummariseInversion(const nlohmann::json& summary,
                                            const std::vector<jobs::FrameReport>& frames);

class ErrorInspector : public QWidget {
  Q_OBJECT

 public:
  explicit ErrorInspector(LogPanel* log = nullptr, QWidget* parent = nullptr);
  ~ErrorInspector() override;

  // Inverts every model of `models` on `takes` of `corpus` (take selections,
  // take_selection.h) in the background; false (and a log line) when one
  // runs. Every take given must hold the models' markers (else the run fails,
  // naming the take); with none given, every take but generated fill versions
  // that holds them (the others are named in the log and in skipped()).
  bool Start(const QString& corpus, const QString& models, const QStringList& takes = {});
  void Cancel();
  bool running() const;
  JobRunner* runner() const { return runner_; }
  QString models_file() const { return models_; }

  const std::vector<ModelErrors>& results() const { return results_; }
  // Takes of the last run left out for lacking the models' markers.
  const QStringList& skipped() const { return skipped_; }
  // The model shown ("face" / "hand"); false when the results have none.
  bool ShowModel(const QString& kind);
  const ModelErrors* shown() const;

  // The bars of the shown model: index = position in shown()->utterances.
  int BarCount() const;
  // Centre of bar `index` in the plot's widget coordinates (click there).
  std::optional<QPointF> BarCenter(int index) const;
  // The bar under a plot position, or -1.
  int BarAt(QPointF plot_pos) const;
  // As a click on bar `index`: emits UtteranceChosen(take, worst frame).
  void ChooseUtterance(int index);
  int chosen() const { return chosen_; }

  // Computes the models' reconstruction of `take` in the background (the
  // latest request wins); ReconstructionReady when done.
  void ReconstructTake(std::shared_ptr<const Take> take);
  std::shared_ptr<const MarkerArray> reconstruction() const { return reconstruction_; }
  QString reconstruction_take() const { return reconstruction_take_; }
  JobRunner* reconstruction_runner() const { return recon_runner_; }

  QCustomPlot* plot() const { return plot_; }
  QTableWidget* marker_table() const { return table_; }
  QComboBox* model_combo() const { return model_combo_; }

 signals:
  // After every run: "succeeded", "canceled" or "failed".
  void Finished(const QString& outcome);
  void UtteranceChosen(const QString& take, qint64 frame);
  void ReconstructionReady(const QString& take);

 private:
  void Refresh();
  void StartReconstruction();

  LogPanel* log_ = nullptr;
  JobRunner* runner_ = nullptr;
  JobRunner* recon_runner_ = nullptr;
  QString corpus_, models_;
  QLabel* source_ = nullptr;
  QComboBox* model_combo_ = nullptr;
  QPushButton* cancel_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QCustomPlot* plot_ = nullptr;
  QTableWidget* table_ = nullptr;
  QLabel* info_ = nullptr;
  std::vector<ModelErrors> pending_;  // written by the worker, read after it finished
  std::vector<ModelErrors> results_;
  QStringList pending_skipped_;  // written by the worker, read after it finished
  QStringList skipped_;
  int shown_ = -1;
  int chosen_ = -1;
  // Reconstruction of the shown take.
  std::shared_ptr<const Take> recon_request_;  // the latest asked for
  std::shared_ptr<const Take> recon_running_;  // the one the worker computes
  std::shared_ptr<MarkerArray> recon_pending_;
  std::shared_ptr<const MarkerArray> reconstruction_;
  QString reconstruction_take_;
};

}  // namespace csw::gui

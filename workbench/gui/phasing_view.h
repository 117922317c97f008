#pragma once
// Phasing histograms and recogniser confusion matrices (issue 16, item 4).
// The data are the JSON results of `csw phasing --json` (per key type CV / V /
// C: shape and placement onset and target times relative to A1, the acoustic
// landmark) with, when known, its per-key CSV (`--csv`: the histograms'
// values), and of `csw keys score --json` (confusion of shape and placement at
// the labelled frames). The view opens such a JSON file, or runs both jobs on
// the open corpus with a chosen key-recogniser file (keys score as a dry run:
// nothing is written into the corpus); either way on a worker thread
// (JobRunner). Both figures export as PNG, SVG or PDF.
#include <QString>
#include <QStringList>
#include <QWidget>
#include <array>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

class QComboBox;
class QCustomPlot;
class QLabel;
class QPushButton;
class QTabWidget;

namespace csw::gui {

class JobRunner;
class LogPanel;

// One key's landmark times relative to A1 (ms; NaN = not measured):
// rel_ms[method][component], method 0 kinematic / 1 posterior, component 0
// placement onset, 1 placement target, 2 shape onset, 3 shape target.
struct PhasingKeyTimes {
  std::string type;  // "CV", "V", "C"
  std::array<std::array<double, 4>, 2> rel_ms{};
};

struct AnalysisData {
  nlohmann::json phasing;             // csw phasing's result, null when none
  std::vector<PhasingKeyTimes> keys;  // its per-key times, empty when unknown
  nlohmann::json keys_score;          // csw keys score's result, null when none
  QStringList notes;                  // why a part is missing
  bool empty() const { return phasing.is_null() && keys_score.is_null(); }
};

// The per-key relative times of a `csw phasing --csv` file. Throws csw::Error.
std::vector<PhasingKeyTimes> ReadPhasingCsv(const std::string& path);
// A JSON file of `csw phasing --json` (with its "csv" read when that file
// exists), of `csw keys score --json`, or `csw demo`'s report.json (its keys and
// phasing stages). Throws csw::Error when it is none of them.
AnalysisData LoadAnalysisJson(const std::string& path);
// Runs jobs::KeysScore (dry run) and jobs::Phasing (per-key CSV in a temporary
// file) on `corpus` with the key model of `keys_file`; a part that fails is
// left null with its reason in notes; throws when both fail (or on Cancelled).
AnalysisData RunAnalysis(const std::string& corpus, const std::string& keys_file, Progress& progress);

class PhasingView : public QWidget {
  Q_OBJECT

 public:
  static constexpr double kBinMs = 20.0;
  static const char* const kTypes[3];       // "CV", "V", "C"
  static const char* const kComponents[4];  // "placement onset", ...

  explicit PhasingView(LogPanel* log, QWidget* parent = nullptr);

  // Reads a JSON file in the background; false when a job runs.
  bool OpenJson(const QString& path);
  // Runs the jobs on a corpus in the background; false when a job runs.
  bool Run(const QString& corpus, const QString& keys_file);
  void Cancel();
  bool running() const;
  // Shows data at once (GUI thread).
  void SetData(AnalysisData data);
  const AnalysisData& data() const { return data_; }
  // 0 kinematic, 1 posterior.
  void SetMethod(int method);
  int method() const { return method_; }

  // Figures: PNG, SVG or PDF; throws csw::Error.
  void ExportPhasing(const QString& path, int width = 0, int height = 0);
  void ExportConfusion(const QString& path, int width = 0, int height = 0);

  // Introspection (tests, tour).
  QCustomPlot* phasing_plot() const { return phasing_plot_; }
  QCustomPlot* confusion_plot() const { return confusion_plot_; }
  QTabWidget* tabs() const { return tabs_; }
  QLabel* status_label() const { return status_; }
  JobRunner* runner() const { return runner_; }
  // Values counted in the histogram of key type t, component c (sum of its bars).
  int HistogramTotal(int type, int component) const;
  // A confusion cell as drawn: which 0 shape / 1 placement; -1 when none.
  int ConfusionCell(int which, int truth, int decided) const;

 signals:
  // "succeeded", "canceled" or "failed".
  void Finished(const QString& outcome);

 private:
  void ChooseJson();
  void ChooseRun();
  void ChooseExport(bool confusion);
  void Start(std::function<AnalysisData(Progress&)> work, const QString& what);
  void DrawPhasing();
  void DrawConfusion();

  LogPanel* log_;
  JobRunner* runner_;
  AnalysisData data_;
  std::shared_ptr<AnalysisData> pending_;
  int method_ = 0;
  QComboBox* method_combo_ = nullptr;
  QTabWidget* tabs_ = nullptr;
  QCustomPlot* phasing_plot_ = nullptr;
  QCustomPlot* confusion_plot_ = nullptr;
  QLabel* status_ = nullptr;
  QPushButton* cancel_ = nullptr;
  std::array<std::array<int, 4>, 3> totals_{};
  std::array<std::vector<std::vector<int>>, 2> cells_;

 public:
  // The corpus Run uses from the Run button ("" = ask for none: the window sets it).
  void SetCorpus(const QString& corpus) { corpus_ = corpus; }

 private:
  QString corpus_;
};

}  // namespace csw::gui

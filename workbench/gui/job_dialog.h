#pragma once
// The Analysis menu's jobs: `csw cue`, `csw keys suggest`, `csw keys train`,
// `csw keys score`, `csw phasing`, `csw clean` and `csw dict build` run from the
// window on the open corpus, as the same job functions the CLI calls
// (workbench/jobs), on a worker thread (JobRunner) with progress and a Cancel
// that stops them (the corpus and the output files are written in one
// transaction or renamed into place at the end, so a cancel leaves them as
// they were). A JobSpec describes one job: its fields (text, or a file to open
// or to save; defaults are the CLI's) and how the field values become the
// job's options. The dialog is not modal; its result text is the CLI's text
// output, also written to the log.
#include <QDialog>
#include <QString>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

class QLabel;
class QLineEdit;
class QPlainTextEdit;
class QProgressBar;
class QPushButton;

namespace csw::gui {

class JobRunner;
class LogPanel;

struct JobField {
  enum class Kind { kText, kOpenFile, kSaveFile };
  QString key;    // e.g. "takes"
  QString label;  // shown
  Kind kind = Kind::kText;
  QString value;  // default
  QString help;   // tool tip
  bool required = false;
};

// Field values by key.
using JobValues = std::map<QString, QString>;

struct JobSpec {
  QString id;     // "cue", "keys-suggest", ...
  QString title;  // menu entry and window title
  QString help;   // one paragraph on what it does and writes
  std::vector<JobField> fields;
  bool writes_corpus = false;  // the window reopens the corpus after a success
  // Runs the job (on the worker thread): the corpus path and the field values.
  using RunFn = std::function<nlohmann::json(const std::string& corpus, const JobValues& values, Progress& progress)>;
  RunFn run;
  // The job's text output (the CLI's), from its result.
  std::function<std::string(const nlohmann::json& result)> text;
  // Checks the options (GUI thread, no file access): "" when valid, else why.
  std::function<std::string(const std::string& corpus, const JobValues& values)> check;
};

// The Analysis menu's jobs, in menu order.
const std::vector<JobSpec>& AnalysisJobs();
// The job of that id, or null.
const JobSpec* FindAnalysisJob(const QString& id);
// A take selection typed as names or patterns separated by commas or spaces.
std::vector<std::string> SplitTakes(const QString& text);

class JobDialog : public QDialog {
  Q_OBJECT

 public:
  // `log` (optional) hears of starts, results, cancels and failures.
  JobDialog(const JobSpec& spec, LogPanel* log = nullptr, QWidget* parent = nullptr);
  ~JobDialog() override;

  const JobSpec& spec() const { return spec_; }
  void SetCorpus(const QString& corpus);
  QString corpus() const { return corpus_; }
  void SetValue(const QString& key, const QString& value);
  QString Value(const QString& key) const;
  JobValues Values() const;

  // Starts the job in the background; false (the reason in the status line)
  // when no corpus is set, a required field is empty, the options are invalid
  // or the job is running.
  bool Start();
  void Cancel();
  bool running() const;
  // The last successful run's result (the job's JSON), null before.
  const nlohmann::json& result() const { return result_; }

  JobRunner* runner() const { return runner_; }
  QPushButton* run_button() const { return run_button_; }
  QPushButton* cancel_button() const { return cancel_button_; }
  QProgressBar* progress_bar() const { return progress_; }
  QLabel* status_label() const { return status_; }
  QPlainTextEdit* output() const { return output_; }
  QLineEdit* field(const QString& key) const;

 signals:
  // After every run: "succeeded", "canceled" or "failed".
  void JobFinished(const QString& outcome);
  // A run that writes into the corpus succeeded: the window reopens it.
  void CorpusWritten(const QString& corpus);

 private:
  void SetRunning(bool on);
  void Log(int level, const QString& message);

  JobSpec spec_;
  LogPanel* log_ = nullptr;
  JobRunner* runner_ = nullptr;
  QString corpus_;
  QLabel* corpus_label_ = nullptr;
  std::map<QString, QLineEdit*> fields_;
  QProgressBar* progress_ = nullptr;
  QLabel* status_ = nullptr;
  QPlainTextEdit* output_ = nullptr;
  QPushButton* run_button_ = nullptr;
  QPushButton* cancel_button_ = nullptr;
  QPushButton* close_button_ = nullptr;
  QString running_corpus_;
  nlohmann::json pending_;  // written by the worker, read after it finished
  nlohmann::json result_;
};

}  // namespace csw::gui

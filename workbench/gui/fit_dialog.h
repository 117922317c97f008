#pragma once
// The model-fit dialog: runs jobs::Fit (the same job as `csw fit`) on a worker
// thread with progress and a Cancel that stops the fit (the model file is
// written only at the end, to a temporary file renamed over it, so a cancel or
// a failure leaves the old file as it was). The user chooses the model kind,
// the takes, the configuration (edited in place, or loaded from a file) and
// the model file. The dialog is not modal: the window stays usable meanwhile.
#include <QDialog>
#include <QString>
#include <QStringList>
#include <QTemporaryDir>
#include <memory>
#include <nlohmann/json.hpp>

#include "workbench/jobs/fit_job.h"

class QComboBox;
class QLabel;
class QLineEdit;
class QListWidget;
class QPlainTextEdit;
class QProgressBar;
class QPushButton;

namespace csw::gui {

class JobRunner;
class LogPanel;

class FitDialog : public QDialog {
  Q_OBJECT

 public:
  // `log` (optional) hears of starts, results, cancels and failures.
  explicit FitDialog(LogPanel* log = nullptr, QWidget* parent = nullptr);
  ~FitDialog() override;

  // The corpus and its takes (in corpus order); every take is checked but
  // generated fill versions (take_selection.h), as `csw fit` selects by default.
  void SetCorpus(const QString& corpus, const QStringList& takes);
  void SetKind(const QString& kind);  // "face", "hand" or "rigid"
  void SetOutput(const QString& model_file);
  void SetMarkerSetFile(const QString& path);  // "" = the one the corpus remembers
  // Checks exactly these takes (names of SetCorpus's list).
  void SetCheckedTakes(const QStringList& takes);
  QStringList CheckedTakes() const;
  // The configuration (docs/model-format.md, "Configuration") as JSON text.
  void SetConfigText(const QString& json);
  QString ConfigText() const;
  // Loads a configuration file into the editor; the fit then uses the file
  // itself (its relative "markerset" resolves against its folder) unless the
  // text is edited. False (and the reason in the status line) when unreadable.
  bool LoadConfigFile(const QString& path);

  // The job's options for the current choices; "" in *why when valid, else the
  // reason. An edited configuration is checked (jobs::ParseModelConfig) and
  // written to a temporary file the fit reads.
  jobs::FitOptions Options(QString* why);
  // Starts the fit in the background; false (reason in the status line) when
  // the choices are invalid or a fit is running.
  bool StartFit();
  void CancelFit();
  bool running() const;
  // The last successful fit's summary (fit_job.h), null before.
  const nlohmann::json& result() const { return result_; }

  JobRunner* runner() const { return runner_; }
  QPushButton* fit_button() const { return fit_button_; }
  QPushButton* cancel_button() const { return cancel_button_; }
  QProgressBar* progress_bar() const { return progress_; }
  QLabel* status_label() const { return status_; }
  QListWidget* take_list() const { return takes_; }
  QComboBox* kind_combo() const { return kind_; }

 signals:
  // After every run: "succeeded", "canceled" or "failed".
  void FitFinished(const QString& outcome);
  void ModelSaved(const QString& model_file);

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  void SetRunning(bool on);
  void Log(int level, const QString& message);

  LogPanel* log_ = nullptr;
  JobRunner* runner_ = nullptr;
  QString corpus_;
  QLabel* corpus_label_ = nullptr;
  QComboBox* kind_ = nullptr;
  QListWidget* takes_ = nullptr;
  QPlainTextEdit* config_ = nullptr;
  QLabel* config_source_ = nullptr;
  QLineEdit* markerset_ = nullptr;
  QLineEdit* output_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QLabel* status_ = nullptr;
  QPushButton* fit_button_ = nullptr;
  QPushButton* cancel_button_ = nullptr;
  QPushButton* close_button_ = nullptr;
  QString config_file_;  // the loaded file, "" = none
  QString config_file_text_;
  std::unique_ptr<QTemporaryDir> temp_;
  jobs::FitOptions running_options_;
  nlohmann::json pending_;  // written by the worker, read after it finished
  nlohmann::json result_;
};

}  // namespace csw::gui

#pragma once
// Runs jobs::Import (the same job as `csw import`) on a worker thread. Progress
// arrives as queued signals; Cancel() asks the job to stop, and the job's
// transaction rolls the corpus back. No event-loop spinning anywhere.
#include <QObject>
#include <QStringList>
#include <functional>
#include <memory>

#include "core/progress.h"
#include "workbench/jobs/jobs.h"

class QThread;

namespace csw::gui {

class ImportRunner : public QObject {
  Q_OBJECT

 public:
  explicit ImportRunner(QObject* parent = nullptr);
  // Cancels a running import and waits for its thread.
  ~ImportRunner() override;

  // Starts the import; false when one is already running.
  bool Start(const jobs::ImportOptions& options);
  void Cancel();
  bool running() const { return thread_ != nullptr; }
  const jobs::ImportOptions& options() const { return options_; }

  // Called on the worker thread at every progress update, before the GUI hears
  // of it (tests use it to cancel at a known point; must be set before Start).
  void SetWorkerHook(std::function<void(const std::string& stage, double fraction)> hook) { hook_ = std::move(hook); }

 signals:
  void ProgressChanged(const QString& stage, double fraction);
  void Succeeded(const QStringList& takes, const QStringList& warnings);
  void Canceled();
  void Failed(const QString& message);

 private:
  void OnThreadFinished();

  jobs::ImportOptions options_;
  std::unique_ptr<Progress> progress_;
  std::function<void(const std::string&, double)> hook_;
  QThread* thread_ = nullptr;
  // Written by the worker, read after it finished.
  enum class Outcome { kSucceeded, kCanceled, kFailed } outcome_ = Outcome::kFailed;
  jobs::ImportResult result_;
  QString error_;
};

}  // namespace csw::gui

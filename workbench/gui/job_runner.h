#pragma once
// Runs one csw job (any function of a csw::Progress&, e.g. jobs::Fit or
// jobs::Invert) on a worker thread, as ImportRunner does for the import:
// progress arrives as queued signals (at most ~30 a second, and each new stage), Cancel() asks the
// job to stop (the job's next Progress::Update throws csw::Cancelled), and the
// outcome is a queued signal. The GUI thread never waits on the job (only the
// destructor does, after cancelling it).
#include <QObject>
#include <QString>
#include <functional>
#include <memory>
#include <string>

#include "core/progress.h"

class QThread;

namespace csw::gui {

class JobRunner : public QObject {
  Q_OBJECT

 public:
  // `name` names the worker thread ("csw-fit").
  explicit JobRunner(const QString& name, QObject* parent = nullptr);
  // Cancels a running job and waits for its thread.
  ~JobRunner() override;

  using Work = std::function<void(Progress& progress)>;
  // Starts `work` on the worker thread; false when a job is already running.
  // `work` reports through the Progress it gets; whatever it returns it keeps
  // in its own captures, which the GUI reads after Succeeded.
  bool Start(Work work);
  void Cancel();
  bool running() const { return thread_ != nullptr; }

  // Called on the worker thread at every progress update, after it was queued
  // for the GUI (when not dropped by the rate limit); tests and the tour use it
  // to hold the job at a known point. Set it only while no job runs.
  void SetWorkerHook(std::function<void(const std::string& stage, double fraction)> hook) { hook_ = std::move(hook); }

 signals:
  void ProgressChanged(const QString& stage, double fraction);
  void Succeeded();
  void Canceled();
  void Failed(const QString& message);

 private:
  void OnThreadFinished();

  QString name_;
  Work work_;
  std::unique_ptr<Progress> progress_;
  std::function<void(const std::string&, double)> hook_;
  QThread* thread_ = nullptr;
  // Written by the worker, read after it finished.
  enum class Outcome { kSucceeded, kCanceled, kFailed } outcome_ = Outcome::kFailed;
  QString error_;
};

}  // namespace csw::gui

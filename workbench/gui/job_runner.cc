#include "workbench/gui/job_runner.h"

#include <QThread>
#include <chrono>

#include "core/error.h"

namespace csw::gui {

JobRunner::JobRunner(const QString& name, QObject* parent) : QObject(parent), name_(name) {}

JobRunner::~JobRunner() {
  if (thread_ != nullptr) {
    progress_->Cancel();
    thread_->wait();
    delete thread_;
  }
}

bool JobRunner::Start(Work work) {
  if (thread_ != nullptr) return false;
  work_ = std::move(work);
  outcome_ = Outcome::kFailed;
  error_.clear();
  // The sink runs on the worker thread: it forwards at most ~30 updates a second.
  auto last = std::make_shared<std::chrono::steady_clock::time_point>();
  // A new stage is always forwarded.
  auto last_stage = std::make_shared<std::string>();
  progress_ = std::make_unique<Progress>([this, last, last_stage](const std::string& stage, double fraction) {
    auto now = std::chrono::steady_clock::now();
    if (now - *last >= std::chrono::milliseconds(33) || fraction >= 1.0 || stage != *last_stage) {
      *last = now;
      *last_stage = stage;
      QString s = QString::fromStdString(stage);
      QMetaObject::invokeMethod(
          this, [this, s, fraction] { emit ProgressChanged(s, fraction); }, Qt::QueuedConnection);
    }
    if (hook_) hook_(stage, fraction);
  });
  thread_ = QThread::create([this] {
    try {
      work_(*progress_);
      // A cancel that came after the job's last check did not stop it: the
      // job finished and its result stands.
      outcome_ = Outcome::kSucceeded;
    } catch (const Cancelled&) {
      outcome_ = Outcome::kCanceled;
    } catch (const std::exception& e) {
      outcome_ = Outcome::kFailed;
      error_ = QString::fromStdString(e.what());
    }
  });
  thread_->setObjectName(name_);
  connect(thread_, &QThread::finished, this, &JobRunner::OnThreadFinished, Qt::QueuedConnection);
  thread_->start();
  return true;
}

void JobRunner::Cancel() {
  if (progress_ && thread_ != nullptr) progress_->Cancel();
}

void JobRunner::OnThreadFinished() {
  if (thread_ == nullptr) return;
  thread_->wait();  // returns at once: the thread has finished
  delete thread_;
  thread_ = nullptr;
  work_ = nullptr;
  switch (outcome_) {
    case Outcome::kSucceeded:
      emit Succeeded();
      break;
    case Outcome::kCanceled:
      emit Canceled();
      break;
    case Outcome::kFailed:
      emit Failed(error_);
      break;
  }
}

}  // namespace csw::gui

#include "workbench/gui/import_runner.h"

#include <QThread>
#include <chrono>

#include "core/error.h"

namespace csw::gui {

ImportRunner::ImportRunner(QObject* parent) : QObject(parent) {}

ImportRunner::~ImportRunner() {
  if (thread_ != nullptr) {
    progress_->Cancel();
    thread_->wait();
    delete thread_;
  }
}

bool ImportRunner::Start(const jobs::ImportOptions& options) {
  if (thread_ != nullptr) return false;
  options_ = options;
  outcome_ = Outcome::kFailed;
  result_ = {};
  error_.clear();
  // The sink runs on the worker thread: it forwards at most ~30 updates a second.
  auto last = std::make_shared<std::chrono::steady_clock::time_point>();
  progress_ = std::make_unique<Progress>([this, last](const std::string& stage, double fraction) {
    if (hook_) hook_(stage, fraction);
    auto now = std::chrono::steady_clock::now();
    if (now - *last < std::chrono::milliseconds(33) && fraction < 1.0) return;
    *last = now;
    QString s = QString::fromStdString(stage);
    QMetaObject::invokeMethod(
        this, [this, s, fraction] { emit ProgressChanged(s, fraction); }, Qt::QueuedConnection);
  });
  thread_ = QThread::create([this] {
    try {
      result_ = jobs::Import(options_, *progress_);
      outcome_ = Outcome::kSucceeded;
    } catch (const Cancelled&) {
      outcome_ = Outcome::kCanceled;
    } catch (const std::exception& e) {
      outcome_ = Outcome::kFailed;
      error_ = QString::fromStdString(e.what());
    }
  });
  thread_->setObjectName("csw-import");
  connect(thread_, &QThread::finished, this, &ImportRunner::OnThreadFinished, Qt::QueuedConnection);
  thread_->start();
  return true;
}

void ImportRunner::Cancel() {
  if (progress_ && thread_ != nullptr) progress_->Cancel();
}

void ImportRunner::OnThreadFinished() {
  if (thread_ == nullptr) return;
  thread_->wait();
  delete thread_;
  thread_ = nullptr;
  switch (outcome_) {
    case Outcome::kSucceeded: {
      QStringList takes, warnings;
      for (const auto& t : result_.takes) takes << QString::fromStdString(t);
      for (const auto& w : result_.warnings) warnings << QString::fromStdString(w);
      emit Succeeded(takes, warnings);
      break;
    }
    case Outcome::kCanceled:
      emit Canceled();
      break;
    case Outcome::kFailed:
      emit Failed(error_);
      break;
  }
}

}  // namespace csw::gui

#pragma once
// Progress and cancellation for long jobs. A job receives a Progress& and calls
// Update() from time to time; Update throws csw::Cancelled when the user asked
// to stop, so the job unwinds and its transaction rolls back.
#include <atomic>
#include <functional>
#include <string>

namespace csw {

class Progress {
 public:
  using Sink = std::function<void(const std::string& stage, double fraction)>;

  Progress() = default;
  explicit Progress(Sink sink) : sink_(std::move(sink)) {}

  // fraction in [0, 1] of the current stage. Throws Cancelled if cancelled.
  void Update(const std::string& stage, double fraction);
  // Throws Cancelled if cancelled, without reporting.
  void CheckCancel() const;

  void Cancel() { cancelled_.store(true); }
  bool cancelled() const { return cancelled_.load(); }

 private:
  Sink sink_;
  std::atomic<bool> cancelled_{false};
};

}  // namespace csw

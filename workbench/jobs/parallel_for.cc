#include "workbench/jobs/parallel_for.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "core/error.h"

namespace csw::jobs {

void ParallelFor(size_t n, int threads, const std::string& stage, Progress& progress,
                 const std::function<void(size_t i, Progress& item_progress)>& body) {
  if (n == 0) return;
  const int hardware = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int count = std::max(1, std::min<int>(threads > 0 ? threads : hardware, static_cast<int>(n)));
  std::unique_ptr<std::atomic<double>[]> fraction(new std::atomic<double>[n]);
  for (size_t i = 0; i < n; ++i) fraction[i].store(0.0);
  std::atomic<size_t> next{0};
  std::atomic<bool> stop{false};
  std::atomic<int> running{count};
  std::mutex error_mutex;
  std::exception_ptr first_error;
  auto worker = [&]() {
    for (size_t i = next++; i < n && !stop.load(); i = next++) {
      try {
        Progress item([&, i](const std::string&, double f) {
          fraction[i].store(std::clamp(f, 0.0, 1.0));
          if (stop.load() || progress.cancelled()) throw Cancelled();
        });
        body(i, item);
        fraction[i].store(1.0);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        stop.store(true);  // stop handing out work
      }
    }
    --running;
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < count; ++t) pool.emplace_back(worker);
  while (running.load() > 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    double done = 0;
    for (size_t i = 0; i < n; ++i) done += fraction[i].load();
    try {
      progress.Update(stage, done / static_cast<double>(n));
    } catch (const Cancelled&) {
      stop.store(true);  // workers see it at their next Update
    }
  }
  for (auto& t : pool) t.join();
  if (progress.cancelled()) throw Cancelled();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace csw::jobs

// ParallelFor (workbench/jobs/parallel_for.h): every item once, errors and
// cancellation propagated, progress reaching 1.
#include "workbench/jobs/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/error.h"

namespace csw::jobs {
namespace {

TEST(ParallelFor, EveryItemExactlyOnce) {
  for (int threads : {0, 1, 3, 64}) {
    std::vector<std::atomic<int>> hits(257);
    double last = -1;
    Progress progress([&](const std::string& stage, double f) {
      EXPECT_EQ(stage, "work");
      last = f;
    });
    ParallelFor(hits.size(), threads, "work", progress, [&](size_t i, Progress& item) {
      item.Update("x", 0.5);
      hits[i] += static_cast<int>(i) + 1;
    });
    for (size_t i = 0; i < hits.size(); ++i) EXPECT_EQ(hits[i].load(), static_cast<int>(i) + 1) << threads;
    EXPECT_TRUE(last == -1 || (last >= 0 && last <= 1.0)) << last;
  }
  Progress quiet;
  ParallelFor(0, 4, "none", quiet, [](size_t, Progress&) { FAIL() << "no item to run"; });
}

TEST(ParallelFor, FirstErrorIsRethrownAndStopsNewItems) {
  Progress progress;
  std::atomic<int> started{0};
  try {
    ParallelFor(1000, 2, "work", progress, [&](size_t i, Progress&) {
      ++started;
      if (i == 3) throw InvalidInput("item 3 failed");
      // Items take time, so the other worker cannot run all of them before
      // the error stops the hand-out (1000 items would take 0.5 s).
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    });
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "item 3 failed");
  }
  EXPECT_LT(started.load(), 500);
}

TEST(ParallelFor, CancelStopsTheItems) {
  Progress progress;
  std::atomic<int> finished{0};
  EXPECT_THROW(ParallelFor(8, 2, "work", progress,
                           [&](size_t i, Progress& item) {
                             if (i == 0) progress.Cancel();
                             // Runs until Update throws Cancelled: no item can finish.
                             for (int k = 0;; ++k) {
                               item.Update("x", 0.5);
                               if (k > 100000000) break;
                             }
                             ++finished;
                           }),
               Cancelled);
  EXPECT_EQ(finished.load(), 0);
}

}  // namespace
}  // namespace csw::jobs

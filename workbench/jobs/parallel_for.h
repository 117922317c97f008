#pragma once
// A small parallel for-loop for jobs: items handed out one at a time to a few
// threads, progress reported from the calling thread, cancellation and the
// first error propagated.
#include <cstddef>
#include <functional>
#include <string>

#include "core/progress.h"

namespace csw::jobs {

// Runs body(i, item_progress) for every i in [0, n) on min(threads, n)
// threads (threads 0 = the hardware's). item_progress.Update(stage, f) records
// item i's fraction done and throws Cancelled once the job is cancelled or
// another item failed. Meanwhile the calling thread reports `stage` with the
// mean fraction of the items to `progress` every 50 ms. After every thread has
// stopped: throws Cancelled if `progress` was cancelled, else rethrows the
// first error of an item (later items are then not started).
void ParallelFor(size_t n, int threads, const std::string& stage, Progress& progress,
                 const std::function<void(size_t i, Progress& item_progress)>& body);

}  // namespace csw::jobs

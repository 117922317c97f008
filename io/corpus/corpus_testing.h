#pragma once
// Test hooks of the corpus store, for the crash tests only.
#include <functional>

namespace csw::corpus_testing {

// Called by CorpusTransaction::Commit() at each stage ("take files synced",
// "index written", "index replaced"); a test kills its own process there to
// crash a writer at an exact point. Pass nullptr to remove.
void SetCommitHook(std::function<void(const char* stage)> hook);

}  // namespace csw::corpus_testing

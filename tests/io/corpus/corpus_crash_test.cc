// Crash safety with a real kill: a child process writes to the corpus and the
// parent SIGKILLs it mid-write; the corpus must still open with exactly the
// takes it had before.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "tests/io/corpus/corpus_test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
using testing::ExpectSameTake;
using testing::MakeFullTake;
using testing::TempDir;

// Kills and reaps the child; returns true when it died of SIGKILL.
bool KillChild(pid_t pid) {
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

// Pseudo-random floats that deflate cannot shrink, so the temporary file grows fast.
void FillNoise(std::vector<float>* v, uint32_t* state) {
  for (float& x : *v) {
    *state = *state * 1664525u + 1013904223u;
    x = static_cast<float>(*state >> 8) * 1e-3f;
  }
}

TEST(CorpusCrash, SigkillWhileStreamingLeavesThePreviousCorpus) {
  TempDir dir;
  const std::string path = (dir / "corpus.h5").string();
  const std::string temp = CorpusTransaction::TempPath(path);
  Take a = MakeFullTake("a", 500, 6);
  Take b = MakeFullTake("b", 300, 4);
  {
    CorpusTransaction tx(path);
    tx.WriteTake(a);
    tx.WriteTake(b);
    tx.Commit();
  }
  const auto size_before = fs::file_size(path);

  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // Child: change the corpus and stream an endless take until killed.
    try {
      CorpusTransaction tx(path);
      tx.RemoveTake("a");
      tx.WriteTiers("b", {});
      Take header = MakeFullTake("big", 0, 113);
      CorpusTransaction::TakeWriter w = tx.BeginTake(header);
      std::vector<float> block(300 * 113 * 3);
      uint32_t state = 1;
      for (;;) {
        FillNoise(&block, &state);
        w.AppendFrames(block.data(), 300);
      }
    } catch (...) {
    }
    _exit(3);
  }
  // Parent: wait until the temporary file has grown past 16 MB, then kill.
  bool grew = false;
  for (int i = 0; i < 3000 && !grew; ++i) {
    std::error_code ec;
    auto size = fs::file_size(temp, ec);
    grew = !ec && size > 16u * 1024 * 1024;
    if (!grew) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(KillChild(pid)) << "the child did not die of SIGKILL";
  ASSERT_TRUE(grew) << "the temporary file never grew";

  EXPECT_EQ(fs::file_size(path), size_before);
  Corpus corpus = Corpus::Open(path);
  std::vector<TakeSummary> takes = corpus.Takes();
  ASSERT_EQ(takes.size(), 2u);
  EXPECT_EQ(takes[0].name, "a");
  EXPECT_EQ(takes[1].name, "b");
  ExpectSameTake(a, corpus.LoadTake("a"));
  ExpectSameTake(b, corpus.LoadTake("b"));

  // The killed writer's temporary file is cleaned up by the next transaction.
  EXPECT_TRUE(fs::exists(temp));
  {
    CorpusTransaction tx(path);
    tx.WriteTake(MakeFullTake("c", 10, 2));
    tx.Commit();
  }
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_EQ(Corpus::Open(path).Takes().size(), 3u);
}

TEST(CorpusCrash, SigkillDuringRepeatedCommitsLeavesAConsistentCorpus) {
  TempDir dir;
  const std::string path = (dir / "corpus.h5").string();
  {
    CorpusTransaction tx(path);
    tx.WriteTake(MakeFullTake("t000", 50, 3));
    tx.Commit();
  }
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // Child: one take per transaction, committing as fast as it can.
    try {
      for (int i = 1; i < 100000; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "t%03d", i % 1000);
        CorpusTransaction tx(path);
        tx.WriteTake(MakeFullTake(name, 50, 3), IfTakeExists::kReplace);
        tx.Commit();
      }
    } catch (...) {
    }
    _exit(3);
  }
  // Kill it once it has committed several times (the corpus inode changes per commit).
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  int commits_seen = 0;
  fs::file_time_type last{};
  for (int i = 0; i < 2000 && commits_seen < 5; ++i) {
    std::error_code ec;
    auto t = fs::last_write_time(path, ec);
    if (!ec && t != last) {
      last = t;
      ++commits_seen;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(KillChild(pid));
  ASSERT_GE(commits_seen, 3) << "the child did not commit";
  // Whatever instant the kill hit, the corpus is one of the committed states:
  // t000 .. tNNN without holes, every take complete.
  Corpus corpus = Corpus::Open(path);
  std::vector<TakeSummary> takes = corpus.Takes();
  ASSERT_GE(takes.size(), 3u);  // the first state seen plus at least two commits
  for (size_t i = 0; i < takes.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "t%03zu", i % 1000);
    EXPECT_EQ(takes[i].name, name);
    ExpectSameTake(MakeFullTake(name, 50, 3), corpus.LoadTake(name));
  }
}

}  // namespace
}  // namespace csw

// Crash safety with a real kill: a child process writes to the corpus and the
// parent SIGKILLs it mid-write (at random moments, and at each stage of a
// commit through a test hook); the corpus must still open with exactly the
// last committed state, and the next transaction removes the killed writer's
// files.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "io/corpus/corpus_testing.h"
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

std::vector<std::string> FolderFiles(const std::string& folder) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
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
  const std::string folder = CorpusTransaction::FolderPath(path);
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
  // Parent: wait until the new take's file has grown past 16 MB, then kill.
  const std::vector<std::string> files_before = FolderFiles(folder);
  ASSERT_EQ(files_before.size(), 6u);  // data, tiers and audio files of a and b
  bool grew = false;
  for (int i = 0; i < 3000 && !grew; ++i) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(folder, ec)) {
      auto size = fs::file_size(e.path(), ec);
      grew = grew || (!ec && size > 16u * 1024 * 1024);
    }
    if (!grew) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(KillChild(pid)) << "the child did not die of SIGKILL";
  ASSERT_TRUE(grew) << "the take file never grew";

  EXPECT_EQ(fs::file_size(path), size_before);
  Corpus corpus = Corpus::Open(path);
  std::vector<TakeSummary> takes = corpus.Takes();
  ASSERT_EQ(takes.size(), 2u);
  EXPECT_EQ(takes[0].name, "a");
  EXPECT_EQ(takes[1].name, "b");
  ExpectSameTake(a, corpus.LoadTake("a"));
  ExpectSameTake(b, corpus.LoadTake("b"));

  // The killed writer's files are cleaned up by the next transaction.
  EXPECT_GT(FolderFiles(folder).size(), files_before.size());
  {
    CorpusTransaction tx(path);
    tx.WriteTake(MakeFullTake("c", 10, 2));
    tx.Commit();
  }
  EXPECT_EQ(FolderFiles(folder).size(), 9u);  // 3 files each for a, b and c
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

// Kills the writer (SIGKILL of its own process) at each stage of a commit: up
// to the rename the corpus is exactly the previous state, from the rename on
// exactly the new one; either way it opens, and the next transaction leaves
// only the files its index references.
TEST(CorpusCrash, SigkillAtEachStageOfACommitLeavesExactlyOneCommittedState) {
  struct Stage {
    const char* name;
    bool committed;
  };
  for (const Stage& stage :
       {Stage{"take files synced", false}, Stage{"index written", false}, Stage{"index replaced", true}}) {
    SCOPED_TRACE(stage.name);
    TempDir dir;
    const std::string path = (dir / "corpus.h5").string();
    const std::string folder = CorpusTransaction::FolderPath(path);
    Take a = MakeFullTake("a", 400, 5);
    Take b = MakeFullTake("b", 300, 4);
    {
      CorpusTransaction tx(path);
      tx.WriteTake(a);
      tx.WriteTake(b);
      tx.Commit();
    }
    LabelTier edited = a.tiers[0];
    edited.labels[0].text = "edited";
    Take n = MakeFullTake("n", 900, 7);
    pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      const std::string wanted = stage.name;
      corpus_testing::SetCommitHook([wanted](const char* at) {
        if (wanted == at) raise(SIGKILL);
      });
      try {
        CorpusTransaction tx(path);
        tx.WriteTake(n);
        tx.WriteTiers("a", {edited});
        tx.RemoveTake("b");
        tx.Commit();
      } catch (...) {
      }
      _exit(3);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the hook did not kill the writer";
    {
      Corpus corpus = Corpus::Open(path);
      std::vector<TakeSummary> takes = corpus.Takes();
      if (stage.committed) {
        ASSERT_EQ(takes.size(), 2u);
        EXPECT_EQ(takes[0].name, "a");
        EXPECT_EQ(takes[1].name, "n");
        Take a2 = a;
        a2.tiers = {edited};
        ExpectSameTake(a2, corpus.LoadTake("a"));
        ExpectSameTake(n, corpus.LoadTake("n"));
      } else {
        ASSERT_EQ(takes.size(), 2u);
        EXPECT_EQ(takes[0].name, "a");
        EXPECT_EQ(takes[1].name, "b");
        ExpectSameTake(a, corpus.LoadTake("a"));
        ExpectSameTake(b, corpus.LoadTake("b"));
      }
    }
    // Leftovers (new files of the killed writer, or the old generation) go
    // with the next transaction, which has nothing else to do.
    EXPECT_GT(FolderFiles(folder).size(), 6u);
    {
      CorpusTransaction tx(path);
      tx.Commit();
    }
    EXPECT_EQ(FolderFiles(folder).size(), 6u);
    EXPECT_FALSE(fs::exists(CorpusTransaction::TempPath(path)));
    EXPECT_EQ(Corpus::Open(path).Takes().size(), 2u);
  }
}

}  // namespace
}  // namespace csw

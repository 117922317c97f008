// Crash safety of label autosave (issue 16, done-when): a labelling session in
// a real csw-workbench window (label_kill_child.cc, offscreen) is killed with
// SIGKILL while it edits a label every kPeriodMs (twice, at two phases of the
// edit and autosave cycles); afterwards the corpus must
// open, be writable again (the dead writer's lock is gone) and hold every edit
// older than the autosave delay plus a margin, with its code at its frame, and
// nothing the session never typed. Times are compared on one clock:
// std::chrono::steady_clock (CLOCK_MONOTONIC, system-wide on Linux) in both
// processes, the kill time taken just before kill().
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/build_paths.h"
#include "io/corpus/corpus.h"
#include "tests/testing/testing.h"

extern char** environ;

namespace csw {
namespace {

constexpr double kRate = 100.0;
constexpr int kFrames = 400;
constexpr int kAutosaveMs = 500;  // the child's autosave delay (the default is 2000 ms)
constexpr int kPeriodMs = 300;    // one edit every 300 ms
constexpr int kEditsBeforeKill = 12;
// Beyond the autosave delay: the snapshot's commit on the saver thread and the
// event loop's lateness on a loaded machine (a commit takes 10-20 ms unloaded).
constexpr long long kMarginNs = 1'500'000'000;
constexpr int kStartTimeoutMs = 60000;

long long NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

Take MakeTake() {
  Take t;
  t.name = "alpha";
  t.rate_hz = kRate;
  t.marker_names = {"m0"};
  t.markers.Resize(kFrames, 1);
  for (int f = 0; f < kFrames; ++f) {
    float* p = t.markers.at(f, 0);
    p[0] = static_cast<float>(f);
    p[1] = 0.0f;
    p[2] = 5.0f;
  }
  t.tiers = {LabelTier{"words", LabelTier::Kind::kInterval, 0.0, 4.0, {{0.0, 4.0, "bonjour"}}}};
  return t;
}

struct Edit {
  int frame = 0;
  std::string code;
  long long t_ns = 0;
};

// Reads the child's stdout line by line.
class LineReader {
 public:
  explicit LineReader(int fd) : fd_(fd) {}
  // The next line, false at end of file or after timeout_ms.
  bool Next(std::string* line, int timeout_ms) {
    const long long deadline = NowNs() + static_cast<long long>(timeout_ms) * 1'000'000;
    for (;;) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        *line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return true;
      }
      const long long left_ms = (deadline - NowNs()) / 1'000'000;
      if (left_ms <= 0) return false;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left_ms)) <= 0) return false;
      char chunk[4096];
      const ssize_t n = ::read(fd_, chunk, sizeof chunk);
      if (n <= 0) return false;
      buffer_.append(chunk, static_cast<size_t>(n));
    }
  }

 private:
  int fd_;
  std::string buffer_;
};

// One session on a fresh corpus, killed `extra_ms` after its kEditsBeforeKill-th edit.
void KillSessionAndCheck(int extra_ms) {
  testing::TempDir dir;
  const std::string corpus = (dir / "corpus.h5").string();
  {
    CorpusTransaction tx(corpus);
    tx.WriteTake(MakeTake());
    tx.Commit();
  }
  const std::string settings = (dir / "settings.ini").string();
  const std::string autosave = std::to_string(kAutosaveMs);
  const std::string period = std::to_string(kPeriodMs);
  std::vector<std::string> args = {CSW_LABEL_KILL_CHILD, corpus, settings, autosave, period};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int out[2];
  ASSERT_EQ(::pipe2(out, O_CLOEXEC), 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  ::setenv("QT_QPA_PLATFORM", "offscreen", 0);
  pid_t pid = 0;
  ASSERT_EQ(::posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0) << argv[0];
  posix_spawn_file_actions_destroy(&actions);
  ::close(out[1]);

  LineReader reader(out[0]);
  std::vector<Edit> edits;
  int saves = 0;
  bool ready = false;
  std::string line;
  auto parse = [&](const std::string& l) {
    std::istringstream in(l);
    std::string word;
    in >> word;
    if (word == "edit") {
      Edit e;
      in >> e.frame >> e.code >> e.t_ns;
      edits.push_back(e);
    } else if (word == "saved") {
      ++saves;
    } else if (word == "ready") {
      ready = true;
    } else {
      ADD_FAILURE() << "child: " << l;
    }
  };
  while (static_cast<int>(edits.size()) < kEditsBeforeKill &&
         reader.Next(&line, ready ? 10 * kPeriodMs + 5000 : kStartTimeoutMs)) {
    parse(line);
  }
  if (extra_ms > 0) {
    const long long until = NowNs() + static_cast<long long>(extra_ms) * 1'000'000;
    while (NowNs() < until && reader.Next(&line, static_cast<int>((until - NowNs()) / 1'000'000) + 1)) parse(line);
  }
  const long long kill_ns = NowNs();
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the child ended before the kill: " << status;
  while (reader.Next(&line, 1000)) parse(line);  // what it wrote before dying
  ::close(out[0]);
  ASSERT_TRUE(ready);
  ASSERT_GE(static_cast<int>(edits.size()), kEditsBeforeKill);

  // The corpus opens and reads, and takes a writer again: the killed writer's lock died with it.
  const Corpus opened = Corpus::Open(corpus);
  std::vector<LabelTier> tiers = opened.LoadTiers("alpha");
  std::map<int, std::string> stored;
  for (const LabelTier& t : tiers) {
    if (t.name != "kill_keys") continue;
    for (const Label& l : t.labels) {
      const double f = l.start_s * kRate;
      EXPECT_NEAR(f, std::round(f), 1e-9);
      stored[static_cast<int>(std::lround(f))] = l.text;
    }
  }
  {
    CorpusTransaction tx(corpus);
    tiers.push_back({"after_kill", LabelTier::Kind::kPoint, 0.0, 4.0, {{1.0, 1.0, "11"}}});
    tx.WriteTiers("alpha", tiers);
    tx.Commit();
  }
  const Take again = Corpus::Open(corpus).LoadTake("alpha");
  EXPECT_EQ(again.frames(), kFrames);
  ASSERT_EQ(again.tiers.size(), tiers.size());
  EXPECT_EQ(again.tiers.back().name, "after_kill");

  // Every edit older than the autosave delay plus the margin is stored.
  const long long cutoff = kill_ns - static_cast<long long>(kAutosaveMs) * 1'000'000 - kMarginNs;
  int checked = 0;
  double newest_stored_age_s = -1.0;
  std::map<int, std::string> typed;
  for (const Edit& e : edits) {
    typed[e.frame] = e.code;
    const auto it = stored.find(e.frame);
    const bool present = it != stored.end() && it->second == e.code;
    if (e.t_ns < cutoff) {
      ++checked;
      EXPECT_TRUE(present) << "edit " << e.code << " at frame " << e.frame << ", made " << (kill_ns - e.t_ns) / 1e9
                           << " s before the kill, is not in the corpus";
    }
  }
  for (auto it = edits.rbegin(); it != edits.rend(); ++it) {
    if (stored.count(it->frame) != 0) {
      newest_stored_age_s = static_cast<double>(kill_ns - it->t_ns) / 1e9;
      break;
    }
  }
  // Enough of the session lies before the cutoff for the check to mean something.
  EXPECT_GE(checked, 3);
  // Nothing the session did not type.
  for (const auto& [frame, code] : stored) {
    const auto it = typed.find(frame);
    EXPECT_TRUE(it != typed.end() && it->second == code) << "stored " << code << " at frame " << frame;
  }
  std::printf(
      "SIGKILL %d ms after edit %d (%zu edits in all, one every %d ms; autosave %d ms; %d saves reported): %zu stored, "
      "%d older than %.1f s "
      "all stored; newest stored edit made %.2f s before the kill\n",
      extra_ms, kEditsBeforeKill, edits.size(), kPeriodMs, kAutosaveMs, saves, stored.size(), checked,
      static_cast<double>(kAutosaveMs) / 1000.0 + static_cast<double>(kMarginNs) / 1e9, newest_stored_age_s);
}

// Two kills at different phases of the edit and autosave cycles.
TEST(LabelKill, SigkillDuringLabellingKeepsEveryEditOlderThanTheAutosaveDelay) {
  for (int extra_ms : {0, 170}) {
    SCOPED_TRACE("killed " + std::to_string(extra_ms) + " ms after the last edit awaited");
    KillSessionAndCheck(extra_ms);
  }
}

}  // namespace
}  // namespace csw

#include "core/file_util.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <regex>

#include "core/error.h"

namespace fs = std::filesystem;

namespace csw {
namespace {

fs::path TempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("csw_file_util_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The stamp is the system clock's UTC time: it lies between two readings of
// std::time taken around the call (same second, or the next one at a tick).
std::string Stamp(std::time_t t, const char* format) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

TEST(FileUtil, UtcNowIsTheCurrentUtcTimeInBothZoneSpellings) {
  for (UtcZone zone : {UtcZone::kZ, UtcZone::kOffset}) {
    const char* format = zone == UtcZone::kZ ? "%Y-%m-%dT%H:%M:%SZ" : "%Y-%m-%dT%H:%M:%S+00:00";
    const std::time_t before = std::time(nullptr);
    const std::string s = UtcNow(zone);
    const std::time_t after = std::time(nullptr);
    EXPECT_TRUE(s == Stamp(before, format) || s == Stamp(after, format)) << s;
    EXPECT_TRUE(std::regex_match(s, std::regex(zone == UtcZone::kZ ? R"(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}Z)"
                                                                   : R"(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}\+00:00)")))
        << s;
  }
  // The default is the "Z" form.
  const std::time_t before = std::time(nullptr);
  const std::string s = UtcNow();
  EXPECT_TRUE(s == Stamp(before, "%Y-%m-%dT%H:%M:%SZ") || s == Stamp(std::time(nullptr), "%Y-%m-%dT%H:%M:%SZ")) << s;
}

TEST(FileUtil, ReadTextFileReadsBytesAndNamesMissingFile) {
  const fs::path d = TempDir("read");
  const std::string bytes("a\0b\r\nc", 6);
  std::ofstream(d / "x.bin", std::ios::binary) << bytes;
  EXPECT_EQ(ReadTextFile((d / "x.bin").string()), bytes);
  try {
    ReadTextFile((d / "missing.json").string());
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json"), std::string::npos) << e.what();
  }
}

TEST(FileUtil, HiddenSiblingIsInTheSameFolder) {
  EXPECT_EQ(HiddenSibling("/a/b/corpus.h5", ".csw-tmp"), "/a/b/.corpus.h5.csw-tmp");
  EXPECT_EQ(HiddenSibling("m.h5", ".csw-lock"), ".m.h5.csw-lock");
}

TEST(FileUtil, ReplaceFileDurablyReplacesContent) {
  const fs::path d = TempDir("replace");
  std::ofstream(d / "f.txt") << "old";
  std::ofstream(d / ".f.txt.tmp") << "new";
  ReplaceFileDurably((d / ".f.txt.tmp").string(), (d / "f.txt").string());
  EXPECT_EQ(ReadTextFile((d / "f.txt").string()), "new");
  EXPECT_FALSE(fs::exists(d / ".f.txt.tmp"));
  EXPECT_THROW(ReplaceFileDurably((d / "absent").string(), (d / "f.txt").string()), IoError);
  EXPECT_EQ(ReadTextFile((d / "f.txt").string()), "new");
}

TEST(FileUtil, WriterLockIsExclusiveAndReleased) {
  const fs::path d = TempDir("lock");
  const std::string path = (d / "models.h5").string();
  {
    WriterLock first(path, "model file");
    EXPECT_EQ(first.lock_path(), (d / ".models.h5.csw-lock").string());
    try {
      WriterLock second(path, "model file");
      FAIL() << "second lock taken";
    } catch (const IoError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("models.h5"), std::string::npos) << m;
      EXPECT_NE(m.find("is writing this model file"), std::string::npos) << m;
      // The holder is named: this test program, by its pid.
      EXPECT_NE(m.find("(pid " + std::to_string(::getpid()) + ") since 20"), std::string::npos) << m;
      EXPECT_NE(m.find("test_core"), std::string::npos) << m;
    }
  }
  EXPECT_NO_THROW(WriterLock again(path, "model file"));
}

// Another process holds the lock: the refusal names it by its pid; once it
// is gone the lock is free (the kernel drops a dead process's flock).
TEST(FileUtil, WriterLockNamesAHolderInAnotherProcess) {
  const fs::path d = TempDir("lock_other");
  const std::string path = (d / "c.h5").string();
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(ready[0]);
    WriterLock held(path, "corpus");
    const char c = 'x';
    if (::write(ready[1], &c, 1) != 1) ::_exit(2);
    for (;;) ::pause();  // until killed
  }
  ::close(ready[1]);
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  ::close(ready[0]);
  std::string message;
  try {
    WriterLock second(path, "corpus");
  } catch (const IoError& e) {
    message = e.what();
  }
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_NE(message.find("(pid " + std::to_string(child) + ") since 20"), std::string::npos) << message;
  EXPECT_NE(message.find("is writing this corpus"), std::string::npos) << message;
  EXPECT_NO_THROW(WriterLock again(path, "corpus"));
}

// A lock file whose line names a process that no longer runs (the new holder
// has not written its own line yet) is not believed.
TEST(FileUtil, WriterLockIgnoresAStaleHolderLine) {
  const fs::path d = TempDir("lock_stale");
  const std::string path = (d / "c.h5").string();
  const pid_t gone = ::fork();
  ASSERT_GE(gone, 0);
  if (gone == 0) ::_exit(0);
  int status = 0;
  ::waitpid(gone, &status, 0);
  const std::string lock_path = (d / ".c.h5.csw-lock").string();
  std::ofstream(lock_path) << "ghost (pid " << gone << ") since 2026-01-01T00:00:00Z\n";
  const int fd = ::open(lock_path.c_str(), O_RDWR | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  std::string message;
  try {
    WriterLock second(path, "corpus");
  } catch (const IoError& e) {
    message = e.what();
  }
  ::close(fd);
  EXPECT_EQ(message.find("ghost"), std::string::npos) << message;
  EXPECT_NE(message.find("another csw command (in this or another process) is writing this corpus"), std::string::npos)
      << message;
}

}  // namespace
}  // namespace csw

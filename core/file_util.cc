#include "core/file_util.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace csw {

namespace fs = std::filesystem;

std::string UtcNow(UtcZone zone) {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return std::string(buf) + (zone == UtcZone::kOffset ? "+00:00" : "Z");
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw IoError(path, "cannot read");
  return s.str();
}

std::string HiddenSibling(const std::string& path, const std::string& suffix) {
  const fs::path p(path);
  return (p.parent_path() / ("." + p.filename().string() + suffix)).string();
}

void FsyncPath(const std::string& p, bool directory, const std::string& target) {
  const int fd = ::open(p.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) throw IoError(target, "cannot open " + p + " to sync it: " + std::strerror(errno));
  const int r = ::fsync(fd);
  const int saved = errno;
  ::close(fd);
  if (r != 0 && !(directory && (saved == EINVAL || saved == EROFS))) {
    throw IoError(target, "cannot sync " + p + ": " + std::strerror(saved));
  }
}

void ReplaceFileDurably(const std::string& temp, const std::string& path) {
  FsyncPath(temp, false, path);
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    throw IoError(path, "cannot rename " + temp + " over it: " + std::strerror(errno));
  }
  const fs::path dir = fs::path(path).parent_path();
  FsyncPath(dir.empty() ? std::string(".") : dir.string(), true, path);
}

namespace {

// This process, as the lock file names its holder: "csw-workbench (pid 4242)
// since 2026-12-03T14:05:09Z".
std::string HolderLine() {
  // The program's name, read once per process (a fork keeps it; the pid is asked every time).
  static const std::string name = [] {
    std::ifstream comm("/proc/self/comm");
    std::string line;
    return std::getline(comm, line) && !line.empty() ? line : std::string("process");
  }();
  return name + " (pid " + std::to_string(::getpid()) + ") since " + UtcNow(UtcZone::kZ);
}

// The holder a lock file names, "" when it names none or a process that no
// longer runs (a holder that has just taken the lock may not have written its
// line yet: the previous holder's line is then stale).
std::string ReadHolder(int fd) {
  char buf[256] = {};
  const ssize_t n = ::pread(fd, buf, sizeof(buf) - 1, 0);
  if (n <= 0) return "";
  std::string line(buf, static_cast<size_t>(n));
  line = line.substr(0, line.find('\n'));
  const size_t at = line.find("(pid ");
  if (at == std::string::npos) return "";
  const long pid = std::strtol(line.c_str() + at + 5, nullptr, 10);
  if (pid <= 0 || (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)) return "";
  for (char& c : line)
    if (static_cast<unsigned char>(c) < 0x20) c = ' ';
  return line;
}

}  // namespace

WriterLock::WriterLock(const std::string& path, const std::string& what_is_locked)
    : lock_path_(HiddenSibling(path, ".csw-lock")) {
  fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw IoError(path, "cannot create the lock file " + lock_path_ + ": " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int saved = errno;
    const std::string holder = saved == EWOULDBLOCK ? ReadHolder(fd_) : "";
    ::close(fd_);
    fd_ = -1;
    if (saved == EWOULDBLOCK) {
      const std::string who = holder.empty() ? "another csw command (in this or another process)" : holder;
      throw IoError(
          path, who + " is writing this " + what_is_locked + " (" + lock_path_ + " is locked); wait for it to finish");
    }
    throw IoError(path, "cannot lock " + lock_path_ + ": " + std::strerror(saved));
  }
  // Name the holder for a writer refused meanwhile (best effort: the lock
  // itself is the flock, not this text).
  const std::string line = HolderLine() + "\n";
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t w = ::pwrite(fd_, line.data(), line.size(), 0);
  }
}

WriterLock::~WriterLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace csw

#pragma once
// Small file helpers shared by every module that saves files: the UTC time
// stamp written into files, whole-file reads, and the pieces of a crash-safe
// save (a hidden temporary sibling, fsync, atomic rename, an advisory writer
// lock). One copy each, so every save in csw keeps the same promises.
#include <string>

namespace csw {

// How UtcNow spells the UTC zone: "Z" (TRC, corpus and model files) or the
// numeric offset "+00:00" (the form ELAN writes in EAF headers).
enum class UtcZone { kZ, kOffset };

// The current time as ISO 8601 UTC to the second, e.g. "2026-01-02T03:04:05Z"
// or, with UtcZone::kOffset, "2026-01-02T03:04:05+00:00".
std::string UtcNow(UtcZone zone = UtcZone::kZ);

// The whole file as bytes; IoError naming the file when it cannot be read.
std::string ReadTextFile(const std::string& path);

// "<dir>/.<name><suffix>" for path "<dir>/<name>": where a save writes before
// it replaces the file, and where its lock lives.
std::string HiddenSibling(const std::string& path, const std::string& suffix);

// Flushes a file (or, with directory, a folder's entries) to disk; IoError
// naming `target` (the file being saved) on failure. A folder that cannot be
// synced (EINVAL/EROFS on some file systems) is not an error.
void FsyncPath(const std::string& path, bool directory, const std::string& target);

// The last step of a crash-safe save: fsyncs `temp`, renames it over `path`
// (atomic on POSIX file systems) and fsyncs the folder. A process killed at
// any moment leaves either the old file or the new one. IoError naming
// `path` on failure (temp is left for the caller to remove).
void ReplaceFileDurably(const std::string& temp, const std::string& path);

// An exclusive advisory lock (flock) on the sibling file ".<name>.csw-lock" of
// `path`, held for the object's lifetime: one writer at a time per file, in
// this process or another. The holder writes its name, pid and start time into
// the lock file; a refused writer gets an IoError naming that holder ("csw
// (pid 4242) since ... is writing this corpus ..."; "another csw command" when
// the file names no live process) and `what_is_locked` (e.g. "corpus", "model
// file").
class WriterLock {
 public:
  WriterLock(const std::string& path, const std::string& what_is_locked);
  ~WriterLock();
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;
  const std::string& lock_path() const { return lock_path_; }

 private:
  std::string lock_path_;
  int fd_ = -1;
};

}  // namespace csw

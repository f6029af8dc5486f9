// An exclusive advisory lock (flock) on a sidecar file: one writer per cache.
#pragma once

#include <string>

namespace magbake::cli {

/// Holds an exclusive flock on `path` (created if missing) for its lifetime, or fails at once
/// when another process holds it. The lock file is removed when the lock is released. Robust to
/// the unlink race: after locking, the file at `path` must still be the one locked.
class FileLock {
 public:
  explicit FileLock(std::string path);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

  /// True when this process holds the lock.
  bool held() const { return fd_ >= 0; }
  /// Why the lock is not held ("" when it is).
  const std::string& error() const { return error_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::string error_;
};

}  // namespace magbake::cli

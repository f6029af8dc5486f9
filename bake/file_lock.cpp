#include "file_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace magbake::cli {

FileLock::FileLock(std::string path) : path_(std::move(path)) {
  for (int attempt = 0; attempt < 8; ++attempt) {
    const int fd = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
      error_ = "cannot create the lock file " + path_ + ": " + std::strerror(errno);
      return;
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int e = errno;
      ::close(fd);
      error_ = e == EWOULDBLOCK ? "another magbake process is writing it (lock " + path_ + " is held)"
                                : "cannot lock " + path_ + ": " + std::strerror(e);
      return;
    }
    // The holder before us may have removed the file between our open and our lock: then we
    // hold a lock on a file nobody else can see, and must try again.
    struct stat a {}, b {};
    if (::fstat(fd, &a) == 0 && ::stat(path_.c_str(), &b) == 0 && a.st_ino == b.st_ino && a.st_dev == b.st_dev) {
      fd_ = fd;
      error_.clear();
      return;
    }
    ::close(fd);
  }
  error_ = "cannot lock " + path_ + ": it keeps being replaced";
}

FileLock::~FileLock() {
  if (fd_ < 0) return;
  ::unlink(path_.c_str());  // while still holding it: a waiting process re-checks the inode
  ::close(fd_);
}

}  // namespace magbake::cli

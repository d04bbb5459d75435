// One writer for a folder of state (stac induct's state): an exclusive flock on DIR/lock, held
// until the FolderLock is destroyed or the process ends (a kill -9 releases it too). The file
// holds the holder's pid, so a refusal names it.
#pragma once

#include <filesystem>
#include <string>

#include "rt/expected.hpp"

namespace stac::formats {

class FolderLock {
 public:
  // Locks `dir` (which must exist) or says who holds it; `what` names the folder's kind in the
  // refusal ("the induction state").
  static rt::Result<FolderLock> acquire(const std::filesystem::path& dir, const std::string& what);

  FolderLock(FolderLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  FolderLock& operator=(FolderLock&& other) noexcept;
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  ~FolderLock();

 private:
  explicit FolderLock(int fd) noexcept : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace stac::formats

// Owns one POSIX file descriptor and closes it when destroyed or reset: a socket, an eventfd, an
// opened device. Move-only; a moved-from owner holds -1 (no descriptor). Any negative value means
// "none" and is never closed. Closing keeps errno, so an owner dying on an error path does not
// overwrite the errno of the call that failed.
#pragma once

#include <unistd.h>

#include <cerrno>

namespace stac::rt {

class UniqueFd {
 public:
  UniqueFd() noexcept = default;
  explicit UniqueFd(int fd) noexcept : fd_(fd) {}
  UniqueFd(UniqueFd&& o) noexcept : fd_(o.release()) {}
  UniqueFd& operator=(UniqueFd&& o) noexcept {
    reset(o.release());  // self-move: release() empties this first, so nothing is closed
    return *this;
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd() { reset(); }

  int get() const noexcept { return fd_; }
  bool valid() const noexcept { return fd_ >= 0; }
  explicit operator bool() const noexcept { return valid(); }

  // Gives the descriptor up without closing it; this owner holds -1 afterwards.
  [[nodiscard]] int release() noexcept {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }
  // Closes the descriptor held (unless it is `fd` itself) and takes `fd`.
  void reset(int fd = -1) noexcept {
    if (fd_ >= 0 && fd_ != fd) {
      const int saved = errno;
      (void)::close(fd_);  // never retried: on Linux the descriptor is gone even on EINTR
      errno = saved;
    }
    fd_ = fd;
  }

 private:
  int fd_ = -1;
};

}  // namespace stac::rt

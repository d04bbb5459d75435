// SocketCAN raw-socket reader: AF_CAN/CAN_RAW bound to one interface, kernel id filters
// (CAN_RAW_FILTER), kernel receive stamps (SO_TIMESTAMPNS), kernel drop count (SO_RXQ_OVFL).
// The read path works on any descriptor that delivers one 16-byte `struct can_frame` per record,
// so it runs unchanged on a SOCK_SEQPACKET socketpair where the kernel has no AF_CAN.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "drivers/can/frame.hpp"
#include "rt/expected.hpp"
#include "rt/unique_fd.hpp"

namespace stac::can {

struct CanIdFilter {
  std::uint32_t id = 0;
  bool extended = false;  // match 29-bit ids (else 11-bit); remote frames never match
};

struct SocketCanConfig {
  std::string interface = "can0";
  std::vector<CanIdFilter> filters;  // empty: every frame
};

struct SocketCanCounters {
  std::uint64_t frames = 0;           // classic frames returned
  std::uint64_t can_fd = 0;           // 72-byte CAN FD records: not supported, dropped
  std::uint64_t bad_size = 0;         // records of any other size: dropped
  std::uint64_t kernel_drops = 0;     // dropped by the kernel, receive queue full (SO_RXQ_OVFL)
  std::uint64_t no_kernel_stamp = 0;  // stamped with CLOCK_REALTIME instead
};

// The index of network interface `name` (if_nametoindex), as open() finds it. Errors: a name of
// 0 or more than 15 characters, no such interface (names it and how to list or create one).
rt::Result<unsigned> interface_index(const std::string& name);

class SocketCanReader {
 public:
  static constexpr int kStopped = -1;
  static constexpr int kError = -2;
  static constexpr int kClosed = -3;  // the peer closed (socketpair) or the interface went away

  // Errors: no such interface (names it and how to list or create one), AF_CAN missing from the
  // kernel (errno 97: names the gs_usb alternative), filters or bind refused.
  static rt::Result<SocketCanReader> open(const SocketCanConfig& config);
  // Takes ownership of an open descriptor carrying struct can_frame records (a raw CAN socket
  // opened elsewhere, or a SOCK_SEQPACKET socketpair end in tests). Asks for SO_TIMESTAMPNS.
  static rt::Result<SocketCanReader> adopt(int fd);

  // Waits up to timeout_ms (-1: forever) and returns up to out.size() frames (0 on timeout),
  // kStopped after stop(), kClosed at end of stream, kError on a socket error. No allocation.
  int read(std::span<Frame> out, int timeout_ms) noexcept;
  // Sends one classic frame; true when the whole record went out.
  bool write(const Frame& frame) noexcept;
  // Any thread: makes the current and every later read() return kStopped.
  void stop() noexcept;

  int fd() const noexcept { return fd_.get(); }
  const SocketCanCounters& counters() const noexcept { return counters_; }

 private:
  SocketCanReader() = default;

  rt::UniqueFd fd_;
  rt::UniqueFd wake_fd_;
  SocketCanCounters counters_;
};

}  // namespace stac::can

// Live UDP: a bound socket read in batches (recvmmsg) into buffers allocated at open(), with
// kernel receive stamps (SO_TIMESTAMPNS), an optional sender filter and drop counters; stop()
// wakes a blocked receive() from another thread. UdpSender sends datagrams (tests, replay).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "drivers/io/datagram.hpp"
#include "rt/expected.hpp"
#include "rt/unique_fd.hpp"

struct mmsghdr;

namespace stac::io {

struct UdpReceiverConfig {
  std::string bind_address = "0.0.0.0";
  std::uint16_t port = 2368;            // 0: any free port (see port())
  int receive_buffer_bytes = 16 << 20;  // SO_RCVBUF asked for; capped by net.core.rmem_max
  std::string sender_address;           // empty: any sender; else only this IPv4 address
  int batch = 32;                       // datagrams per recvmmsg
  int max_payload = 2048;               // larger datagrams are truncated and counted
};

struct UdpReceiverCounters {
  std::uint64_t received = 0;         // datagrams returned
  std::uint64_t filtered_sender = 0;  // from another address: dropped
  std::uint64_t truncated = 0;        // longer than max_payload: dropped
  std::uint64_t kernel_drops = 0;     // dropped by the kernel, receive buffer full (SO_RXQ_OVFL)
  std::uint64_t no_kernel_stamp = 0;  // stamped with CLOCK_REALTIME instead
};

class UdpReceiver {
 public:
  static constexpr int kStopped = -1;
  static constexpr int kError = -2;

  // Errors name the address and port and what to change (port in use, bad address, ...).
  static rt::Result<UdpReceiver> open(const UdpReceiverConfig& config);
  // Defaulted in the .cpp, where mmsghdr is a complete type.
  UdpReceiver(UdpReceiver&&) noexcept;
  UdpReceiver& operator=(UdpReceiver&&) noexcept;
  UdpReceiver(const UdpReceiver&) = delete;
  ~UdpReceiver();

  // Waits up to timeout_ms for datagrams and fills `out`; returns how many (0 on timeout),
  // kStopped after stop(), kError on a socket error. No allocation. Payloads stay valid until
  // the next call.
  int receive(std::span<Datagram> out, int timeout_ms) noexcept;
  // Any thread: makes the current and every later receive() return kStopped.
  void stop() noexcept;

  std::uint16_t port() const noexcept { return port_; }
  int receive_buffer_bytes() const noexcept { return granted_rcvbuf_; }  // as granted by the kernel
  const UdpReceiverCounters& counters() const noexcept { return counters_; }

 private:
  UdpReceiver() = default;

  rt::UniqueFd fd_;
  rt::UniqueFd wake_fd_;
  std::uint16_t port_ = 0;
  int granted_rcvbuf_ = 0;
  std::uint32_t sender_ = 0;
  bool filter_sender_ = false;
  int batch_ = 0;
  std::size_t max_payload_ = 0;
  std::vector<std::uint8_t> buffers_;  // batch x (max_payload + 1)
  std::vector<std::uint8_t> control_;  // batch x cmsg space
  std::vector<mmsghdr> messages_;
  std::vector<std::byte> iovecs_;     // struct iovec[batch]
  std::vector<std::byte> addresses_;  // struct sockaddr_in[batch]
  UdpReceiverCounters counters_;
};

class UdpSender {
 public:
  static rt::Result<UdpSender> open(const std::string& address, std::uint16_t port);
  // True when the whole datagram went out.
  bool send(std::span<const std::uint8_t> payload) noexcept;

 private:
  UdpSender() = default;
  rt::UniqueFd fd_;
};

}  // namespace stac::io

// TCP client for the POS LV Real-Time Data port (5602): connects, reads the byte stream,
// reconnects with exponential backoff when the connection fails, drops, or stalls (no byte for
// stall_timeout_ms while connected), and stops promptly from another thread. The bytes go to a
// StreamParser; call its end_of_stream() whenever session() changes (a new connection starts a
// new stream). One reading thread; stop() from any thread. No allocation after open().
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "rt/expected.hpp"
#include "rt/unique_fd.hpp"

namespace stac::applanix {

struct TcpClientConfig {
  std::string address;            // the POS computer, IPv4 (no default: site-specific)
  std::uint16_t port = 5602;      // Real-Time Data
  int connect_timeout_ms = 2000;  // one connection attempt
  int stall_timeout_ms = 1000;    // connected but silent this long: reconnect
  // Connected, bytes arriving, but no valid message (note_message()) for this long: reconnect
  // (a trickle or a flood of garbage keeps a connection from stalling). 0: never.
  int message_timeout_ms = 2000;
  int initial_backoff_ms = 100;  // delay after the first failure, doubled per failure
  int max_backoff_ms = 5000;
};

struct TcpClientCounters {
  std::uint64_t connects = 0;          // connections established
  std::uint64_t connect_failures = 0;  // refused, unreachable or timed out
  std::uint64_t disconnects = 0;       // closed by the peer or a socket error
  std::uint64_t stalls = 0;            // closed by us after stall_timeout_ms of silence
  std::uint64_t no_message = 0;        // closed by us: bytes, but no valid message for a while
  std::uint64_t bytes = 0;
};

class TcpClient {
 public:
  static constexpr int kStopped = -1;

  // Checks the configuration only (errors name the field); connecting happens in receive().
  static rt::Result<TcpClient> open(const TcpClientConfig& config);

  // Waits up to timeout_ms for stream bytes, (re)connecting as needed. Returns the number of
  // bytes written to `out` (> 0), 0 when the time ran out, or kStopped after stop().
  int receive(std::span<std::uint8_t> out, int timeout_ms) noexcept;
  // The reading thread: the bytes so far held a valid message (the stream is the INS's).
  void note_message() noexcept;
  // Any thread: makes the current and every later receive() return kStopped.
  void stop() noexcept;

  // Increments with every established connection.
  std::uint64_t session() const noexcept { return counters_.connects; }
  bool connected() const noexcept { return fd_.valid(); }
  // Delay before the next connection attempt after the failures so far (0 when connected).
  int backoff_ms() const noexcept { return backoff_ms_; }
  const TcpClientCounters& counters() const noexcept { return counters_; }

 private:
  TcpClient() = default;
  bool try_connect(std::int64_t now_ns) noexcept;
  void disconnect(std::int64_t now_ns) noexcept;
  bool wait_wake(int timeout_ms) noexcept;  // true when stop() was called

  TcpClientConfig config_;
  std::uint32_t address_ = 0;
  rt::UniqueFd fd_;
  rt::UniqueFd wake_fd_;
  int backoff_ms_ = 0;
  std::int64_t next_attempt_ns_ = 0;
  std::int64_t last_data_ns_ = 0;
  std::int64_t last_message_ns_ = 0;
  TcpClientCounters counters_;
};

}  // namespace stac::applanix

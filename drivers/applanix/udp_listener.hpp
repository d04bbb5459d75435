// Applanix over UDP (the Display port 5600, or the Real-Time Data port when set to UDP): the
// project's batched UdpReceiver feeding a StreamParser. Each datagram carries whole messages,
// so each one is parsed as its own stream: a partial message at its end is counted truncated.
// One reading thread; stop() from any thread. No allocation after open().
#pragma once

#include <array>
#include <cstdint>

#include "drivers/applanix/stream_parser.hpp"
#include "drivers/io/udp_receiver.hpp"

namespace stac::applanix {

class UdpListener {
 public:
  // `config.max_payload` must hold the largest datagram (1456 bytes in the real Display capture).
  static rt::Result<UdpListener> open(const io::UdpReceiverConfig& config,
                                      std::size_t max_message_bytes = 8192);

  // Waits up to timeout_ms for datagrams: their count, 0 on timeout, or io::UdpReceiver::kStopped
  // / kError. Messages left from an earlier batch are dropped unread.
  int receive(int timeout_ms) noexcept;
  // The next message of the received datagrams; false when they are used up.
  bool next(Parsed& out) noexcept;
  // Kernel receive stamp (ns since the Unix epoch) of the datagram the last message came from.
  std::int64_t stamp_ns() const noexcept { return stamp_ns_; }
  void stop() noexcept { receiver_.stop(); }

  std::uint16_t port() const noexcept { return receiver_.port(); }
  const StreamParser& parser() const noexcept { return parser_; }
  const io::UdpReceiverCounters& receiver_counters() const noexcept { return receiver_.counters(); }

 private:
  UdpListener(io::UdpReceiver receiver, std::size_t max_message_bytes)
      : receiver_(std::move(receiver)), parser_(max_message_bytes) {}

  io::UdpReceiver receiver_;
  StreamParser parser_;
  std::array<io::Datagram, 32> batch_{};
  int count_ = 0;
  int index_ = 0;  // datagram being parsed (count_ when none)
  std::int64_t stamp_ns_ = 0;
};

}  // namespace stac::applanix

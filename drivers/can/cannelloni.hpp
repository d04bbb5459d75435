// CAN frames over UDP in the cannelloni format (mguentner/cannelloni, doc/udp_format.md, version
// 2): what a CAN-to-Ethernet gateway sends where the vehicle computer has no CAN controller of its
// own (cannelloni on a gateway's SocketCAN, or an embedded lwIP port). A datagram is a 5-byte
// header {u8 version = 2, u8 op code = 0 (DATA), u8 sequence number, u16 frame count} and then
// each frame: {u32 can_id (SocketCAN flag bits), u8 len, [u8 flags when len has bit 0x80: a CAN
// FD frame], len data bytes}. Everything big-endian.
//
// CannelloniReader is a can.transport for `stac run` (can.transport: cannelloni): it binds a UDP
// port and returns the frames of every datagram, stamped with the receive time. CAN FD frames are
// dropped and counted (STAC's signals are classic CAN); a datagram of another version or op code,
// or shorter than its count says, is counted malformed (the frames before the damage are kept);
// datagrams lost on the way show as gaps in the 8-bit sequence numbers (counted per sender).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>

#include "drivers/can/frame.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "rt/expected.hpp"

namespace stac::can {

inline constexpr std::uint8_t kCannelloniVersion = 2;
inline constexpr std::uint8_t kCannelloniData = 0;  // op code DATA (ACK and NACK: not over UDP)
inline constexpr std::size_t kCannelloniHeaderBytes = 5;
inline constexpr std::uint8_t kCannelloniFdFlag = 0x80;  // in len: a CAN FD frame, flags follow
inline constexpr std::size_t kCannelloniMaxDatagram = 65507;  // the largest IPv4 UDP payload

struct CannelloniHeader {
  std::uint8_t version = 0, op_code = 0, sequence = 0;
  std::uint16_t count = 0;  // frames in the datagram
};

// The header of a datagram; false when it is shorter than a header.
bool parse_cannelloni_header(std::span<const std::uint8_t> datagram,
                             CannelloniHeader& header) noexcept;

enum class CannelloniFrameKind : std::uint8_t {
  kClassic,    // `frame` holds it
  kFd,         // a CAN FD frame: skipped (its bytes are consumed)
  kTruncated,  // the datagram ends inside the frame, or a classic len above 8: stop here
};

// The frame at byte `at` of a datagram (at >= the header): what it is, and in `next` the byte
// after it. No allocation.
CannelloniFrameKind parse_cannelloni_frame(std::span<const std::uint8_t> datagram, std::size_t at,
                                           Frame& frame, std::size_t& next) noexcept;

// One datagram of `frames` (classic, at most 8 data bytes each) with sequence number `sequence`,
// written to `out`; returns its size, or 0 when it does not fit. No allocation.
std::size_t encode_cannelloni(std::span<const Frame> frames, std::uint8_t sequence,
                              std::span<std::uint8_t> out) noexcept;

struct CannelloniConfig {
  std::string bind_address = "0.0.0.0";  // IPv4 address to listen on
  std::uint16_t port = 20000;            // UDP port (cannelloni's usual one)
};

struct CannelloniCounters {
  std::uint64_t datagrams = 0;     // datagrams received
  std::uint64_t frames = 0;        // classic frames returned
  std::uint64_t can_fd = 0;        // CAN FD frames: dropped
  std::uint64_t malformed = 0;     // datagrams not version 2 DATA, or cut inside a frame
  std::uint64_t lost = 0;          // datagrams missing between two of one sender (sequence gaps)
  std::uint64_t kernel_drops = 0;  // dropped by the kernel, receive buffer full
};

class CannelloniReader {
 public:
  static constexpr int kStopped = -1;
  static constexpr int kError = -2;

  // Binds the UDP port (port 0: any free one, see port()). Errors name the address and port and
  // what to change.
  static rt::Result<CannelloniReader> open(const CannelloniConfig& config);

  // Waits up to timeout_ms (-1: forever) for a datagram and returns up to out.size() frames (0 on
  // timeout), kStopped after stop(), kError on a socket error. Frames of a datagram that do not
  // fit in `out` are returned by the next read. No allocation.
  int read(std::span<Frame> out, int timeout_ms) noexcept;
  // Any thread: makes the current and every later read() return kStopped.
  void stop() noexcept;

  [[nodiscard]] std::uint16_t port() const noexcept { return udp_.port(); }  // the bound port
  [[nodiscard]] CannelloniCounters counters() const noexcept;

 private:
  explicit CannelloniReader(io::UdpReceiver udp) : udp_(std::move(udp)) {}
  // A datagram just received: its header checked and counted; left_ is its frames to return.
  void begin() noexcept;

  io::UdpReceiver udp_;     // one datagram per receive, payloads up to kCannelloniMaxDatagram
  io::Datagram datagram_;   // the datagram being read (valid until the next receive)
  std::size_t at_ = 0;      // the byte of its next frame
  std::uint16_t left_ = 0;  // frames of it not yet returned
  bool have_sequence_ = false;
  std::uint32_t sender_ip_ = 0;  // whose sequence numbers last_sequence_ is of
  std::uint16_t sender_port_ = 0;
  std::uint8_t last_sequence_ = 0;
  CannelloniCounters counters_;
};

}  // namespace stac::can

// TCP segments (as read from a capture) and their in-order reassembly for one direction of one
// connection at a time: retransmitted bytes are dropped, out-of-order segments wait in a fixed
// store until the gap before them is filled, and a gap that never fills (lost in the capture) is
// skipped at finish() or when the store is full, and counted. No allocation after construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace stac::io {

struct TcpSegment {
  std::span<const std::uint8_t> payload;  // views the source's storage until its next call
  std::int64_t stamp_ns = 0;              // capture time, ns since the Unix epoch
  std::uint32_t src_ip = 0;               // IPv4, host byte order
  std::uint32_t dst_ip = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::uint32_t seq = 0;   // sequence number of the first payload byte (or SYN)
  std::uint8_t flags = 0;  // TCP flags (kTcpSyn, kTcpFin, kTcpRst, ...)
};

inline constexpr std::uint8_t kTcpFin = 0x01;
inline constexpr std::uint8_t kTcpSyn = 0x02;
inline constexpr std::uint8_t kTcpRst = 0x04;
inline constexpr std::uint8_t kTcpAck = 0x10;

struct TcpReassemblerCounters {
  std::uint64_t segments = 0;       // added
  std::uint64_t bytes = 0;          // delivered in order
  std::uint64_t retransmitted = 0;  // segments whose bytes were all delivered already
  std::uint64_t overlap_bytes = 0;  // repeated bytes cut from partly new segments
  std::uint64_t out_of_order = 0;   // segments stored until the bytes before them came
  std::uint64_t gaps = 0;           // holes skipped (bytes never seen)
  std::uint64_t gap_bytes = 0;
  std::uint64_t streams = 0;  // connections started (SYN, or the first segment seen)
};

class TcpReassembler {
 public:
  // slots x slot_bytes of store for out-of-order segments (larger segments count as a gap).
  explicit TcpReassembler(std::size_t slots = 16, std::size_t slot_bytes = 9000);

  // Adds the next segment of the direction being followed. True when it starts a new stream
  // (the first segment, or a SYN): whoever parses the bytes should restart. Undelivered bytes
  // of an earlier stream are dropped.
  bool add(const TcpSegment& segment) noexcept;
  // The in-order bytes made available by the last add() (or finish()), chunk by chunk; false
  // when there are none left. A chunk stays valid until the next add()/next()/finish().
  bool next(std::span<const std::uint8_t>& out) noexcept;
  // End of the capture: next() then also delivers stored segments beyond holes (counted gaps).
  void finish() noexcept;

  const TcpReassemblerCounters& counters() const noexcept { return counters_; }

 private:
  struct Slot {
    std::uint32_t seq = 0;
    std::size_t length = 0;
    bool used = false;
  };
  void release_delivered() noexcept;
  Slot* earliest() noexcept;
  void skip_to(std::uint32_t seq) noexcept;  // declares a gap up to seq

  std::vector<Slot> slots_;
  std::vector<std::uint8_t> store_;  // slots x slot_bytes
  std::size_t slot_bytes_;
  Slot* delivered_ = nullptr;  // slot handed out by the last next(), freed on the next call
  std::span<const std::uint8_t> current_;  // the last added segment, not stored
  std::uint32_t current_seq_ = 0;
  std::uint32_t expected_ = 0;  // next sequence number to deliver
  bool started_ = false;
  bool finishing_ = false;
  TcpReassemblerCounters counters_;
};

}  // namespace stac::io

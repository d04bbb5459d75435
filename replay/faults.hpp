// Faults injected into a replay's UDP datagrams (`stac replay --faults`, issue 31): what a
// hostile or broken network does to a sensor's stream, seeded so a failing run repeats exactly.
//
//   loss=P            each datagram lost with probability P
//   burst=P:N         with probability P a datagram starts a burst of N lost ones
//   reorder=P         a datagram held back and sent after the next one
//   duplicate=P       a datagram sent twice
//   truncate=P        a datagram cut to a random shorter length (at least 1 byte)
//   oversize=P        a datagram sent with 1 to 200 random bytes appended
//   garbage=P         a datagram of random bytes (1 to 1500, or exactly the size of the
//                     datagram after it) sent before a datagram
//   dropout=S+L       nothing sent from S to S+L seconds of capture time (a sensor dropout)
//   clock-jump=S:J    from S seconds of capture time on, the Velodyne timestamp of each data
//                     packet (bytes 1200-1203, microseconds past the hour) shifted by J seconds
//   window=S+L        the random faults above only from S to S+L seconds of capture time
//   seed=N            the random draws' seed (default 1)
// and into the replayed TCP streams (the INS, Applanix port 5602):
//   ins-dropout=S+L   nothing of the stream sent from S to S+L s (the connection stays up)
//   ins-garbage=S+L   the stream's bytes replaced by random ones from S to S+L s
//   ins-checksum=S+L  a body byte of every Applanix message ("$GRP") flipped from S to S+L s, so
//                     its checksum fails
//   ins-disconnect=S  the connection closed at S s of each pass (the client connects again and
//                     gets the stream from then on)
// and into the CAN frames of `--can LOG` (sent as cannelloni datagrams, can_replay.hpp):
//   can-silence=S+L   no frame sent from S to S+L s (a silent bus, or a gateway that stopped)
//
// Capture time counts from the first datagram of each pass (a TCP-only capture: from the first
// stream byte). Everything is decided per datagram or chunk from a SplitMix64 stream and written
// into buffers sized at start-up: no allocation per datagram.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/io/udp_receiver.hpp"
#include "rt/expected.hpp"
#include "rt/splitmix64.hpp"

namespace stac::replay {

using TimeSpan = std::optional<std::pair<double, double>>;  // start s, length s

struct StreamFaultPlan {
  TimeSpan dropout, garbage, checksum;
  std::optional<double> disconnect;  // at s
  std::uint64_t seed = 1;

  [[nodiscard]] bool any() const noexcept { return dropout || garbage || checksum || disconnect; }
};

struct FaultPlan {
  double loss = 0, burst = 0, reorder = 0, duplicate = 0, truncate = 0, oversize = 0, garbage = 0;
  std::uint32_t burst_length = 0;
  std::optional<std::pair<double, double>> dropout;     // start s, length s
  std::optional<std::pair<double, double>> clock_jump;  // from s, jump s
  std::optional<std::pair<double, double>> window;      // start s, length s
  std::uint64_t seed = 1;
  StreamFaultPlan ins;   // the TCP streams' (ins-...)
  TimeSpan can_silence;  // the CAN frames' (can-silence)

  // A fault in the UDP datagrams.
  [[nodiscard]] bool any() const noexcept {
    return loss > 0 || burst > 0 || reorder > 0 || duplicate > 0 || truncate > 0 || oversize > 0 ||
           garbage > 0 || dropout || clock_jump;
  }
};

// "loss=0.01,burst=0.001:20,..." (the list above); an error names the item and what is wrong.
rt::Result<FaultPlan> parse_fault_plan(const std::string& spec);

struct FaultCounts {
  std::uint64_t lost = 0, burst_lost = 0, dropout_lost = 0, reordered = 0, duplicated = 0,
                truncated = 0, oversized = 0, garbage = 0, clock_jumped = 0;
};

// "faults: 12 lost, 3 reordered, ..." (or "faults: none happened").
std::string summary(const FaultCounts& counts);

class FaultInjector {
 public:
  explicit FaultInjector(const FaultPlan& plan) : plan_(plan), rng_(plan.seed) {}

  // One datagram at `capture_s` seconds into its pass: sends what the faults make of it (none,
  // one or more datagrams) with `send`. Returns how many sends the socket refused.
  std::uint64_t offer(std::span<const std::uint8_t> payload, double capture_s, io::UdpSender& send);
  // The end of a pass: a datagram still held back for reordering is sent.
  std::uint64_t flush();

  [[nodiscard]] const FaultCounts& counts() const noexcept { return counts_; }

 private:
  static constexpr std::size_t kMaxDatagram = 2048;

  bool in_window(double capture_s) const noexcept;

  FaultPlan plan_;
  rt::SplitMix64 rng_;
  io::UdpSender* held_by_ = nullptr;  // the sender of the held datagram
  FaultCounts counts_;
  std::uint32_t burst_left_ = 0;
  std::array<std::uint8_t, kMaxDatagram + 256> work_{};  // a datagram being changed
  std::array<std::uint8_t, kMaxDatagram> held_{};        // one held back for reordering
  std::size_t held_size_ = 0;
  bool holding_ = false;
  std::array<std::uint8_t, 1500> junk_{};
};

struct StreamFaultCounts {
  std::uint64_t dropout_bytes = 0, garbage_bytes = 0, checksums_broken = 0, disconnects = 0;
};

std::string summary(const StreamFaultCounts& counts);  // "ins faults: ..."

// The faults of a StreamFaultPlan on one stream's chunks, in order.
class StreamFaultInjector {
 public:
  static constexpr std::size_t kMaxChunk =
      std::size_t{64} * 1024;  // longer chunks are offered in pieces

  explicit StreamFaultInjector(const StreamFaultPlan& plan) : plan_(plan), rng_(plan.seed) {}

  // A new pass over the stream (the disconnect happens once per pass).
  void new_pass() noexcept { disconnected_ = false; }
  // A chunk (at most kMaxChunk bytes) due at `capture_s`: sets `disconnect` when the connection
  // must be closed before it is sent, and returns the bytes to send (empty: none).
  std::span<const std::uint8_t> apply(std::span<const std::uint8_t> chunk, double capture_s,
                                      bool& disconnect) noexcept;

  [[nodiscard]] const StreamFaultCounts& counts() const noexcept { return counts_; }

 private:
  StreamFaultPlan plan_;
  rt::SplitMix64 rng_;
  StreamFaultCounts counts_;
  bool disconnected_ = false;
  std::vector<std::uint8_t> work_ = std::vector<std::uint8_t>(kMaxChunk);
};

}  // namespace stac::replay

// Replays the UDP datagrams of a pcap capture over a socket: each payload is sent, in capture
// order, to an address (loopback by default) at its recorded time divided by a rate, or as fast
// as possible; optionally looping. Pacing follows an absolute schedule on CLOCK_MONOTONIC
// (replay_pacing.hpp: its own, or one shared with a TcpReplay of the same capture), so sleep
// errors never accumulate; the error |send time - scheduled time| of every datagram is kept in
// a 1 us histogram.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "replay/faults.hpp"
#include "replay/replay_pacing.hpp"
#include "rt/expected.hpp"

namespace stac::replay {

struct ReplayConfig {
  std::string address = "127.0.0.1";  // destination IPv4 address
  std::optional<std::uint16_t> port;  // destination port; default: each datagram's captured one
  std::optional<std::uint16_t> filter_port;  // replay only datagrams captured to this port
  double rate = 1.0;                         // > 0: recorded time differences are divided by it
  bool fast = false;                         // no pacing: send as fast as the socket takes them
  std::uint64_t loops = 1;                   // passes over the capture; 0: until stopped
  bool allow_empty = false;         // a capture without (matching) datagram is a plan of 0 packets
  std::optional<FaultPlan> faults;  // faults injected into the datagrams (faults.hpp)
};

// What one pass over the capture holds (found by open()).
struct ReplayPlan {
  std::uint64_t packets = 0;             // matching datagrams per pass
  std::uint64_t bytes = 0;               // their UDP payload bytes
  std::int64_t first_stamp_ns = 0;       // capture time of the first datagram
  std::int64_t span_ns = 0;              // recorded time from the first to the last datagram
  std::int64_t pass_period_ns = 0;       // recorded time from one pass's start to the next one's:
                                         // the span plus one mean gap between datagrams
  std::vector<std::uint16_t> dst_ports;  // distinct captured destination ports
  std::string why_empty;                 // no datagram (allowed): the capture's frames by cause
};

struct ReplayReport {
  std::uint64_t packets = 0;           // datagrams sent (whole datagram accepted by the socket);
                                       // with faults: the capture's datagrams offered to them
  std::uint64_t bytes = 0;             // their payload bytes
  std::uint64_t send_failures = 0;     // send() refused or short: counted, not retried
  std::uint64_t passes = 0;            // passes whose every datagram was sent
  std::uint64_t stamps_backwards = 0;  // datagrams stamped before their predecessor: sent at once
  bool stopped = false;                // ended by the stop flag
  std::int64_t scheduled_ns = 0;       // scheduled time of the last datagram sent, from the start
  std::int64_t elapsed_ns = 0;         // measured time from the start to the last send
                                       // (the start: the first send, or the shared clock's)
  // |send time - scheduled time| over all datagrams sent, ns (median and p99 to 1 us, floor;
  // max exact). All -1 with fast.
  std::int64_t error_median_ns = -1, error_p99_ns = -1, error_max_ns = -1;
  std::optional<FaultCounts> faults;  // what the faults did (with config.faults)
};

class UdpReplay {
 public:
  // Reads the capture once to plan the replay and opens the sockets. Fails naming the file when
  // it is missing or damaged, or holds no (matching) UDP datagram, or when rate <= 0.
  static rt::Result<UdpReplay> open(const std::filesystem::path& capture,
                                    const ReplayConfig& config);

  const ReplayPlan& plan() const noexcept { return plan_; }

  // Sends the passes; returns early (stopped = true) once `stop` is set, also from a signal
  // handler (a sleeping wait is interrupted by EINTR). Fails only when the capture cannot be
  // read again. No allocation per datagram. With `shared`, datagrams are due on that clock
  // (its rate and pass period; config.rate is then unused) instead of from the first send.
  rt::Result<ReplayReport> run(const std::atomic<bool>& stop, const ReplayClock* shared = nullptr);

  // The scheduled offset of datagram `stamp_ns` in pass `pass` (ns after the first send).
  std::int64_t scheduled_ns(std::uint64_t pass, std::int64_t stamp_ns) const noexcept;

 private:
  UdpReplay() = default;
  io::UdpSender* sender_for(std::uint16_t port) noexcept;

  std::filesystem::path capture_;
  ReplayConfig config_;
  ReplayPlan plan_;
  std::vector<std::pair<std::uint16_t, io::UdpSender>> senders_;  // by destination port
  std::optional<FaultInjector> faults_;
};

}  // namespace stac::replay

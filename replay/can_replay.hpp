// A candump log's CAN frames sent as cannelloni datagrams (CAN over UDP,
// drivers/can/cannelloni.hpp) beside a capture's replay, on its clock: what a CAN-to-Ethernet
// gateway on the vehicle would send `stac run` (can.transport: cannelloni). The log's stamps are
// the capture's time (`stac sim --can` writes both on one clock), so frame and datagrams keep
// their recorded order. One frame per datagram, sequence numbers counting up. A `can-silence`
// fault (faults.hpp) sends nothing for its span: a silent bus, not a loss, so the sequence
// numbers go on without a gap.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "drivers/can/frame.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "replay/faults.hpp"
#include "replay/replay_pacing.hpp"
#include "rt/expected.hpp"

namespace stac::replay {

struct CanReplayConfig {
  std::string address = "127.0.0.1";  // destination IPv4 address
  std::uint16_t port = 20000;         // destination UDP port
  bool fast = false;                  // no pacing
  std::uint64_t loops = 1;            // passes; 0: until stopped
  TimeSpan silence;                   // can-silence: capture seconds from `origin_ns`
  std::int64_t origin_ns = 0;         // capture time 0 of the faults (the first datagram's)
};

struct CanReplayPlan {
  std::uint64_t frames = 0;         // per pass
  std::int64_t first_stamp_ns = 0;  // the log's first frame
  std::int64_t span_ns = 0;         // first to last frame
};

struct CanReplayReport {
  std::uint64_t frames = 0;         // frames sent
  std::uint64_t silenced = 0;       // frames not sent: can-silence
  std::uint64_t send_failures = 0;  // send() refused: counted, not retried
  std::uint64_t passes = 0;         // passes whose every frame was offered
  bool stopped = false;
};

class CanReplay {
 public:
  // Reads the whole log (a malformed line is an error naming file and line) and opens the socket.
  static rt::Result<CanReplay> open(const std::filesystem::path& log, const CanReplayConfig& c);

  const CanReplayPlan& plan() const noexcept { return plan_; }

  // Sends the passes on `clock` (the capture's); returns early once `stop` is set.
  CanReplayReport run(const std::atomic<bool>& stop, const ReplayClock& clock);

 private:
  CanReplay(std::vector<can::Frame> frames, io::UdpSender sender, const CanReplayConfig& c);

  std::vector<can::Frame> frames_;
  io::UdpSender sender_;
  CanReplayConfig config_;
  CanReplayPlan plan_;
};

}  // namespace stac::replay

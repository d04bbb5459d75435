#include "replay/can_replay.hpp"

#include <algorithm>
#include <array>

#include "drivers/can/candump.hpp"
#include "drivers/can/cannelloni.hpp"

namespace stac::replay {

rt::Result<CanReplay> CanReplay::open(const std::filesystem::path& log, const CanReplayConfig& c) {
  auto reader = can::CandumpReader::open(log);
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  std::vector<can::Frame> frames;
  for (can::Frame f;;) {
    auto more = reader->next(f);
    if (!more) return rt::Unexpected<rt::Error>{more.error()};
    if (!*more) break;
    frames.push_back(f);
  }
  if (frames.empty()) return rt::make_error(log.string() + ": no CAN frame to replay");
  auto sender = io::UdpSender::open(c.address, c.port);
  if (!sender) return rt::Unexpected<rt::Error>{sender.error()};
  return CanReplay(std::move(frames), std::move(*sender), c);
}

CanReplay::CanReplay(std::vector<can::Frame> frames, io::UdpSender sender, const CanReplayConfig& c)
    : frames_(std::move(frames)), sender_(std::move(sender)), config_(c) {
  plan_.frames = frames_.size();
  plan_.first_stamp_ns = frames_.front().stamp_ns;
  std::int64_t last = plan_.first_stamp_ns;
  for (const can::Frame& f : frames_) last = std::max(last, f.stamp_ns);
  plan_.span_ns = last - plan_.first_stamp_ns;
}

CanReplayReport CanReplay::run(const std::atomic<bool>& stop, const ReplayClock& clock) {
  CanReplayReport report;
  std::array<std::uint8_t, can::kCannelloniHeaderBytes + 5 + can::kMaxDataBytes> datagram{};
  std::uint8_t sequence = 0;
  for (std::uint64_t pass = 0; config_.loops == 0 || pass < config_.loops; ++pass) {
    std::int64_t last_offset = 0;
    for (const can::Frame& f : frames_) {
      if (stop.load(std::memory_order_relaxed)) {
        report.stopped = true;
        return report;
      }
      if (!config_.fast) {
        last_offset = std::max(last_offset, clock.offset_ns(pass, f.stamp_ns));
        wait_until(clock.start_ns + last_offset, stop);
        if (stop.load(std::memory_order_relaxed)) {
          report.stopped = true;
          return report;
        }
      }
      const double capture_s = static_cast<double>(f.stamp_ns - config_.origin_ns) * 1e-9;
      if (config_.silence && capture_s >= config_.silence->first &&
          capture_s < config_.silence->first + config_.silence->second) {
        ++report.silenced;
        continue;
      }
      const std::size_t n = can::encode_cannelloni({&f, 1}, sequence, datagram);
      if (n > 0 && sender_.send({datagram.data(), n})) {
        ++report.frames;
        ++sequence;
      } else {
        ++report.send_failures;
      }
    }
    ++report.passes;
  }
  return report;
}

}  // namespace stac::replay

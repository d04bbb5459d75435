#include "drivers/velodyne/scan_stream.hpp"

namespace stac::velodyne {

ScanStream::ScanStream(const Calibration& calibration, const ScanAssemblerConfig& config,
                       std::size_t slots)
    : assembler_(calibration, config),
      exchange_(slots < 2 ? 2 : slots, [&] { return Scan(scan_capacity(config)); }) {
  assembler_.begin(exchange_.current());
}

bool ScanStream::publish() noexcept {
  (void)exchange_.publish();  // on a drop the producer keeps its slot: begin() clears it
  assembler_.begin(exchange_.current());
  return true;
}

bool ScanStream::add_packet(std::span<const std::uint8_t> payload,
                            std::int64_t receive_stamp_ns) noexcept {
  const RawPacket* packet = as_packet(payload);
  const bool dual = packet != nullptr && assembler_.decoder().dual_return(*packet);
  const std::int64_t first_firing_ns = receive_stamp_ns - assembler_.decoder().packet_span_ns(dual);
  if (!assembler_.add_packet(payload, first_firing_ns)) return false;
  return publish();
}

bool ScanStream::finish() noexcept {
  if (!assembler_.flush()) return false;
  return publish();
}

}  // namespace stac::velodyne

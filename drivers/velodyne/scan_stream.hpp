// The receiver side of the data path: packets in, complete scans out through a SlotExchange of
// preallocated Scan slots (ARCHITECTURE: "decodes packets straight into the scan slot being
// filled; when the azimuth crosses the cut angle it publishes the slot to the ring").
//
//   producer thread: stream.add_packet(payload, receive_stamp_ns);   // ... stream.finish();
//   consumer thread: if (const Scan* s = stream.take()) { use(*s); stream.release(); }
//
// Stamps: sources give the time a packet was received (pcap or kernel timestamp), which is
// after its last firing; the stream subtracts the packet's firing span so that a point's time
// is its firing time (docs/velodyne.md, "Time"). When the consumer holds every slot, the newest
// scan is dropped and counted (SlotExchange policy).
#pragma once

#include <cstdint>
#include <span>

#include "drivers/velodyne/scan_assembler.hpp"
#include "rt/slot_exchange.hpp"

namespace stac::velodyne {

class ScanStream {
 public:
  // Allocates `slots` (>= 2) scans of scan_capacity(config) points: all the memory it will use.
  ScanStream(const Calibration& calibration, const ScanAssemblerConfig& config, std::size_t slots);

  // Producer: one UDP payload and the time it was received (ns). Publishes a scan when the
  // packet completes one; true then.
  bool add_packet(std::span<const std::uint8_t> payload, std::int64_t receive_stamp_ns) noexcept;
  // Producer, at the end of input: publishes the scan in progress (marked incomplete).
  bool finish() noexcept;

  // Consumer: the oldest complete scan not yet released, or nullptr. The consumer owns it until
  // release() and may change it in place (deskew).
  Scan* take() noexcept { return exchange_.take(); }
  void release() noexcept { exchange_.release(); }

  const ScanAssembler& assembler() const noexcept { return assembler_; }
  // Scans dropped because the consumer held every slot.
  [[nodiscard]] std::uint64_t scans_dropped() const noexcept { return exchange_.dropped(); }
  [[nodiscard]] std::uint64_t scans_published() const noexcept { return exchange_.published(); }

 private:
  bool publish() noexcept;

  ScanAssembler assembler_;
  rt::SlotExchange<Scan> exchange_;
};

}  // namespace stac::velodyne

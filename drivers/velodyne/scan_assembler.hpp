// Frames packets into 360-degree scans at a cut angle (never by packet count), writing points
// straight into a caller-owned Scan. Robust to RPM drift (300-1200), loss (counted as gaps),
// duplicates (dropped, counted) and reordering (late firings of a closed scan dropped, counted).
//
//   ScanAssembler a(calibration, config);
//   a.begin(slot);
//   for each packet: if (a.add_packet(payload, stamp_ns)) { publish(slot); a.begin(next slot); }
//   if (a.flush()) publish(slot);   // end of input: the scan in progress, marked incomplete
//
// A completed scan must be taken (begin() called) before the next add_packet(); the firings of
// the packet that fall after the cut are carried into the scan given to begin().
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "drivers/velodyne/decoder.hpp"
#include "drivers/velodyne/scan.hpp"
#include "drivers/velodyne/status.hpp"

namespace stac::velodyne {

struct ScanAssemblerConfig {
  DecoderConfig decoder;
  std::uint16_t cut_angle = 0;       // 0.01 deg; a scan starts at the firing that crosses it
  double min_rpm = 300.0;            // sizes the scan capacity (slowest = most points)
  double max_gap_s = 0.05;           // silence longer than this closes the scan in progress
  double max_scan_duration_s = 0.3;  // a scan longer than this is closed (sensor not turning)
  // A scan whose packets arrived for less than this fraction (the rest lost on the wire,
  // estimated from azimuth steps) is not complete: not processed, counted.
  double min_completeness = 0.9;
  // The model was taken from the capture's own packets (velodyne.model: auto, offline): a packet
  // whose bytes name another model STAC knows is then another sensor's, and is dropped and counted
  // (other_model_dropped) rather than decoded as the first one's lasers. Off: decoded as
  // configured and counted (model_mismatch), as the bytes are not always true.
  bool drop_other_models = false;
};

struct AssemblerCounters {
  std::uint64_t packets = 0;              // payloads offered
  std::uint64_t wrong_size = 0;           // not 1206 bytes: dropped
  std::uint64_t model_mismatch = 0;       // their bytes name another model (PacketIdentity): see
                                          // last_identity(); decoded as the configured model...
  std::uint64_t other_model_dropped = 0;  // ...but for these: dropped (drop_other_models)
  std::uint64_t invalid_block = 0;        // bad bank id, rotation >= 36000, or rotations that jump
                                          // between its blocks (over 3 deg): packet dropped
  std::uint64_t duplicates = 0;           // identical to one of the last 16 packets: dropped
  std::uint64_t late_firings = 0;         // reordered firings belonging to an already closed scan
  std::uint64_t packets_lost = 0;         // estimated from azimuth steps
  std::uint64_t time_gaps = 0;            // scans closed by silence or a clock jump
  std::uint64_t timeouts = 0;             // scans closed by max_scan_duration_s
  std::uint64_t points_dropped = 0;       // returns beyond a scan's capacity
  std::uint64_t scans = 0;                // scans closed
  std::uint64_t below_completeness = 0;   // scans closed with too many packets lost
};

// Points a scan must hold at the slowest configured rotation, with 10% margin.
std::size_t scan_capacity(const ScanAssemblerConfig& config) noexcept;

class ScanAssembler {
 public:
  ScanAssembler(const Calibration& calibration, const ScanAssemblerConfig& config);

  // Takes `scan` as the output; its previous content is discarded.
  void begin(Scan& scan) noexcept;
  // Decodes one UDP payload whose first firing happened at `stamp_ns`; true when it closed
  // the current scan (which is then complete and must be taken before the next call).
  [[nodiscard]] bool add_packet(std::span<const std::uint8_t> payload,
                                std::int64_t stamp_ns) noexcept;
  // Closes the scan in progress at the end of input; true when it held any point.
  [[nodiscard]] bool flush() noexcept;

  const AssemblerCounters& counters() const noexcept { return counters_; }
  const DecodeCounters& decode_counters() const noexcept { return decoder_.counters(); }
  const PacketDecoder& decoder() const noexcept { return decoder_; }
  // The S2.1/S3 status cycle of the accepted packets (GPS time, temperature, calibration dump).
  const StatusDecoder& status() const noexcept { return status_; }
  // What the bytes of the last packet that disagreed with the configured model said.
  const PacketIdentity& last_identity() const noexcept { return last_identity_; }
  // The 6 trailer bytes of the last accepted packet (see packet.hpp for both kinds).
  const std::array<std::uint8_t, 6>& last_trailer() const noexcept { return last_trailer_; }

 private:
  struct Target {
    ScanHeader* header = nullptr;
    rt::FixedVector<Point>* points = nullptr;
    bool open = false;
    std::uint64_t epoch = 0;  // which opening of this target: tells one scan from the next
  };
  struct Gap {  // the last azimuth gap counted as lost packets
    std::uint16_t from = 0, to = 0;
    std::uint32_t open = 0;  // lost packets not yet seen arriving late
    const Target* target = nullptr;
    std::uint64_t epoch = 0;
  };
  void open(Target& t, std::int64_t stamp_ns, std::uint16_t rotation, bool at_cut,
            std::uint32_t device_usec, std::int32_t firing_in_packet_ns, bool dual) noexcept;
  void close(bool at_cut) noexcept;
  bool is_duplicate(std::span<const std::uint8_t> payload) noexcept;
  // The steps of add_packet, in order.
  bool accept(const RawPacket& packet, std::span<const std::uint8_t> payload) noexcept;
  std::uint32_t read_trailer(const RawPacket& packet) noexcept;
  bool close_stale(std::int64_t stamp_ns) noexcept;
  void estimate_loss(std::uint16_t r0) noexcept;
  bool write_firings(const RawPacket& packet, std::int64_t stamp_ns, std::uint32_t device_usec,
                     bool dual) noexcept;
  bool frame_firing(std::int64_t t, std::uint16_t r, std::uint32_t device_usec, std::int32_t firing,
                    bool dual, bool& completed) noexcept;
  void decode_firing(const RawPacket& packet, int first, int group, std::int64_t stamp_ns,
                     bool dual, int azimuth_step) noexcept;

  ScanAssemblerConfig config_;
  PacketDecoder decoder_;
  StatusDecoder status_;
  std::int64_t max_gap_ns_;
  std::int64_t max_duration_ns_;
  Scan* scan_ = nullptr;
  Target current_;  // the caller's scan
  Target carry_;    // firings after a cut, waiting for the next begin()
  Target* target_ = &current_;
  ScanHeader carry_header_;
  rt::FixedVector<Point> carry_points_;
  bool have_prev_ = false;
  std::uint16_t prev_rotation_ = 0;         // last forward firing rotation
  std::uint16_t prev_packet_rotation_ = 0;  // first rotation of the last packet
  std::int64_t prev_stamp_ns_ = 0;
  double step_ema_ = 0.0;  // usual azimuth step between packets
  std::uint64_t next_sequence_ = 0;
  std::uint64_t epochs_ = 0;
  Gap gap_;
  std::array<std::uint64_t, 16> recent_{};
  std::size_t recent_next_ = 0;
  std::array<std::uint8_t, 6> last_trailer_{};
  PacketIdentity last_identity_;
  AssemblerCounters counters_;
};

}  // namespace stac::velodyne

// Point math of one data block: the ros-drivers/velodyne formulas (REFERENCE §1) evaluated from
// tables built once at start-up. No allocation, no exceptions, no I/O.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/packet.hpp"
#include "drivers/velodyne/point.hpp"

namespace stac::velodyne {

struct DecoderConfig {
  Model model = Model::kS2;
  float min_range_m = 0.9f;    // returns closer than this (after correction) are dropped
  float max_range_m = 130.0f;  // and farther than this
  // Two-point correction only below 25.04 m, where the ROS formula's correction reaches zero;
  // ROS extrapolates it beyond (ros-drivers/velodyne #109). Off = exactly the ROS math.
  bool gate_two_point_correction = false;
  // Focal distance in the intensity correction: false = centimetres, as the formula expects
  // (256 (1 - fd/13100)^2); true = metres as ROS passes it from its yaml (#499).
  bool ros_intensity_units = false;
};

struct DecodeCounters {
  std::uint64_t no_return = 0;         // raw distance 0
  std::uint64_t out_of_range = 0;      // outside [min_range_m, max_range_m]
  std::uint64_t disabled = 0;          // laser disabled in the calibration
  std::uint64_t invalid_rotation = 0;  // block rotation >= 36000: block skipped
};

class PacketDecoder {
 public:
  PacketDecoder(const Calibration& calibration, const DecoderConfig& config);

  // Decodes block `block_index` of a packet whose first firing is at `packet_offset_ns`
  // relative to the scan stamp. Writes at most 32 points to `out`; returns how many.
  int decode_block(const RawBlock& block, int block_index, bool dual_return,
                   std::int64_t packet_offset_ns, Point* out) noexcept;

  // Firing time of block `block_index`, laser j (0..31) relative to the packet's first firing.
  std::int32_t firing_offset_ns(int block_index, int j, bool dual_return) const noexcept {
    return firing_ns_[dual_return ? 1 : 0][static_cast<std::size_t>(block_index)]
                     [static_cast<std::size_t>(j)];
  }
  // Time from the first to the last firing of a packet.
  std::int32_t packet_span_ns(bool dual_return) const noexcept {
    return firing_offset_ns(kBlocksPerPacket - 1, kLasersPerBlock - 1, dual_return);
  }
  const ModelTraits& model() const noexcept { return *traits_; }
  const DecodeCounters& counters() const noexcept { return counters_; }
  int ring_of(int laser) const noexcept { return lasers_.ring[laser]; }

 private:
  // Per-laser constants as structure-of-arrays, so the 32 returns of a block are corrected in
  // one branch-free loop the compiler vectorises; invalid returns are dropped afterwards.
  struct LaserTables {
    alignas(64) float cos_vert[kMaxLasers], sin_vert[kMaxLasers];
    alignas(64) float cos_rot[kMaxLasers], sin_rot[kMaxLasers];
    alignas(64) float dist[kMaxLasers], dist_x[kMaxLasers], dist_y[kMaxLasers];
    alignas(64) float vert_offset[kMaxLasers], horiz_offset[kMaxLasers];
    alignas(64) float two_pt[kMaxLasers];  // 1 when the two-point correction applies, else 0
    alignas(64) float focal_offset[kMaxLasers], focal_slope[kMaxLasers];
    alignas(64) float min_intensity[kMaxLasers], max_intensity[kMaxLasers];
    bool enabled[kMaxLasers];
    std::uint8_t ring[kMaxLasers];
  };
  const ModelTraits* traits_;
  DecoderConfig config_;
  float resolution_m_;
  LaserTables lasers_{};
  std::vector<float> cos_table_, sin_table_;  // by raw rotation, 36000 entries, built once
  std::array<std::array<std::array<std::int32_t, kLasersPerBlock>, kBlocksPerPacket>, 2>
      firing_ns_{};
  DecodeCounters counters_;
};

}  // namespace stac::velodyne

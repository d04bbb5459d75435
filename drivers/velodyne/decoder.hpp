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
  // `azimuth_step`: rotation (0.01 deg) from this block's firing to the next one, for the models
  // whose later firings in a block are placed by interpolation (VLP-16: the second sequence);
  // ignored by the others.
  int decode_block(const RawBlock& block, int block_index, bool dual_return,
                   std::int64_t packet_offset_ns, Point* out, int azimuth_step = 0) noexcept;

  // Firing time of block `block_index`, laser j (0..31) relative to the packet's first firing.
  std::int32_t firing_offset_ns(int block_index, int j, bool dual_return) const noexcept {
    return firing_ns_[dual_return ? 1 : 0][static_cast<std::size_t>(block_index)]
                     [static_cast<std::size_t>(j)];
  }
  // Time from the first to the last firing of a packet.
  std::int32_t packet_span_ns(bool dual_return) const noexcept {
    return firing_offset_ns(kBlocksPerPacket - 1, kLasersPerBlock - 1, dual_return);
  }
  // Blocks fired at once (sharing a rotation): 2 or 4 (dual) for an HDL-64E, else 1 or 2.
  int blocks_per_firing(bool dual_return) const noexcept {
    return (traits_->layout == Layout::kBankPairs ? 2 : 1) * (dual_return ? 2 : 1);
  }
  ReturnType return_type(int block_index, bool dual_return) const noexcept;
  // Whether a packet of this model is in dual-return mode.
  bool dual_return(const RawPacket& packet) const noexcept {
    return is_dual_return(packet, traits_->supports_dual_return,
                          traits_->trailer == TrailerKind::kFactory);
  }
  const ModelTraits& model() const noexcept { return *traits_; }
  Model model_id() const noexcept { return config_.model; }
  const DecodeCounters& counters() const noexcept { return counters_; }
  int ring_of(int laser) const noexcept { return ring_by_laser_[static_cast<std::size_t>(laser)]; }

 private:
  // Per-channel constants as structure-of-arrays, so the 32 returns of a block are corrected in
  // one branch-free loop the compiler vectorises; invalid returns are dropped afterwards. Slot
  // = the channel's laser for an HDL-64E (bank * 32 + channel); the channel (0..31) for the
  // others, holding its laser's constants (a VLP-16's lasers twice).
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
    std::uint8_t laser[kMaxLasers];
  };
  const ModelTraits* traits_;
  DecoderConfig config_;
  float resolution_m_;
  LaserTables lasers_{};
  std::array<std::uint8_t, kMaxLasers> ring_by_laser_{};
  bool interpolates_ = false;                 // some channel's azimuth is interpolated (VLP-16)
  std::vector<float> cos_table_, sin_table_;  // by raw rotation, 36000 entries, built once
  std::array<std::array<std::array<std::int32_t, kLasersPerBlock>, kBlocksPerPacket>, 2>
      firing_ns_{};
  std::array<std::array<std::array<float, kLasersPerBlock>, kBlocksPerPacket>, 2> fraction_{};
  DecodeCounters counters_;
};

}  // namespace stac::velodyne

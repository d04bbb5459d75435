// A virtual Velodyne (HDL-64E, HDL-32E, VLP-16, VLP-32C: velodyne::Layout): every laser is cast at
// its real firing time (REFERENCE §1 timing) from the moving ego, along the decoder's own beam line
// (drivers/velodyne/beam.hpp), so decoding the packets gives back every hit within the 2 mm
// quantisation before noise. Adds range noise, intensity from reflectivity, incidence and distance,
// and missing returns (too far, too dark, grazing). Deterministic: every random draw is a hash of
// (seed, packet, block, laser).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "drivers/velodyne/beam.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/packet.hpp"
#include "sim/world.hpp"

namespace stac::sim {

// The ego's own body as the sensor sees it, in the ego frame (x forward, y left, z up from the
// ground under the ego origin): the bonnet, boot and sides as one box over the whole footprint
// up to `bonnet_height_m`, and the roof (cabin) under the sensor. Beams that meet it give no
// return (a real HDL-64E's returns off its own car are dropped by the driver's body filter).
// Default: a 4.6 x 1.9 m car; bonnet height and the roof's size fitted to the points per ring of
// the lowest ten rings of the KITTI scans
// (docs/simulator.md).
struct EgoBody {
  bool enabled = true;
  double length_m = 4.6, width_m = 1.9;  // footprint centred on the ego origin
  double bottom_m = 0.25;                // underside above the ground
  double bonnet_height_m = 0.90;         // top of bonnet and boot above the ground
  double roof_below_sensor_m = 0.20;     // roof top, below the sensor origin
  double roof_front_m = 0.5, roof_back_m = 0.9, roof_half_width_m = 0.5;  // from the ego origin
};

struct LidarConfig {
  velodyne::Model model = velodyne::Model::kS2_1;
  double rpm = 600.0;
  double start_azimuth_deg = 0.0;
  bool dual_return = false;      // S3, HDL-32E, VLP-16, VLP-32C
  double mount_height_m = 1.73;  // sensor origin above the ground under the ego origin
  double range_noise_m = 0.012;  // 1 sigma (HDL-64E: < 2 cm)
  double max_range_m = 120.0;    // for a white target; dark ones are lost sooner
  double dropout = 0.004;        // returns lost at random
  EgoBody body;
  std::uint64_t seed = 1;
};

// The ego vehicle: where it is, its attitude follows the ground under it.
struct EgoState {
  double x = 0, y = 0, z = 0, roll = 0, pitch = 0, yaw = 0;  // world frame, rad
  double speed = 0, yaw_rate = 0;                            // m/s, rad/s
};

// What happened to one beam, for truth and tests.
struct BeamRecord {
  std::uint32_t packet;
  // Block 0..11 of the echo described here (the one single-return mode gives: in dual return
  // the strongest block, or the last-return block when it is the farther of two), laser 0..63.
  std::uint8_t block, laser;
  std::uint16_t rotation;        // 0.01 deg, of this beam (VLP-16: interpolated within the block)
  std::uint8_t channel;          // 0..31 within the block
  std::uint16_t block_rotation;  // the block's rotation, by which scans are framed
  std::int64_t actor;            // -1 ground, -2 nothing hit
  double time_s;                 // firing time
  double sensor_xyz[3];          // exact hit in the sensor frame at firing time, before noise
  double world_xyz[3];
  bool returned;  // a return was written (not lost, in range)
};

class LidarSim {
 public:
  using EgoFn = std::function<EgoState(double)>;
  LidarSim(const velodyne::Calibration& calibration, const LidarConfig& config, const World& world,
           EgoFn ego);

  // Packet k of the run: its 1206 bytes (trailer GPS time left for the caller) and the time of
  // its first firing (s from the start). Calls `record` for every beam when set.
  void make_packet(std::uint32_t k, std::array<std::uint8_t, velodyne::kPacketSize>& bytes,
                   double& first_firing_s, const std::function<void(const BeamRecord&)>& record);

  double packets_per_second() const noexcept;
  // Azimuth of the firing at time t (0.01 deg).
  std::uint16_t rotation_at(double t) const noexcept;

 private:
  void refresh_candidates(double t);
  bool hits_body(const velodyne::BeamLine& line) const;  // line in the sensor frame
  // The steps of make_packet (lidar.cpp).
  struct PacketContext;
  struct Beam;
  struct Echo;
  void firing_rotations(const PacketContext& p, int firings,
                        std::array<std::uint16_t, velodyne::kBlocksPerPacket>& rotation,
                        std::array<int, velodyne::kBlocksPerPacket>& step) const noexcept;
  void fire(const PacketContext& p, int firing, std::uint16_t block_rotation, int azimuth_step);
  void cast(const PacketContext& p, const Beam& b, BeamRecord& rec);
  void cast_second(const PacketContext& p, const Beam& b, const Echo& main, double raw,
                   std::uint8_t intensity, BeamRecord& rec);
  Echo trace(const Beam& b, int through, double yaw_offset);

  velodyne::Calibration calibration_;
  velodyne::BeamModel beams_;
  LidarConfig config_;
  const World& world_;
  World::PoseCache poses_;
  EgoFn ego_;
  std::array<std::array<double, 32>, 12> firing_offset_s_{};  // [block][laser in block]
  // Actors that may be hit, by 1-degree world azimuth bin around the sensor, for a window.
  std::array<std::vector<std::uint32_t>, 360> bins_;
  double window_start_ = -1.0, window_end_ = -1.0;
};

}  // namespace stac::sim

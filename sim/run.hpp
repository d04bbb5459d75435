// One simulated drive: HDL-64E packets (as the sensor sends them) and ground truth per scan,
// framed by the same cut-angle rule as the driver's ScanAssembler.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/velodyne/calibration.hpp"
#include "sim/lidar.hpp"
#include "sim/scenario.hpp"

namespace stac::sim {

struct RunConfig {
  std::string scenario = "urban";
  std::uint64_t seed = 1;
  double duration_s = 10.0;
  LidarConfig lidar;
  std::uint16_t cut_angle = 0;                        // 0.01 deg, as the driver's config
  std::int64_t start_ns = 1'767'268'800'000'000'000;  // 2026-01-01 12:00:00 UTC
  // Kinds left out of the scenario (`stac sim --without pole`: a street known to hold none, the
  // background set of a class being taught); the rest of the world is the same.
  std::vector<ObjectClass> without;
};

struct TruthObject {
  std::uint32_t id;
  ObjectClass cls;
  double x, y, z, length, width, height, yaw;  // box centre and size, world frame
  double vx, vy;
  std::uint32_t points;  // returns written for it in this scan
  double time_s;         // when the sweep passed it (mean firing time of its hits)
};

struct TruthScan {
  std::uint64_t scan = 0;
  std::int64_t start_ns = 0, end_ns = 0;  // first and last firing
  EgoState ego;                           // at the first firing
  std::vector<TruthObject> objects;
  std::uint32_t points = 0, ground_points = 0;
};

// One JSON line. With `origin` (the world's geodetic anchor: lat, lon in deg, alt in m), the line
// says it, so the world frame of the truth can be rebuilt from the INS stream.
std::string to_json(const TruthScan& scan, const double* origin_lat_lon_alt = nullptr);

class SimRun {
 public:
  static rt::Result<std::unique_ptr<SimRun>> create(const velodyne::Calibration& calibration,
                                                    const RunConfig& config);

  std::uint32_t packet_count() const noexcept;
  // Packet k: bytes, absolute first-firing time (ns). Calls `on_scan` when packet k closed a
  // scan (the truth of the scan before it), and `on_beam` for every beam when set.
  void packet(std::uint32_t k, std::array<std::uint8_t, velodyne::kPacketSize>& bytes,
              std::int64_t& first_firing_ns, const std::function<void(const TruthScan&)>& on_scan,
              const std::function<void(const BeamRecord&)>& on_beam = {});
  // The scan in progress at the end (incomplete), for the caller to write if it wants.
  bool finish(const std::function<void(const TruthScan&)>& on_scan);

  const World& world() const noexcept { return *world_; }
  const Scenario& scenario() const noexcept { return scenario_; }
  EgoState ego(double t) const { return ego_state(*world_, scenario_.ego_path, t); }

 private:
  SimRun() = default;
  void close_scan(const std::function<void(const TruthScan&)>& on_scan);

  RunConfig config_;
  Scenario scenario_;
  std::unique_ptr<World> world_;
  std::unique_ptr<LidarSim> lidar_;
  // Truth of the scan being framed.
  bool open_ = false;
  bool have_prev_ = false;
  std::uint16_t prev_rotation_ = 0;
  TruthScan current_;
  std::vector<std::uint32_t> hits_;   // per actor
  std::vector<double> hit_time_sum_;  // per actor
  std::uint64_t next_scan_ = 0;
};

}  // namespace stac::sim

// The ego poses of a whole capture, for offline jobs (`stac process`): every Applanix message in
// the pcap (TCP from, or UDP to, the configured INS port) goes through the EgoEstimator into a
// PoseHistory sized to hold the whole drive (allocated once, before the per-scan loop).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>

#include "ego/ego_estimator.hpp"
#include "rt/expected.hpp"
#include "settings/settings.hpp"

namespace stac::formats {

struct CapturePoses {
  std::unique_ptr<ego::LocalFrame> frame;
  std::unique_ptr<ego::PoseHistory> history;
  ego::EgoCounters counters;
  applanix::ParserCounters parser;  // the INS stream's messages dropped, by cause
  std::uint64_t group1 = 0;         // Group 1 messages in the capture (OXTS records of a drive)
  std::string mounting;             // a KITTI drive's: where the sensor's mounting came from
};

// Empty (no error) when the capture holds no Group 1 on the port: a parked sensor, identity pose.
// An error when it holds none but messages dropped for bad checksums or framing: the INS stream
// is there but corrupt, which must not pass for a parked sensor.
rt::Result<std::optional<CapturePoses>> load_capture_poses(const std::filesystem::path& capture,
                                                           const settings::EgoSettings& settings);

// The poses of a KITTI raw drive folder from its OXTS records (DIR/oxts; formats/kitti_raw.hpp),
// through the same EgoEstimator (local frame, time jumps); `group1` counts the records. The IMU's
// frame is the vehicle's: the drive's calib_imu_to_velo.txt (find_kitti_imu_to_velo) becomes
// settings.deskew.vehicle_T_sensor, else the config's stays; `mounting` says which.
rt::Result<CapturePoses> load_kitti_raw_poses(const std::filesystem::path& drive,
                                              settings::EgoSettings& settings);

}  // namespace stac::formats

// Deskew: every point of a scan is moved to where it was seen from the sensor at ONE instant,
// the scan's last firing, using the pose at its own firing time (Apollo compensator.cc: linear
// position, slerp attitude). The scan also gets its world pose at that instant, for tracking.
//
// Points are grouped by firing time into buckets of `bucket_ns` that share one transform
// (100 us: at 30 m/s and 30 deg/s the largest error is 1.5 mm + 0.0015 deg). The table is sized
// once from max_scan_duration_s; apply() allocates nothing, throws nothing.
#pragma once

#include <cstdint>
#include <vector>

#include "drivers/velodyne/scan.hpp"
#include "ego/pose_history.hpp"

namespace stac::ego {

struct DeskewConfig {
  Eigen::Isometry3d vehicle_T_sensor = Eigen::Isometry3d::Identity();  // extrinsics
  std::int64_t bucket_ns = 100'000;  // firings this close share a transform
  double max_scan_duration_s = 0.3;  // sizes the transform table (as the assembler's limit)
};

struct DeskewResult {
  PoseStatus status = PoseStatus::kEmpty;  // of the pose at the reference time; not ok: the
                                           // points are left as they were
  std::int64_t reference_ns = 0;           // pose clock: the scan's last firing
  Eigen::Isometry3d world_T_sensor = Eigen::Isometry3d::Identity();  // at reference_ns
  std::uint32_t points_without_pose = 0;  // firing time without a usable pose: left in place
  [[nodiscard]] bool ok() const noexcept {
    return status == PoseStatus::kInterpolated || status == PoseStatus::kExtrapolated;
  }
};

class Deskewer {
 public:
  explicit Deskewer(const DeskewConfig& config);

  // `scan_to_pose_ns` is added to the scan's stamps to read the pose history (see
  // ego/time_sync.hpp for where it comes from; 0 when both share a clock).
  DeskewResult apply(velodyne::Scan& scan, const PoseHistory& poses,
                     std::int64_t scan_to_pose_ns) noexcept;

 private:
  struct Bucket {
    Eigen::Matrix3f rotation;
    Eigen::Vector3f translation;
    std::uint8_t state = 0;  // 0 not computed, 1 usable, 2 no pose
  };
  DeskewConfig config_;
  std::vector<Bucket> buckets_;
};

}  // namespace stac::ego

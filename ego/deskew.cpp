#include "ego/deskew.hpp"

#include <cmath>

namespace stac::ego {

Deskewer::Deskewer(const DeskewConfig& config) : config_(config) {
  if (config_.bucket_ns <= 0) config_.bucket_ns = 100'000;
  const auto n = static_cast<std::size_t>(std::ceil(config_.max_scan_duration_s * 1e9 /
                                                    static_cast<double>(config_.bucket_ns))) +
                 2;
  buckets_.resize(n);
}

DeskewResult Deskewer::apply(velodyne::Scan& scan, const PoseHistory& poses,
                             std::int64_t scan_to_pose_ns) noexcept {
  DeskewResult result;
  const velodyne::ScanHeader& h = scan.header;
  result.reference_ns = h.end_stamp_ns + scan_to_pose_ns;
  const PoseLookup ref = poses.at(result.reference_ns);
  result.status = ref.status;
  if (!ref.ok()) return result;
  result.world_T_sensor = to_isometry(ref.pose) * config_.vehicle_T_sensor;
  const Eigen::Isometry3d ref_T_world = result.world_T_sensor.inverse();

  for (Bucket& b : buckets_) b.state = 0;
  const std::int64_t base = h.stamp_ns + scan_to_pose_ns;
  for (velodyne::Point& p : scan.points) {
    const std::int64_t index = p.time_offset_ns / config_.bucket_ns;
    if (index < 0 || static_cast<std::size_t>(index) >= buckets_.size()) {
      ++result.points_without_pose;
      continue;
    }
    Bucket& b = buckets_[static_cast<std::size_t>(index)];
    if (b.state == 0) {
      const PoseLookup at = poses.at(base + index * config_.bucket_ns + config_.bucket_ns / 2);
      b.state = at.ok() ? 1 : 2;
      if (at.ok()) {
        const Eigen::Isometry3d ref_T_sensor =
            ref_T_world * to_isometry(at.pose) * config_.vehicle_T_sensor;
        b.rotation = ref_T_sensor.linear().cast<float>();
        b.translation = ref_T_sensor.translation().cast<float>();
      }
    }
    if (b.state != 1) {
      ++result.points_without_pose;
      continue;
    }
    const Eigen::Vector3f q = b.rotation * Eigen::Vector3f(p.x, p.y, p.z) + b.translation;
    p.x = q.x();
    p.y = q.y();
    p.z = q.z();
  }
  return result;
}

}  // namespace stac::ego

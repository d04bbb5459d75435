#include "evaluation/tracklet_truth.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ego/pose.hpp"
#include "formats/capture_poses.hpp"
#include "formats/kitti_raw.hpp"
#include "formats/kitti_tracklets.hpp"

namespace stac::evaluation {

namespace {

// Points of the scan inside a tracklet's box (sensor frame: bottom centre, yaw about z).
std::uint32_t points_in_box(const velodyne::Scan& scan, const formats::TrackletPose& p,
                            const formats::Tracklet& t) {
  const double c = std::cos(p.rz), s = std::sin(p.rz);
  std::uint32_t n = 0;
  for (const velodyne::Point& q : scan.points) {
    const double dx = q.x - p.tx, dy = q.y - p.ty, dz = q.z - p.tz;
    const double along = c * dx + s * dy, across = -s * dx + c * dy;
    n += std::abs(along) <= t.l / 2 && std::abs(across) <= t.w / 2 && dz >= 0 && dz <= t.h ? 1 : 0;
  }
  return n;
}

}  // namespace

rt::Result<std::vector<TruthScanRecord>> truth_from_tracklets(const std::filesystem::path& file,
                                                              const std::filesystem::path& dir,
                                                              settings::EgoSettings ego) {
  auto tracklets = formats::read_kitti_tracklets(file);
  if (!tracklets) return rt::Unexpected<rt::Error>{tracklets.error()};
  auto drive = formats::open_kitti_raw_drive(dir);
  if (!drive) return rt::Unexpected<rt::Error>{drive.error()};
  if (!drive->has_oxts)
    return rt::make_error(dir.string() +
                          " has no oxts/: its poses are needed to place the labels in the world");
  auto poses = formats::load_kitti_raw_poses(dir, ego);  // sets the mounting
  if (!poses) return rt::Unexpected<rt::Error>{poses.error()};
  const Eigen::Isometry3d vehicle_T_sensor = ego.deskew.vehicle_T_sensor;
  const ego::Geodetic origin = poses->frame->origin();
  const std::size_t frames = drive->scans.size();

  std::vector<TruthScanRecord> out(frames);
  std::vector<Eigen::Isometry3d> world_T_sensor(frames, Eigen::Isometry3d::Identity());
  std::vector<bool> posed(frames, false);
  for (std::size_t f = 0; f < frames; ++f) {
    TruthScanRecord& r = out[f];
    r.origin = std::array<double, 3>{origin.lat_deg, origin.lon_deg, origin.alt_m};
    r.scan = f;
    // The sweep the scan was fired in (a deskewed scan is stamped at its start), else the one
    // instant of the scan; the labels and the ego at the frame's time (facing forward).
    const bool sweeps = !drive->sweep_start_ns.empty();
    r.stamp_ns = sweeps ? drive->sweep_start_ns[f] : drive->stamps_ns[f];
    r.end_stamp_ns = sweeps ? drive->sweep_end_ns[f] : drive->stamps_ns[f];
    const ego::PoseLookup at = poses->history->at(drive->stamps_ns[f]);
    if (!at.ok()) continue;
    posed[f] = true;
    const Eigen::Isometry3d world_T_vehicle = ego::to_isometry(at.pose);
    world_T_sensor[f] = world_T_vehicle * vehicle_T_sensor;
    const Eigen::Vector3d p = world_T_vehicle.translation();
    r.ego = {p.x(), p.y(), p.z(),
             std::atan2(world_T_vehicle.linear()(1, 0), world_T_vehicle.linear()(0, 0))};
  }

  // Each box's points are counted after every box is placed, a frame at a time: one read of each
  // scan (reading a frame for every tracklet in it took 20 s on a one-minute drive).
  struct Unread {
    std::size_t frame, object, tracklet, pose;
  };
  std::vector<Unread> unread;
  for (std::size_t k = 0; k < tracklets->size(); ++k) {
    const formats::Tracklet& t = (*tracklets)[k];
    const std::string cls(formats::stac_class_of_kitti_type(t.object_type));
    if (cls.empty()) continue;                                // Misc, DontCare
    std::vector<std::pair<std::size_t, std::size_t>> placed;  // (frame, index in its objects)
    for (std::size_t i = 0; i < t.poses.size(); ++i) {
      const std::size_t f = t.first_frame + i;
      if (f >= frames)
        return rt::make_error(file.string() + ": tracklet " + std::to_string(k) +
                              " has a pose for frame " + std::to_string(f) + "; the drive has " +
                              std::to_string(frames) + " scans");
      if (!posed[f]) continue;
      const formats::TrackletPose& p = t.poses[i];
      const Eigen::Vector3d centre =
          world_T_sensor[f] * Eigen::Vector3d(p.tx, p.ty, p.tz + t.h / 2);
      const Eigen::Vector3d heading =
          world_T_sensor[f].linear() * Eigen::Vector3d(std::cos(p.rz), std::sin(p.rz), 0);
      TruthObjectRecord o;
      o.id = static_cast<std::uint32_t>(k + 1);
      o.cls = cls;
      o.x = centre.x(), o.y = centre.y(), o.z = centre.z();
      o.length = t.l, o.width = t.w, o.height = t.h;
      o.yaw = std::atan2(heading.y(), heading.x());
      unread.push_back({f, out[f].objects.size(), k, i});
      placed.emplace_back(f, out[f].objects.size());
      out[f].objects.push_back(o);
    }
    // Velocity from the neighbouring frames (one-sided at the ends), over the frames' times, at
    // which the boxes are (not the sweeps' starts the truth scans are stamped with).
    for (std::size_t j = 0; j < placed.size() && placed.size() > 1; ++j) {
      const auto& [fa, ia] = placed[j == 0 ? 0 : j - 1];
      const auto& [fb, ib] = placed[j + 1 == placed.size() ? j : j + 1];
      const double dt = static_cast<double>(drive->stamps_ns[fb] - drive->stamps_ns[fa]) * 1e-9;
      if (!(dt > 0)) continue;
      TruthObjectRecord& o = out[placed[j].first].objects[placed[j].second];
      o.vx = (out[fb].objects[ib].x - out[fa].objects[ia].x) / dt;
      o.vy = (out[fb].objects[ib].y - out[fa].objects[ia].y) / dt;
    }
  }
  std::stable_sort(unread.begin(), unread.end(),
                   [](const Unread& a, const Unread& b) { return a.frame < b.frame; });
  velodyne::Scan scan(drive->max_points);
  std::size_t loaded = frames;  // the frame whose points `scan` holds
  for (const Unread& u : unread) {
    if (loaded != u.frame) {
      auto c = formats::load_kitti_raw_scan(drive->scans[u.frame], u.frame,
                                            drive->stamps_ns[u.frame], scan);
      if (!c) return rt::Unexpected<rt::Error>{c.error()};
      loaded = u.frame;
    }
    const formats::Tracklet& t = (*tracklets)[u.tracklet];
    out[u.frame].objects[u.object].points = points_in_box(scan, t.poses[u.pose], t);
  }
  std::erase_if(out, [&](const TruthScanRecord& r) { return !posed[r.scan]; });
  return out;
}

}  // namespace stac::evaluation

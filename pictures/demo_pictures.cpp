#include "pictures/demo_pictures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <set>
#include <string_view>

#include "pictures/birds_eye.hpp"

namespace stac::pictures {
namespace {

// World (m) into the frame of the vehicle's last pose.
struct ToVehicle {
  float x0, y0, c, s, yaw;
  ToVehicle(const DriveView& v)
      : x0(v.ego_x), y0(v.ego_y), c(std::cos(v.ego_yaw)), s(std::sin(v.ego_yaw)), yaw(v.ego_yaw) {}
  [[nodiscard]] PointM operator()(float x, float y) const {
    const float dx = x - x0, dy = y - y0;
    return {c * dx + s * dy, -s * dx + c * dy};
  }
};

// A colour per track id, spread around the hue circle (BGR).
Bgr track_colour(std::uint64_t id) {
  const double h = std::fmod(static_cast<double>(id) * 0.61803398875, 1.0) * 6.0;
  const int i = static_cast<int>(h);
  const double f = h - i;
  const double q = 1 - f;
  const double rgb[6][3] = {{1, f, 0}, {q, 1, 0}, {0, 1, f}, {0, q, 1}, {f, 0, 1}, {1, 0, q}};
  const auto& c = rgb[std::clamp(i, 0, 5)];
  return {cv::saturate_cast<std::uint8_t>(60 + 195 * c[2]),
          cv::saturate_cast<std::uint8_t>(60 + 195 * c[1]),
          cv::saturate_cast<std::uint8_t>(60 + 195 * c[0])};
}

std::vector<PointM> in_vehicle(const std::vector<PointM>& world, const ToVehicle& to) {
  std::vector<PointM> out;
  out.reserve(world.size());
  for (const PointM& p : world) out.push_back(to(p.x, p.y));
  return out;
}

}  // namespace

rt::Status draw_drive(const DriveView& v, DrivePicture picture, const std::filesystem::path& png) {
  const ToVehicle to(v);
  BirdsEyeOptions o;
  o.height_bar = false;
  o.size_px = 1000;
  o.range_m = 40;
  o.z_min_m = -0.5;  // vehicle frame: the road at about 0
  o.z_max_m = 3.0;
  double centre_x = 0, centre_y = 0;
  if (picture == DrivePicture::kWholeDrive) {  // the extent of the vehicle's path, with a margin
    float x_min = 0, x_max = 0, y_min = 0, y_max = 0;
    for (const PointM& p : in_vehicle(v.ego_path, to)) {
      x_min = std::min(x_min, p.x), x_max = std::max(x_max, p.x);
      y_min = std::min(y_min, p.y), y_max = std::max(y_max, p.y);
    }
    centre_x = (x_min + x_max) / 2.0, centre_y = (y_min + y_max) / 2.0;
    o.range_m = std::max(50.0, std::max(x_max - x_min, y_max - y_min) / 2.0 + 30.0);
  }
  BirdsEye bev(o);
  const auto shift = [&](PointM p) {
    return PointM{static_cast<float>(p.x - centre_x), static_cast<float>(p.y - centre_y)};
  };
  const auto shifted = [&](const std::vector<PointM>& world) {
    std::vector<PointM> out = in_vehicle(world, to);
    for (PointM& p : out) p = shift(p);
    return out;
  };
  if (picture == DrivePicture::kLastScan) {
    for (const Point3M& p : v.points) bev.add_point(p.x, p.y, p.z);
    for (const BoxView& b : v.segments) {
      const PointM c = to(b.x, b.y);
      bev.add_box(c.x, c.y, b.length, b.width, b.yaw - to.yaw, Bgr{90, 90, 90});
    }
  }
  // Paths of the tracks that moved (more than kMovedM from where they were first confirmed),
  // but not of those last classified as background (clutter whose tracked position jumps).
  constexpr float kMovedM = 3.0f;
  std::set<std::uint64_t> moved;
  for (const auto& [id, path] : v.paths) {
    if (path.size() < 2 ||
        std::hypot(path.back().x - path.front().x, path.back().y - path.front().y) < kMovedM)
      continue;
    if (const auto c = v.classes.find(id); c != v.classes.end() && c->second == "background")
      continue;
    moved.insert(id);
    bev.add_path(shifted(path), track_colour(id));
  }
  bev.add_path(shifted(v.ego_path), Bgr{255, 255, 255}, 2);
  std::size_t confirmed = 0;
  for (const TrackView& t : v.last.tracks) {
    if (t.state == 0) continue;  // tentative tracks: their segment box is drawn already
    ++confirmed;
    const PointM c = shift(to(t.x, t.y));
    bev.add_box(c.x, c.y, t.length, t.width, t.yaw - to.yaw, track_colour(t.id));
    if (picture == DrivePicture::kWholeDrive && moved.count(t.id) == 0) continue;
    const bool classified = t.class_name != "unknown";
    char label[48];
    std::snprintf(label, sizeof(label), "#%llu%s%s", static_cast<unsigned long long>(t.id),
                  classified ? " " : "", classified ? t.class_name.c_str() : "");
    bev.add_label(c.x, c.y, label, track_colour(t.id));
  }
  const PointM ego = shift({0, 0});
  bev.add_box(ego.x, ego.y, 4.5f, 1.8f, 0, Bgr{255, 255, 255});  // the vehicle
  char line[160];
  std::snprintf(line, sizeof(line),
                "stac demo: scan %llu, %zu confirmed tracks (boxes, ids, class)",
                static_cast<unsigned long long>(v.last.scan_index), confirmed);
  bev.add_legend(line);
  bev.add_legend(picture == DrivePicture::kLastScan
                     ? "points by height (not deskewed); grey: segments; coloured: tracks, #id "
                       "(class once classified), paths"
                     : "the whole drive: the vehicle's path (white), paths of the tracks that "
                       "moved (not background)");
  bev.add_legend("frame of the vehicle's last pose: x forward = up, y left = left");
  return bev.save(png);
}

}  // namespace stac::pictures

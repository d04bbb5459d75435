// The pictures of `stac demo`, drawn from what arrived on DDS: the last scan's tracks (boxes, ids,
// class) and segments around the vehicle, and the tracks' paths over the whole drive. Both are in
// the frame of the vehicle's last pose (x forward = up, y left = left;
// pictures/birds_eye.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "pictures/drawing.hpp"
#include "rt/expected.hpp"

namespace stac::pictures {

struct BoxView {
  float x = 0, y = 0, length = 0, width = 0, yaw = 0;  // world (m, rad)
};
struct TrackView {
  std::uint64_t id = 0;
  float x = 0, y = 0, length = 0, width = 0, yaw = 0;  // world (m, rad)
  float speed_mps = 0;
  std::uint8_t state = 0;  // 0 tentative, 1 confirmed, 2 coasting
  std::string class_name = "unknown";
};
struct ScanView {
  std::uint64_t scan_index = 0;
  std::vector<TrackView> tracks;
};
struct DriveView {
  ScanView last;
  std::vector<BoxView> segments;  // the last segments sample
  std::vector<Point3M> points;    // the last scan's points, vehicle frame of the last pose (m)
  float ego_x = 0, ego_y = 0, ego_yaw = 0;             // the last pose (world)
  std::vector<PointM> ego_path;                        // world
  std::map<std::uint64_t, std::vector<PointM>> paths;  // confirmed tracks' positions, world
  std::map<std::uint64_t, std::string> classes;        // their latest class ("unknown" before one)
};

enum class DrivePicture {
  kLastScan,    // 40 m around the vehicle: points by height, segments (grey), tracks (boxes, ids),
                // paths
  kWholeDrive,  // the whole drive's extent: the vehicle's path and every confirmed track's path
};

rt::Status draw_drive(const DriveView& view, DrivePicture picture,
                      const std::filesystem::path& png);

}  // namespace stac::pictures

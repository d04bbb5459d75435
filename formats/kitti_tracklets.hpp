// KITTI raw's object labels, tracklet_labels.xml (a boost::serialization XML archive; the KITTI
// raw devkit's readme and readTrackletsXML): per object its type, its box size and, from its
// first frame on, a pose per frame in the velodyne's frame: the centre of the box's bottom
// (tx, ty, tz, m), its rotation (rx, ry, rz, rad; rz the yaw about the velodyne's z axis), and
// its state, occlusion and truncation codes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "rt/expected.hpp"

namespace stac::formats {

struct TrackletPose {
  double tx = 0, ty = 0, tz = 0, rx = 0, ry = 0, rz = 0;
  int state = 1, occlusion = 0, truncation = 0;
};

struct Tracklet {
  std::string object_type;     // Car, Van, Truck, Pedestrian, Person_sitting, Cyclist, Tram, Misc
  double h = 0, w = 0, l = 0;  // m
  std::uint32_t first_frame = 0;
  std::vector<TrackletPose> poses;  // frames first_frame, first_frame + 1, ...
};

// The STAC class of a KITTI object type: Car, Van, Truck and Tram are cars, Pedestrian and
// Person_sitting pedestrians, Cyclist bicyclists; Misc and DontCare are "" (left out of the
// scoring); any other is "?" (not a KITTI type).
std::string_view stac_class_of_kitti_type(std::string_view type) noexcept;

// The tracklets of a file's text (`name` names it in errors): refused, naming the tracklet and
// pose, when the archive's structure is not KITTI's, a number is not finite, a size is not in
// (0, 50] m, a type is no KITTI type, or a <count> differs from the items that follow it.
rt::Result<std::vector<Tracklet>> parse_kitti_tracklets(const std::string& text,
                                                        const std::string& name);
rt::Result<std::vector<Tracklet>> read_kitti_tracklets(const std::filesystem::path& file);
// The archive KITTI writes (what `stac sim --kitti-raw` labels a drive with).
std::string format_kitti_tracklets(const std::vector<Tracklet>& tracklets);

}  // namespace stac::formats

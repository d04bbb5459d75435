// KITTI files (the real scans in ../shared/data/kitti and kitti-object): velodyne scans, the
// object benchmark's calibration (Tr_velo_to_cam, R0_rect) and labels. Errors name the file.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::formats {

// float32 x, y, z, reflectance per point (velodyne frame, m; reflectance 0..1).
rt::Result<std::vector<float>> load_kitti_scan(const std::string& path);
// The points of a KITTI scan file from its size; an error when it cannot be read or its size is
// not a whole number of points (16 bytes each).
rt::Result<std::size_t> kitti_scan_points(const std::string& path);
// The .bin files of a folder, in name order (empty when it holds none).
rt::Result<std::vector<std::filesystem::path>> kitti_scans_in(const std::filesystem::path& folder);

// The numbers of a "KEY: n n n ..." line of a KITTI calibration file (calib.txt,
// calib_imu_to_velo.txt): exactly `count` of them, all finite; false when the key's line is
// missing or holds fewer (or other words).
bool kitti_calib_values(const std::string& text, const std::string& key, std::size_t count,
                        std::vector<double>& out);
// Orthonormal with determinant +1 (to 1e-3): what a calibration's rotation must be (a file of
// zeros would put every point at the origin).
bool is_rotation(const Eigen::Matrix3d& m) noexcept;

// The velodyne -> rectified camera 0 transform: R0_rect * Tr_velo_to_cam.
rt::Result<Eigen::Isometry3d> load_kitti_rect_T_velo(const std::string& calib_path);

// One object of a label_2 file (camera coordinates: x right, y down, z forward).
struct KittiObject {
  std::string type;      // Car, Van, Truck, Pedestrian, Person_sitting, Cyclist, Tram, Misc
  double truncated = 0;  // 0..1
  int occluded = 0;      // 0 visible, 1 partly, 2 largely occluded, 3 unknown
  double height = 0, width = 0, length = 0;                 // m
  Eigen::Vector3d bottom_centre = Eigen::Vector3d::Zero();  // rectified camera frame (m)
  double rotation_y = 0;                                    // rad, about the camera's y axis
  // Whether a point of the rectified camera frame lies in the box grown by `margin` (m).
  [[nodiscard]] bool contains(const Eigen::Vector3d& p_rect, double margin) const noexcept;
};

// Every object but DontCare.
rt::Result<std::vector<KittiObject>> load_kitti_labels(const std::string& path);

}  // namespace stac::formats

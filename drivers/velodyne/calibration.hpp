// Velodyne per-laser calibration (HDL-64E, HDL-32E, VLP-16, VLP-32C): the corrections the point
// math needs, in SI units. Loaded from Velodyne db.xml (cm, degrees) or ROS yaml (m, radians).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>

#include "drivers/velodyne/model.hpp"
#include "rt/expected.hpp"

namespace stac::velodyne {

inline constexpr int kMaxLasers = 64;

struct LaserCalibration {
  int laser_id = 0;                  // 0..63; 0-31 upper bank, 32-63 lower bank
  double rot_correction_rad = 0.0;   // azimuth correction, subtracted from the rotation
  double vert_correction_rad = 0.0;  // elevation of the beam, positive up
  double dist_correction_m = 0.0;    // added to the raw distance
  double dist_correction_x_m = 0.0;  // two-point correction at 2.4 m along x
  double dist_correction_y_m = 0.0;  // two-point correction at 1.93 m along y
  double vert_offset_m = 0.0;        // vertical offset of the beam origin
  double horiz_offset_m = 0.0;       // horizontal offset of the beam origin
  double focal_distance_m = 0.0;     // intensity focal distance (db.xml stores cm)
  double focal_slope = 0.0;          // intensity focal slope (unitless)
  int min_intensity = 0;             // clamp range of corrected intensity
  int max_intensity = 255;
  bool two_pt_correction_available = false;
  bool enabled = true;
};

struct Calibration {
  std::array<LaserCalibration, kMaxLasers> lasers{};
  int num_lasers = kMaxLasers;
  double distance_resolution_m = 0.002;  // size of one raw distance unit
  std::string source;                    // file path or "status stream", for messages
};

// Loads a db.xml or ROS yaml file, chosen by content. Errors name the file, the laser and the
// field ("calib.yaml: laser 12: missing 'vert_correction'").
rt::Result<Calibration> load_calibration(const std::filesystem::path& path);
rt::Result<Calibration> load_db_xml(const std::filesystem::path& path);
rt::Result<Calibration> load_ros_yaml(const std::filesystem::path& path);
// The same from text in memory; `name` stands for the file in messages.
rt::Result<Calibration> parse_db_xml(const std::string& text, const std::filesystem::path& name);
rt::Result<Calibration> parse_ros_yaml(const std::string& text, const std::filesystem::path& name);

// Checks every correction against an HDL-64E's sanity limits; errors name `source`, the laser
// and the field. The loaders call it; so does the status-stream calibration.
rt::Status check_calibration(const Calibration& calibration);

// Checks that a calibration fits a model: at least its lasers, none enabled beyond them (a
// VeloView file pads a VLP-16's 16 lasers to 64, disabled), not only the first half enabled
// (a VLP-16 file for a 32- or 64-laser sensor), and (HDL-32E, VLPs) the model's distance unit
// (an HDL-32E file for a VLP-32C: 2 mm, not 4). Errors say what to set.
rt::Status check_calibration_for(const Calibration& calibration, Model model);
// The calibration with its padding cut to the model's lasers.
Calibration lasers_of(const Calibration& calibration, Model model);

// Writes the ROS yaml form (metres, radians), as gen_calibration.py would, without its bugs.
rt::Status save_ros_yaml(const Calibration& calibration, const std::filesystem::path& path);

}  // namespace stac::velodyne

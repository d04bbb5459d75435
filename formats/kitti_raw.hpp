// A KITTI raw drive folder as an input of `stac process` (issue 33): its scans are
// DIR/velodyne_points/data/NNNNNNNNNN.bin (float32 x, y, z, reflectance 0..1, sensor frame, one
// revolution each, in name order), with DIR/velodyne_points/timestamps.txt (one UTC time per scan,
// "YYYY-MM-DD HH:MM:SS.fffffffff") when the drive has it; DIR/oxts/ holds its GPS/IMU.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "drivers/velodyne/scan.hpp"
#include "rt/expected.hpp"

namespace stac::formats {

struct KittiRawDrive {
  std::vector<std::filesystem::path> scans;  // in name order
  std::vector<std::int64_t> stamps_ns;       // one per scan: UTC ns
  bool stamps_from_file = false;             // else 100 ms apart (10 Hz) from 1 s
  bool has_oxts = false;                     // DIR/oxts/data exists
  std::size_t max_points = 0;                // of the largest scan
};

// Whether `path` is a folder holding velodyne_points/data/.
bool is_kitti_raw_drive(const std::filesystem::path& path);

// Lists the scans and reads their times. Fails naming the file: no scan, a scan whose size is not
// a multiple of 16 bytes, a timestamps file whose line count or a line does not fit.
rt::Result<KittiRawDrive> open_kitti_raw_drive(const std::filesystem::path& path);

// "2011-09-26 13:02:25.964389445" as UTC ns; false when the line is not such a time.
bool parse_kitti_time(const std::string& line, std::int64_t& ns);

struct KittiScanCounts {
  std::uint64_t points = 0, refused = 0;  // refused: not finite, or farther than 1 km
};

// One scan into `out` (capacity >= its points; sequence and stamp given): each point's x, y, z,
// its reflectance as intensity 0..255, its range and azimuth; no firing times (time offset 0),
// no laser or ring (0). The scan is complete (one revolution). Non-finite points, and points
// farther than 1 km, are left out and counted.
rt::Result<KittiScanCounts> load_kitti_raw_scan(const std::filesystem::path& file,
                                                std::uint64_t sequence, std::int64_t stamp_ns,
                                                velodyne::Scan& out);

}  // namespace stac::formats

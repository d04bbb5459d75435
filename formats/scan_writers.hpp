// Writes decoded scans: csv (one row per point) or kitti (one float32 x,y,z,intensity file per
// scan, intensity scaled to 0..1 like KITTI's reflectance).
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "drivers/velodyne/scan.hpp"
#include "rt/expected.hpp"

namespace stac::formats {

class ScanWriter {
 public:
  virtual ~ScanWriter() = default;
  virtual rt::Status write(const velodyne::Scan& scan) = 0;
  virtual rt::Status close() = 0;
};

// format: "csv" or "kitti"; for kitti `out` is a directory, created if missing.
rt::Result<std::unique_ptr<ScanWriter>> make_scan_writer(const std::string& format,
                                                         const std::filesystem::path& out);

}  // namespace stac::formats

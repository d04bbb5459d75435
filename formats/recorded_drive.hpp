// The complete scans of a recorded drive, whichever way it was recorded: a capture (the Velodyne's
// packets, decoded with the sensor's calibration; poses from the INS stream beside them) or a
// KITTI raw drive folder (velodyne_points; poses from its OXTS records and calib_imu_to_velo.txt).
// What `stac process`, `stac dataset`, `stac segment` and `stac demo` read, through one loop
// (issue 51).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "formats/capture_poses.hpp"
#include "formats/kitti_raw.hpp"
#include "rt/expected.hpp"
#include "settings/settings.hpp"

namespace stac::formats {

struct RecordedDriveOptions {
  std::string calib;  // a calibration file, "stream" (the unit's status bytes), or "": the config's
  std::string sensor;  // a model name, "auto", or "": the config's (apply_sensor_option)
  bool deskew = true;  // false: no poses, every scan in the vehicle frame (--no-deskew)
};

class RecordedDrive {
 public:
  // Opens IN (a KITTI raw drive folder, or a capture) with SETTINGS' Velodyne and ego sections,
  // which it completes as the drive says (the model, the calibration, a KITTI drive's mounting):
  // the sensor and its calibration, then the poses. Fails with a message naming what to fix.
  static rt::Result<RecordedDrive> open(const std::filesystem::path& in,
                                        settings::PipelineSettings& settings,
                                        const RecordedDriveOptions& options);

  // Calls ON_SCAN with each complete scan in order and the CPU time its decoding took (ns), until
  // it returns false; PROGRESS (when given) with how far it is (done of total, in the drive's own
  // unit). Stops at the first error (a KITTI scan that cannot be read); a capture cut short is
  // not one (capture_error()). scans() counts the complete scans passed on.
  rt::Status for_each_scan(const std::function<bool(velodyne::Scan&, std::int64_t)>& on_scan,
                           const std::function<void(double, double)>& progress = {});
  [[nodiscard]] std::uint64_t scans() const { return scans_; }
  // Why a capture gave no complete scan, for an error message (its reader's and assembler's
  // counts: nothing on the port, all truncated, ...).
  [[nodiscard]] std::string nothing_decoded() const;

  [[nodiscard]] const CapturePoses* poses() const { return poses_ ? &*poses_ : nullptr; }
  [[nodiscard]] ego::PoseHistory* pose_history() const {
    return poses_ ? poses_->history.get() : nullptr;
  }
  [[nodiscard]] const KittiRawDrive* kitti() const { return kitti_ ? &*kitti_ : nullptr; }
  // A capture's: what its reader and the scan assembler counted, and why the file broke off ("":
  // it did not). A KITTI drive's: its points read and left out.
  [[nodiscard]] const io::PcapReader* reader() const { return reader_ ? &*reader_ : nullptr; }
  [[nodiscard]] const velodyne::ScanStream* stream() const { return stream_.get(); }
  [[nodiscard]] std::string capture_error() const { return reader_ ? reader_->error() : ""; }
  [[nodiscard]] const KittiScanCounts& kitti_points() const { return kitti_points_; }

 private:
  std::filesystem::path in_;
  std::optional<KittiRawDrive> kitti_;
  std::optional<CapturePoses> poses_;
  std::optional<io::PcapReader> reader_;
  std::unique_ptr<velodyne::ScanStream> stream_;
  KittiScanCounts kitti_points_;
  std::uint64_t scans_ = 0;
  std::uint16_t port_ = 0;
};

}  // namespace stac::formats

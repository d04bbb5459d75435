// A KITTI raw drive folder as an input of `stac process` (issue 33): its scans are
// DIR/velodyne_points/data/NNNNNNNNNN.bin (float32 x, y, z, reflectance 0..1, sensor frame, one
// revolution each, in name order), with DIR/velodyne_points/timestamps.txt (one UTC time per scan,
// "YYYY-MM-DD HH:MM:SS.fffffffff") when the drive has it; DIR/oxts/ holds its GPS/IMU (one
// record a file, DIR/oxts/data/NNNNNNNNNN.txt, and DIR/oxts/timestamps.txt), and
// calib_imu_to_velo.txt (in DIR or, as KITTI ships it, in the date folder above) the mounting.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "drivers/velodyne/scan.hpp"
#include "ego/local_frame.hpp"
#include "rt/expected.hpp"

namespace stac::formats {

struct KittiRawDrive {
  std::vector<std::filesystem::path> scans;  // in name order
  std::vector<std::int64_t> stamps_ns;       // one per scan: UTC ns (facing forward, mid-sweep)
  bool stamps_from_file = false;             // else 100 ms apart (10 Hz) from 1 s
  // velodyne_points/timestamps_start.txt and _end.txt, when the drive has both: when each
  // sweep began and ended (facing backward); empty otherwise.
  std::vector<std::int64_t> sweep_start_ns, sweep_end_ns;
  bool has_oxts = false;       // DIR/oxts/data exists
  std::size_t max_points = 0;  // of the largest scan
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
// no laser or ring (0). The scan is complete (one revolution) and one instant (its end stamp is
// its stamp: placed in the world by the pose at its time). Non-finite points, and points
// farther than 1 km, are left out and counted.
rt::Result<KittiScanCounts> load_kitti_raw_scan(const std::filesystem::path& file,
                                                std::uint64_t sequence, std::int64_t stamp_ns,
                                                velodyne::Scan& out);

// Scan i of a drive: load_kitti_raw_scan at the drive's time of it, or, when the drive has its
// sweeps' start and end times, deskewable: the scan stamped at the sweep's start and ending at
// its end, each point's firing time placed by its azimuth in the sweep. A KITTI sweep starts
// and ends facing backward and turns clockwise seen from above (x forward, y left), facing
// forward at mid-sweep: fraction = (1 - atan2(y, x) / pi) / 2 (as KISS-ICP's KITTI raw reader).
rt::Result<KittiScanCounts> load_kitti_drive_scan(const KittiRawDrive& drive, std::size_t i,
                                                  velodyne::Scan& out);
// Where in a KITTI sweep (0 start .. 1 end) a point at sensor-frame (x, y) was fired.
double kitti_sweep_fraction(double x, double y) noexcept;

// One OXTS record (the KITTI raw devkit's readme, 30 values a line): the unit's position, its
// attitude (rad; roll positive left side up, pitch positive front down, yaw 0 east and positive
// counter-clockwise), velocities (m/s: north, east; forward, left, up along the earth's surface),
// accelerations, angular rates (rad/s about the forward, left, up axes), accuracies and the GPS
// modes; its time from oxts/timestamps.txt. The unit's frame is x forward, y left, z up.
struct OxtsRecord {
  std::int64_t stamp_ns = 0;
  double lat_deg = 0, lon_deg = 0, alt_m = 0;
  double roll_rad = 0, pitch_rad = 0, yaw_rad = 0;
  double vn = 0, ve = 0, vf = 0, vl = 0, vu = 0;
  double ax = 0, ay = 0, az = 0, af = 0, al = 0, au = 0;
  double wx = 0, wy = 0, wz = 0, wf = 0, wl = 0, wu = 0;
  double pos_accuracy = 0, vel_accuracy = 0;
  int navstat = 0, numsats = 0, posmode = 0, velmode = 0, orimode = 0;
};

// One record's text: 30 numbers, finite, the last five integers, the position and attitude
// within what a vehicle can have (|lat| <= 90, |lon| <= 180, altitude -1..20 km, |roll|, |yaw|
// <= pi, |pitch| <= pi/2, speeds under 200 m/s). An error says which value is wrong.
rt::Result<OxtsRecord> parse_oxts_record(const std::string& text);
// Writes a record as KITTI does (the same 30 values, the last five as integers).
std::string format_oxts_record(const OxtsRecord& r);

// DIR/oxts: every record with its time, in name order. Fails naming the file (and line): no
// record, a record that does not parse, a file of more than one record, a timestamps file
// missing, or whose count does not fit, and a record impossible after the one before it (its time
// not later, or more than 1 s later; moved faster than 100 m/s; its yaw turned faster than
// 4 rad/s).
rt::Result<std::vector<OxtsRecord>> read_kitti_oxts(const std::filesystem::path& drive);

// The record as the INS fix STAC's ego path takes (ego::InsFix: Tate-Bryant angles of the
// x-forward, y-right, z-down body in NED): heading = 90 deg - yaw, pitch = -pitch (nose up
// positive), roll = roll; velocity (vn, ve, -vu); rates (wf, -wl, -wu) in deg/s.
ego::InsFix oxts_fix(const OxtsRecord& r);

// oxts_fix's inverse: the record of a fix (yaw wrapped to +-pi; forward and left velocity from the
// heading; the unit's accelerations left 0, gravity 9.81 m/s^2 on its up axis; accuracies of an
// RTK fix, navstat 4, 10 satellites, GPS modes 4).
OxtsRecord oxts_record(const ego::InsFix& fix);

// Writes a drive in KITTI raw's layout (`stac sim --kitti-raw DIR`): each scan's points as
// velodyne_points/data/NNNNNNNNNN.bin (x, y, z, intensity / 255 as reflectance), a record per
// scan as oxts/data/NNNNNNNNNN.txt, the times in velodyne_points/timestamps.txt and
// oxts/timestamps.txt (KITTI's format, UTC), and calib_imu_to_velo.txt from the mounting.
class KittiRawWriter {
 public:
  // Makes the folders (an existing drive's files are replaced) and writes the mounting.
  static rt::Result<KittiRawWriter> create(const std::filesystem::path& dir,
                                           const Eigen::Isometry3d& velo_T_imu);
  // One scan, placed at `stamp_ns`, and the record of that time; its header's first and last
  // firing are its sweep's start and end.
  rt::Status add(const velodyne::Scan& scan, std::int64_t stamp_ns, const OxtsRecord& record);
  // The timestamps files (timestamps.txt, and the sweeps' _start and _end); the drive is
  // complete after it.
  rt::Status finish();
  [[nodiscard]] std::size_t scans() const noexcept { return stamps_ns_.size(); }

 private:
  std::filesystem::path dir_;
  std::vector<std::int64_t> stamps_ns_, starts_ns_, ends_ns_;
};

// "2011-09-26 13:02:25.964389445": a UTC time (ns) as KITTI writes it.
std::string format_kitti_time(std::int64_t ns);

// calib_imu_to_velo.txt: "R:" (9 numbers, row-major) and "T:" (3, m), which take a point from
// the IMU's frame to the velodyne's: returns velo_T_imu. Refuses an R that is not a rotation.
rt::Result<Eigen::Isometry3d> read_kitti_imu_to_velo(const std::filesystem::path& file);
// The drive's calib_imu_to_velo.txt: in DIR, else in DIR/.. (KITTI's date folder); empty when
// neither has one.
std::filesystem::path find_kitti_imu_to_velo(const std::filesystem::path& drive);

}  // namespace stac::formats

#include "formats/kitti_raw.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>

#include "formats/kitti_files.hpp"

namespace stac::formats {
namespace fs = std::filesystem;

bool is_kitti_raw_drive(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path / "velodyne_points" / "data", ec);
}

bool parse_kitti_time(const std::string& line, std::int64_t& ns) {
  int y = 0, mo = 0, d = 0, h = 0, mi = 0, used = 0;
  double s = 0;
  if (std::sscanf(line.c_str(), "%4d-%2d-%2d %2d:%2d:%lf%n", &y, &mo, &d, &h, &mi, &s, &used) != 6)
    return false;
  if (line.find_first_not_of(" \t\r", static_cast<std::size_t>(used)) != std::string::npos)
    return false;
  if (y < 1970 || y > 2200 || mo < 1 || mo > 12 || h > 23 || mi > 59 || !(s >= 0 && s < 61))
    return false;
  // A day past its month's end (Feb 30) or a second of 60 would roll into the next day or minute
  // and be blamed on the next line ("not after the line before"): refused here, on their own
  // line. A second of 60 is a leap second, only ever at the end of June or December (UTC).
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  constexpr int kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const int last_day = kDays[mo - 1] + (mo == 2 && leap ? 1 : 0);
  if (d < 1 || d > last_day) return false;
  if (s >= 60 && !((mo == 6 || mo == 12) && d == last_day && h == 23 && mi == 59)) return false;
  std::tm t{};
  t.tm_year = y - 1900;
  t.tm_mon = mo - 1;
  t.tm_mday = d;
  t.tm_hour = h;
  t.tm_min = mi;
  const std::int64_t whole = static_cast<std::int64_t>(timegm(&t));
  ns = whole * 1'000'000'000 + std::llround(s * 1e9);
  return true;
}

namespace {

// The times of a KITTI timestamps file, one a line, increasing (one per `what`).
rt::Result<std::vector<std::int64_t>> read_kitti_times(const fs::path& file,
                                                       const std::string& what) {
  std::ifstream in(file);
  if (!in) return rt::make_error(file.string() + ": missing (one time per " + what + ")");
  std::vector<std::int64_t> out;
  std::string line;
  for (std::size_t n = 1; std::getline(in, line); ++n) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::int64_t ns = 0;
    if (!parse_kitti_time(line, ns))
      return rt::make_error(file.string() + ":" + std::to_string(n) + ": '" + line +
                            "' is not a time (YYYY-MM-DD HH:MM:SS.fffffffff, a day of its month, "
                            "seconds under 60)");
    if (!out.empty() && ns <= out.back())
      return rt::make_error(file.string() + ":" + std::to_string(n) +
                            ": not after the line before (one " + what + " per line, in order)");
    out.push_back(ns);
  }
  return out;
}

}  // namespace

rt::Result<KittiRawDrive> open_kitti_raw_drive(const fs::path& path) {
  KittiRawDrive drive;
  const fs::path data = path / "velodyne_points" / "data";
  auto scans = kitti_scans_in(data);
  if (!scans) return rt::Unexpected<rt::Error>{scans.error()};
  if (scans->empty()) return rt::make_error(data.string() + ": no .bin scan in it");
  drive.scans = std::move(*scans);
  for (const fs::path& scan : drive.scans) {
    const auto points = kitti_scan_points(scan.string());
    if (!points) return rt::Unexpected<rt::Error>{points.error()};
    drive.max_points = std::max(drive.max_points, *points);
  }
  std::error_code ec;
  const fs::path times = path / "velodyne_points" / "timestamps.txt";
  if (fs::exists(times, ec)) {
    auto stamps = read_kitti_times(times, "scan");
    if (!stamps) return rt::Unexpected<rt::Error>{stamps.error()};
    drive.stamps_ns = std::move(*stamps);
    if (drive.stamps_ns.size() != drive.scans.size())
      return rt::make_error(times.string() + " has " + std::to_string(drive.stamps_ns.size()) +
                            " times for " + std::to_string(drive.scans.size()) + " scans");
    drive.stamps_from_file = true;
  } else {
    for (std::size_t i = 0; i < drive.scans.size(); ++i)
      drive.stamps_ns.push_back(1'000'000'000 + static_cast<std::int64_t>(i) * 100'000'000);
  }
  // The sweeps' start and end times: both files or neither, one time per scan each.
  const fs::path starts = path / "velodyne_points" / "timestamps_start.txt";
  const fs::path ends = path / "velodyne_points" / "timestamps_end.txt";
  const bool has_start = fs::exists(starts, ec), has_end = fs::exists(ends, ec);
  if (has_start != has_end) {
    return rt::make_error((has_start ? ends : starts).string() + " is missing beside " +
                          (has_start ? starts : ends).filename().string() +
                          " (a sweep's times need both; remove the other to read the drive "
                          "without them)");
  }
  if (has_start) {
    auto a = read_kitti_times(starts, "sweep");
    if (!a) return rt::Unexpected<rt::Error>{a.error()};
    auto b = read_kitti_times(ends, "sweep");
    if (!b) return rt::Unexpected<rt::Error>{b.error()};
    for (const auto& [file, list] : {std::pair{&starts, &*a}, std::pair{&ends, &*b}}) {
      if (list->size() != drive.scans.size())
        return rt::make_error(file->string() + " has " + std::to_string(list->size()) +
                              " times for " + std::to_string(drive.scans.size()) + " scans");
    }
    for (std::size_t i = 0; i < a->size(); ++i) {
      if ((*b)[i] <= (*a)[i] || (*b)[i] - (*a)[i] > 1'000'000'000) {
        return rt::make_error(ends.string() + ": line " + std::to_string(i + 1) +
                              ": a sweep must end after it starts, within 1 s (" +
                              format_kitti_time((*a)[i]) + " .. " + format_kitti_time((*b)[i]) +
                              ")");
      }
    }
    drive.sweep_start_ns = std::move(*a);
    drive.sweep_end_ns = std::move(*b);
  }
  drive.has_oxts = fs::is_directory(path / "oxts" / "data", ec);
  if (!drive.has_oxts && fs::exists(path / "oxts", ec))
    return rt::make_error((path / "oxts").string() +
                          ": has no data/ folder of records; a drive's GPS/IMU is oxts/data/*.txt "
                          "with oxts/timestamps.txt (remove oxts/ to run the drive unposed)");
  return drive;
}

double kitti_sweep_fraction(double x, double y) noexcept {
  return 0.5 * (1.0 - std::atan2(y, x) / std::numbers::pi);
}

rt::Result<KittiScanCounts> load_kitti_drive_scan(const KittiRawDrive& drive, std::size_t i,
                                                  velodyne::Scan& out) {
  const bool sweeps = !drive.sweep_start_ns.empty();
  auto counts = load_kitti_raw_scan(drive.scans[i], i,
                                    sweeps ? drive.sweep_start_ns[i] : drive.stamps_ns[i], out);
  if (!counts || !sweeps) return counts;
  const std::int64_t span = drive.sweep_end_ns[i] - drive.sweep_start_ns[i];
  for (velodyne::Point& p : out.points) {
    p.time_offset_ns = static_cast<std::int32_t>(
        std::llround(kitti_sweep_fraction(p.x, p.y) * static_cast<double>(span)));
  }
  out.header.end_stamp_ns = drive.sweep_end_ns[i];
  return counts;
}

rt::Result<KittiScanCounts> load_kitti_raw_scan(const fs::path& file, std::uint64_t sequence,
                                                std::int64_t stamp_ns, velodyne::Scan& out) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return rt::make_error(file.string() + ": cannot open");
  out.points.clear();
  out.header = {};
  KittiScanCounts counts;
  float p[4];
  while (in.read(reinterpret_cast<char*>(p), sizeof(p))) {
    ++counts.points;
    const double range = std::sqrt(double{p[0]} * p[0] + double{p[1]} * p[1] + double{p[2]} * p[2]);
    if (!std::isfinite(range) || range > 1000.0 || !std::isfinite(p[3])) {
      ++counts.refused;
      continue;
    }
    velodyne::Point* q = out.points.append();
    if (q == nullptr)
      return rt::make_error(file.string() + ": more points than the scan holds (" +
                            std::to_string(out.points.capacity()) + ")");
    double azimuth = std::atan2(double{p[1]}, double{p[0]}) * 18000.0 / std::numbers::pi;
    if (azimuth < 0) azimuth += 36000.0;
    *q = {p[0],
          p[1],
          p[2],
          std::clamp(p[3], 0.0f, 1.0f) * 255.0f,
          static_cast<float>(range),
          0,
          static_cast<std::uint16_t>(std::min(35999.0, std::floor(azimuth))),
          0,
          0,
          0};
  }
  if (in.bad()) return rt::make_error(file.string() + ": read error");
  out.header.sequence = sequence;
  out.header.stamp_ns = stamp_ns;
  // No firing times: the whole scan is one instant, its time (KITTI's: when the sensor faced
  // forward, mid-sweep), so with poses it is placed by the pose at that time.
  out.header.end_stamp_ns = stamp_ns;
  out.header.starts_at_cut = out.header.ends_at_cut = true;
  return counts;
}

namespace {

constexpr const char* kOxtsNames[30] = {
    "lat",          "lon",     "alt",     "roll",    "pitch",   "yaw",    "vn", "ve",
    "vf",           "vl",      "vu",      "ax",      "ay",      "az",     "af", "al",
    "au",           "wx",      "wy",      "wz",      "wf",      "wl",     "wu", "pos_accuracy",
    "vel_accuracy", "navstat", "numsats", "posmode", "velmode", "orimode"};

}  // namespace

rt::Result<OxtsRecord> parse_oxts_record(const std::string& text) {
  std::istringstream in(text);
  double v[30];
  for (int i = 0; i < 30; ++i) {
    std::string word;
    if (!(in >> word))
      return rt::make_error("has " + std::to_string(i) + " values, an OXTS record has 30 (" +
                            kOxtsNames[i] + " missing)");
    char* end = nullptr;
    v[i] = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || !std::isfinite(v[i]))
      return rt::make_error(std::string(kOxtsNames[i]) + " '" + word + "' is not a finite number");
    if (i >= 25 && (v[i] != std::floor(v[i]) || std::abs(v[i]) > 1e6))
      return rt::make_error(std::string(kOxtsNames[i]) + " '" + word + "' is not an integer");
  }
  if (std::string extra; in >> extra)
    return rt::make_error("more than 30 values ('" + extra + "' after orimode)");
  OxtsRecord r;
  r.lat_deg = v[0], r.lon_deg = v[1], r.alt_m = v[2];
  r.roll_rad = v[3], r.pitch_rad = v[4], r.yaw_rad = v[5];
  r.vn = v[6], r.ve = v[7], r.vf = v[8], r.vl = v[9], r.vu = v[10];
  r.ax = v[11], r.ay = v[12], r.az = v[13], r.af = v[14], r.al = v[15], r.au = v[16];
  r.wx = v[17], r.wy = v[18], r.wz = v[19], r.wf = v[20], r.wl = v[21], r.wu = v[22];
  r.pos_accuracy = v[23], r.vel_accuracy = v[24];
  r.navstat = static_cast<int>(v[25]), r.numsats = static_cast<int>(v[26]);
  r.posmode = static_cast<int>(v[27]), r.velmode = static_cast<int>(v[28]);
  r.orimode = static_cast<int>(v[29]);
  const double pi = std::numbers::pi;
  if (std::abs(r.lat_deg) > 90 || std::abs(r.lon_deg) > 180)
    return rt::make_error("lat/lon " + std::to_string(r.lat_deg) + ", " +
                          std::to_string(r.lon_deg) + " are not a place on Earth");
  if (r.alt_m < -1000 || r.alt_m > 20000)
    return rt::make_error("alt " + std::to_string(r.alt_m) + " m is no road's altitude");
  if (std::abs(r.roll_rad) > pi + 1e-6 || std::abs(r.yaw_rad) > pi + 1e-6 ||
      std::abs(r.pitch_rad) > pi / 2 + 1e-6)
    return rt::make_error("roll, pitch, yaw must be radians within +-pi, +-pi/2, +-pi");
  if (std::hypot(r.vn, r.ve, r.vu) > 200)
    return rt::make_error("a speed over 200 m/s is no vehicle's");
  return r;
}

std::string format_oxts_record(const OxtsRecord& r) {
  char line[1024];
  std::snprintf(line, sizeof line,
                "%.14f %.14f %.10f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f "
                "%.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %.12f %d %d %d "
                "%d %d",
                r.lat_deg, r.lon_deg, r.alt_m, r.roll_rad, r.pitch_rad, r.yaw_rad, r.vn, r.ve, r.vf,
                r.vl, r.vu, r.ax, r.ay, r.az, r.af, r.al, r.au, r.wx, r.wy, r.wz, r.wf, r.wl, r.wu,
                r.pos_accuracy, r.vel_accuracy, r.navstat, r.numsats, r.posmode, r.velmode,
                r.orimode);
  return line;
}

namespace {

// What makes record `b` impossible right after `a` (empty: nothing): time that does not move on
// or jumps more than a second, or a move a vehicle cannot make in that time (the Applanix reader
// counts such fixes as impossible: ego/ego_estimator.hpp).
std::string oxts_jump(const OxtsRecord& a, const OxtsRecord& b) {
  constexpr double kMaxGapS = 1.0, kMaxSpeedMps = 100.0, kMaxYawRateRadps = 4.0;
  constexpr double kEarthRadiusM = 6'378'137.0, kRad = std::numbers::pi / 180.0;
  const double dt = static_cast<double>(b.stamp_ns - a.stamp_ns) * 1e-9;
  char text[160];
  if (dt <= 0.0) {
    std::snprintf(text, sizeof(text), "its time is %.3f s, not after", dt);
    return text;
  }
  if (dt > kMaxGapS) {
    std::snprintf(text, sizeof(text), "its time jumps %.3f s (more than %.0f s)", dt, kMaxGapS);
    return text;
  }
  const double north = (b.lat_deg - a.lat_deg) * kRad * kEarthRadiusM;
  const double east = (b.lon_deg - a.lon_deg) * kRad * kEarthRadiusM *
                      std::cos(0.5 * (a.lat_deg + b.lat_deg) * kRad);
  const double moved = std::hypot(north, east, b.alt_m - a.alt_m);
  if (moved > kMaxSpeedMps * dt + 1.0) {
    std::snprintf(text, sizeof(text), "it is %.1f m away in %.3f s (over %.0f m/s)", moved, dt,
                  kMaxSpeedMps);
    return text;
  }
  const double yaw = std::remainder(b.yaw_rad - a.yaw_rad, 2.0 * std::numbers::pi);
  if (std::abs(yaw) > kMaxYawRateRadps * dt + 0.05) {
    std::snprintf(text, sizeof(text), "its yaw turns %.2f rad in %.3f s (over %.0f rad/s)", yaw, dt,
                  kMaxYawRateRadps);
    return text;
  }
  return {};
}

}  // namespace

rt::Result<std::vector<OxtsRecord>> read_kitti_oxts(const fs::path& drive) {
  const fs::path data = drive / "oxts" / "data";
  std::error_code ec;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(data, ec))
    if (e.path().extension() == ".txt") files.push_back(e.path());
  if (ec) return rt::make_error(data.string() + ": cannot list (" + ec.message() + ")");
  std::sort(files.begin(), files.end());
  if (files.empty()) return rt::make_error(data.string() + ": no .txt record in it");
  auto times = read_kitti_times(drive / "oxts" / "timestamps.txt", "record");
  if (!times) return rt::Unexpected<rt::Error>{times.error()};
  if (times->size() != files.size())
    return rt::make_error((drive / "oxts" / "timestamps.txt").string() + " has " +
                          std::to_string(times->size()) + " times for " +
                          std::to_string(files.size()) + " records in " + data.string());
  std::vector<OxtsRecord> out;
  out.reserve(files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    std::ifstream in(files[i]);
    std::string text;
    if (!in || !std::getline(in, text))
      return rt::make_error(files[i].string() + ": cannot read (one line of 30 values)");
    auto r = parse_oxts_record(text);
    if (!r) return rt::make_error(files[i].string() + ": " + r.error().message);
    for (std::string more; std::getline(in, more);)
      if (more.find_first_not_of(" \t\r") != std::string::npos)
        return rt::make_error(files[i].string() +
                              ": holds more than one record (KITTI writes "
                              "one a file, one file a frame)");
    r->stamp_ns = (*times)[i];
    if (i > 0)
      if (const std::string why = oxts_jump(out.back(), *r); !why.empty())
        return rt::make_error(files[i].string() + " (" +
                              (drive / "oxts" / "timestamps.txt").string() + " line " +
                              std::to_string(i + 1) + "): " + why +
                              " after the record before it; a drive's records follow each "
                              "other at 10 Hz (a damaged or spliced drive)");
    out.push_back(*r);
  }
  return out;
}

ego::InsFix oxts_fix(const OxtsRecord& r) {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  ego::InsFix f;
  f.stamp_ns = r.stamp_ns;
  f.position = {r.lat_deg, r.lon_deg, r.alt_m};
  f.roll_deg = r.roll_rad * kDeg;
  f.pitch_deg = -r.pitch_rad * kDeg;
  double heading = 90.0 - r.yaw_rad * kDeg;
  if (heading >= 360.0) heading -= 360.0;
  if (heading < 0.0) heading += 360.0;
  f.heading_deg = heading;
  f.velocity_ned_mps = {r.vn, r.ve, -r.vu};
  f.angular_rate_frd_dps = {r.wf * kDeg, -r.wl * kDeg, -r.wu * kDeg};
  return f;
}

rt::Result<Eigen::Isometry3d> read_kitti_imu_to_velo(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return rt::make_error(file.string() + ": cannot read the IMU -> velodyne calibration");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::vector<double> r_values, t_values;
  if (!kitti_calib_values(text, "R", 9, r_values) || !kitti_calib_values(text, "T", 3, t_values))
    return rt::make_error(file.string() + ": needs 'R:' (9 numbers) and 'T:' (3 numbers)");
  const Eigen::Matrix3d r =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r_values.data());
  const Eigen::Vector3d t(t_values[0], t_values[1], t_values[2]);
  if (!is_rotation(r))
    return rt::make_error(file.string() + ": 'R:' is not a rotation (orthonormal, determinant 1)");
  if (t.norm() > 10.0)
    return rt::make_error(file.string() + ": 'T:' puts the velodyne over 10 m from the IMU");
  Eigen::Isometry3d velo_T_imu = Eigen::Isometry3d::Identity();
  velo_T_imu.linear() = r;
  velo_T_imu.translation() = t;
  return velo_T_imu;
}

fs::path find_kitti_imu_to_velo(const fs::path& drive) {
  std::error_code ec;
  fs::path folder = fs::absolute(drive, ec).lexically_normal();
  if (!folder.has_filename()) folder = folder.parent_path();  // "drive/" names the same folder
  for (const fs::path& f :
       {folder / "calib_imu_to_velo.txt", folder.parent_path() / "calib_imu_to_velo.txt"})
    if (fs::is_regular_file(f, ec)) return f;
  return {};
}

OxtsRecord oxts_record(const ego::InsFix& fix) {
  constexpr double kRad = std::numbers::pi / 180.0;
  OxtsRecord r;
  r.stamp_ns = fix.stamp_ns;
  r.lat_deg = fix.position.lat_deg, r.lon_deg = fix.position.lon_deg;
  r.alt_m = fix.position.alt_m;
  r.roll_rad = fix.roll_deg * kRad;
  r.pitch_rad = -fix.pitch_deg * kRad;
  r.yaw_rad = std::remainder((90.0 - fix.heading_deg) * kRad, 2.0 * std::numbers::pi);
  r.vn = fix.velocity_ned_mps.x(), r.ve = fix.velocity_ned_mps.y();
  r.vu = -fix.velocity_ned_mps.z();
  const double h = fix.heading_deg * kRad;  // clockwise from north
  r.vf = r.vn * std::cos(h) + r.ve * std::sin(h);
  r.vl = r.vn * std::sin(h) - r.ve * std::cos(h);
  r.az = r.au = 9.81;
  r.wx = r.wf = fix.angular_rate_frd_dps.x() * kRad;
  r.wy = r.wl = -fix.angular_rate_frd_dps.y() * kRad;
  r.wz = r.wu = -fix.angular_rate_frd_dps.z() * kRad;
  r.pos_accuracy = 0.02, r.vel_accuracy = 0.02;
  r.navstat = 4, r.numsats = 10, r.posmode = 4, r.velmode = 4, r.orimode = 0;
  return r;
}

std::string format_kitti_time(std::int64_t ns) {
  const std::int64_t s = ns >= 0 ? ns / 1'000'000'000 : (ns - 999'999'999) / 1'000'000'000;
  const auto frac = static_cast<long long>(ns - s * 1'000'000'000);
  const auto whole = static_cast<std::time_t>(s);
  std::tm t{};
  gmtime_r(&whole, &t);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02d %02d:%02d:%02d.%09lld", t.tm_year + 1900,
                t.tm_mon + 1, t.tm_mday, t.tm_hour, t.tm_min, t.tm_sec, frac);
  return text;
}

rt::Result<KittiRawWriter> KittiRawWriter::create(const fs::path& dir,
                                                  const Eigen::Isometry3d& velo_T_imu) {
  std::error_code ec;
  for (const fs::path& sub : {dir / "velodyne_points" / "data", dir / "oxts" / "data"}) {
    fs::remove_all(sub, ec);
    fs::create_directories(sub, ec);
    if (ec) return rt::make_error(sub.string() + ": cannot create (" + ec.message() + ")");
  }
  std::ofstream calib(dir / "calib_imu_to_velo.txt");
  const Eigen::Matrix3d& r = velo_T_imu.linear();
  const Eigen::Vector3d& t = velo_T_imu.translation();
  char text[512];
  std::snprintf(text, sizeof text,
                "calib_time: written by stac sim\nR: %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e\n"
                "T: %.9e %.9e %.9e\n",
                r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2),
                t.x(), t.y(), t.z());
  calib << text;
  if (!calib) return rt::make_error((dir / "calib_imu_to_velo.txt").string() + ": cannot write");
  KittiRawWriter w;
  w.dir_ = dir;
  return w;
}

rt::Status KittiRawWriter::add(const velodyne::Scan& scan, std::int64_t stamp_ns,
                               const OxtsRecord& record) {
  char name[32];
  std::snprintf(name, sizeof name, "%010zu", stamps_ns_.size());
  const fs::path bin = dir_ / "velodyne_points" / "data" / (std::string(name) + ".bin");
  std::ofstream out(bin, std::ios::binary);
  std::vector<float> values;
  values.reserve(scan.points.size() * 4);
  for (const velodyne::Point& p : scan.points)
    values.insert(values.end(), {p.x, p.y, p.z, std::clamp(p.intensity / 255.0f, 0.0f, 1.0f)});
  out.write(reinterpret_cast<const char*>(values.data()),
            static_cast<std::streamsize>(values.size() * sizeof(float)));
  if (!out) return rt::make_error(bin.string() + ": cannot write");
  const fs::path txt = dir_ / "oxts" / "data" / (std::string(name) + ".txt");
  std::ofstream(txt) << format_oxts_record(record) << '\n';
  if (!fs::exists(txt)) return rt::make_error(txt.string() + ": cannot write");
  stamps_ns_.push_back(stamp_ns);
  starts_ns_.push_back(scan.header.stamp_ns);
  ends_ns_.push_back(scan.header.end_stamp_ns);
  return {};
}

rt::Status KittiRawWriter::finish() {
  const auto lines = [](const std::vector<std::int64_t>& ns) {
    std::string times;
    for (const std::int64_t t : ns) times += format_kitti_time(t) + "\n";
    return times;
  };
  const fs::path velo = dir_ / "velodyne_points";
  for (const auto& [f, times] : {std::pair{velo / "timestamps.txt", lines(stamps_ns_)},
                                 std::pair{dir_ / "oxts" / "timestamps.txt", lines(stamps_ns_)},
                                 std::pair{velo / "timestamps_start.txt", lines(starts_ns_)},
                                 std::pair{velo / "timestamps_end.txt", lines(ends_ns_)}}) {
    std::ofstream out(f);
    out << times;
    if (!out) return rt::make_error(f.string() + ": cannot write");
  }
  return {};
}

}  // namespace stac::formats

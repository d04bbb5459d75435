#include "formats/kitti_raw.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <numbers>

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
  if (y < 1970 || y > 2200 || mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59 ||
      !(s >= 0 && s < 61))
    return false;
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
    std::ifstream in(times);
    std::string line;
    for (std::size_t n = 1; std::getline(in, line); ++n) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::int64_t ns = 0;
      if (!parse_kitti_time(line, ns))
        return rt::make_error(times.string() + ":" + std::to_string(n) + ": '" + line +
                              "' is not a time (YYYY-MM-DD HH:MM:SS.fffffffff)");
      if (!drive.stamps_ns.empty() && ns <= drive.stamps_ns.back())
        return rt::make_error(times.string() + ":" + std::to_string(n) +
                              ": not after the line before (one scan per line, in order)");
      drive.stamps_ns.push_back(ns);
    }
    if (drive.stamps_ns.size() != drive.scans.size())
      return rt::make_error(times.string() + " has " + std::to_string(drive.stamps_ns.size()) +
                            " times for " + std::to_string(drive.scans.size()) + " scans");
    drive.stamps_from_file = true;
  } else {
    for (std::size_t i = 0; i < drive.scans.size(); ++i)
      drive.stamps_ns.push_back(1'000'000'000 + static_cast<std::int64_t>(i) * 100'000'000);
  }
  drive.has_oxts = fs::is_directory(path / "oxts" / "data", ec);
  return drive;
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
  out.header.end_stamp_ns = stamp_ns + 100'000'000;
  out.header.starts_at_cut = out.header.ends_at_cut = true;
  return counts;
}

}  // namespace stac::formats

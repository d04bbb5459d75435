// The simulator's realism job (sim_compare_job.hpp): real KITTI scans and simulated ones decoded
// by the project's decoder, the same statistics on both, and the report.
#include "offline/sim_compare_job.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <numbers>
#include <sstream>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "formats/capture_input.hpp"
#include "formats/durable_file.hpp"
#include "formats/kitti_files.hpp"
#include "formats/kitti_raw.hpp"
#include "pictures/birds_eye.hpp"
#include "pictures/chart.hpp"
#include "rt/formatted.hpp"
#include "settings/settings.hpp"

namespace stac::offline {

using namespace stac::settings;
using namespace stac::formats;
namespace {

constexpr int kRings = 64;
constexpr double kRangeBinM = 2.0;
constexpr int kRangeBins = 60;         // 0..120 m
constexpr double kMaxRangeM = 1000.0;  // farther: not a LIDAR return
constexpr int kIntensityBins = 20;

struct P {
  float x, y, z, intensity01;
  int ring;  // 0 = lowest beam
};

// Statistics of one source, averaged over its scans.
struct Stats {
  std::string name;
  std::size_t scans = 0;
  std::uint64_t bad_points = 0;  // non-finite or beyond kMaxRangeM: left out
  double points_mean = 0, points_min = 1e300, points_max = 0;
  double rings_mean = 0;                        // rings with points per scan
  std::array<double, kRings> ring_points{};     // mean points per ring, 0 = lowest
  std::array<double, kRings> ring_elevation{};  // mean of the per-scan median elevation, deg
  std::array<double, kRangeBins> range_hist{};  // fraction of points per 2 m bin (beyond: last)
  std::array<double, kIntensityBins> intensity_hist{};
  double range_median = 0, range_mean = 0, beyond_50m = 0;
  double ground_fraction = 0;
  double intensity_mean = 0, intensity_zero = 0;
  std::vector<double> per_scan_points, per_scan_ground;  // in scan order

  void add(const std::vector<P>& pts, const SimCompareJobOptions& o) {
    ++scans;
    const auto n = static_cast<double>(pts.size());
    points_mean += n;
    points_min = std::min(points_min, n);
    points_max = std::max(points_max, n);
    std::array<std::vector<double>, kRings> elev;
    std::vector<double> ranges;
    ranges.reserve(pts.size());
    std::array<double, kRangeBins> rh{};
    std::array<double, kIntensityBins> ih{};
    double ground = 0, beyond = 0, isum = 0, izero = 0;
    for (const P& p : pts) {
      const double horiz = std::hypot(p.x, p.y);
      const double r = std::sqrt(horiz * horiz + static_cast<double>(p.z) * p.z);
      // A NaN or absurd point (a damaged file) is counted, never binned.
      if (!std::isfinite(r) || r > kMaxRangeM || !std::isfinite(p.intensity01)) {
        ++bad_points;
        continue;
      }
      ranges.push_back(r);
      rh[static_cast<std::size_t>(std::min(kRangeBins - 1, static_cast<int>(r / kRangeBinM)))] += 1;
      beyond += r > 50.0 ? 1 : 0;
      ground += p.z < -o.mount_height_m + o.ground_margin_m ? 1 : 0;
      const double i01 = std::clamp(static_cast<double>(p.intensity01), 0.0, 1.0);
      ih[static_cast<std::size_t>(
          std::min(kIntensityBins - 1, static_cast<int>(i01 * kIntensityBins)))] += 1;
      isum += i01;
      izero += i01 < 0.005 ? 1 : 0;
      if (p.ring >= 0 && p.ring < kRings) {
        elev[static_cast<std::size_t>(p.ring)].push_back(std::atan2(p.z, horiz) * 180.0 /
                                                         std::numbers::pi);
      }
    }
    const double inv = n > 0 ? 1.0 / n : 0.0;
    for (int i = 0; i < kRangeBins; ++i)
      range_hist[static_cast<std::size_t>(i)] += rh[static_cast<std::size_t>(i)] * inv;
    for (int i = 0; i < kIntensityBins; ++i)
      intensity_hist[static_cast<std::size_t>(i)] += ih[static_cast<std::size_t>(i)] * inv;
    if (!ranges.empty()) {
      std::nth_element(ranges.begin(),
                       ranges.begin() + static_cast<std::ptrdiff_t>(ranges.size() / 2),
                       ranges.end());
      range_median += ranges[ranges.size() / 2];
    }
    double rsum = 0;
    for (double r : ranges) rsum += r;
    range_mean += rsum * inv;
    beyond_50m += beyond * inv;
    ground_fraction += ground * inv;
    per_scan_points.push_back(n);
    per_scan_ground.push_back(ground * inv);
    intensity_mean += isum * inv;
    intensity_zero += izero * inv;
    int rings = 0;
    for (int k = 0; k < kRings; ++k) {
      auto& e = elev[static_cast<std::size_t>(k)];
      ring_points[static_cast<std::size_t>(k)] += static_cast<double>(e.size());
      if (e.empty()) continue;
      ++rings;
      std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2), e.end());
      ring_elevation[static_cast<std::size_t>(k)] += e[e.size() / 2];
    }
    rings_mean += rings;
  }

  void finish() {
    if (scans == 0) return;
    const double s = 1.0 / static_cast<double>(scans);
    for (double* v : {&points_mean, &rings_mean, &range_median, &range_mean, &beyond_50m,
                      &ground_fraction, &intensity_mean, &intensity_zero}) {
      *v *= s;
    }
    for (auto& v : ring_points) v *= s;
    for (auto& v : ring_elevation) v *= s;
    for (auto& v : range_hist) v *= s;
    for (auto& v : intensity_hist) v *= s;
  }
};

// A KITTI scan: rings from the azimuth wrap (each ring starts at the front, azimuth rising
// through +-180 deg back to the front), then ordered by elevation so that 0 is the lowest.
rt::Result<std::vector<P>> read_kitti(const std::filesystem::path& file, int& rings_found) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return rt::make_error(file.string() + ": cannot open the KITTI scan");
  in.seekg(0, std::ios::end);
  const auto bytes = static_cast<std::size_t>(in.tellg());
  if (bytes == 0 || bytes % 16 != 0) {
    return rt::make_error(file.string() + ": not a KITTI scan (size " + std::to_string(bytes) +
                          " is not a positive multiple of 16 bytes: float32 x,y,z,reflectance)");
  }
  std::vector<float> raw(bytes / 4);
  in.seekg(0);
  in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(bytes));
  std::vector<P> pts(bytes / 16);
  std::vector<int> file_ring(pts.size());
  int ring = 0;
  double prev = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    pts[i] = {raw[4 * i], raw[4 * i + 1], raw[4 * i + 2], raw[4 * i + 3], -1};
    const double az = std::atan2(pts[i].y, pts[i].x);
    if (i > 0 && prev < 0 && prev > -std::numbers::pi / 2 && az >= 0 && az < std::numbers::pi / 2)
      ++ring;
    prev = az;
    file_ring[i] = ring;
  }
  rings_found = ring + 1;
  // Order the rings found by their median elevation.
  std::vector<std::pair<double, int>> order;
  for (int r = 0; r < rings_found; ++r) {
    std::vector<double> e;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (file_ring[i] == r) e.push_back(std::atan2(pts[i].z, std::hypot(pts[i].x, pts[i].y)));
    }
    std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2), e.end());
    order.emplace_back(e[e.size() / 2], r);
  }
  std::sort(order.begin(), order.end());
  std::vector<int> rank(static_cast<std::size_t>(rings_found));
  for (std::size_t k = 0; k < order.size(); ++k)
    rank[static_cast<std::size_t>(order[k].second)] = static_cast<int>(k);
  for (std::size_t i = 0; i < pts.size(); ++i)
    pts[i].ring = rank[static_cast<std::size_t>(file_ring[i])];
  return pts;
}

rt::Result<std::vector<std::filesystem::path>> kitti_files(const std::filesystem::path& where) {
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_regular_file(where)) {
    files.push_back(where);
  } else if (std::filesystem::is_directory(where)) {
    // A KITTI raw drive folder: its scans.
    auto scans = formats::kitti_scans_in(
        formats::is_kitti_raw_drive(where) ? where / "velodyne_points" / "data" : where);
    if (!scans) return rt::Unexpected<rt::Error>{scans.error()};
    files = std::move(*scans);
  }
  if (files.empty())
    return rt::make_error(where.string() +
                          ": no KITTI .bin scan there (pass a file or a folder of them)");
  return files;
}

std::string fmt(double v, int digits = 4) {
  char b[64];
  std::snprintf(b, sizeof(b), "%.*g", digits, v);
  return b;
}

template <class Array>
std::string json_array(const Array& a) {
  std::string s = "[";
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (i > 0) s += ',';
    s += fmt(a[i], 6);
  }
  return s + "]";
}

std::string json_stats(const Stats& s, int rings_found) {
  std::string j = "{";
  j += "\"scans\":" + std::to_string(s.scans);
  j += ",\"points_per_scan\":{\"mean\":" + fmt(s.points_mean, 8) +
       ",\"min\":" + fmt(s.points_min, 8) + ",\"max\":" + fmt(s.points_max, 8) + "}";
  j += ",\"ring_count\":" + std::to_string(rings_found);
  j += ",\"rings_with_points_mean\":" + fmt(s.rings_mean, 6);
  j += ",\"points_per_ring\":" + json_array(s.ring_points);
  j += ",\"ring_elevation_deg\":" + json_array(s.ring_elevation);
  j += ",\"range_m\":{\"median\":" + fmt(s.range_median, 6) + ",\"mean\":" + fmt(s.range_mean, 6) +
       ",\"fraction_beyond_50m\":" + fmt(s.beyond_50m, 6) + ",\"bin_m\":" + fmt(kRangeBinM) +
       ",\"histogram\":" + json_array(s.range_hist) + "}";
  j += ",\"ground_fraction\":" + fmt(s.ground_fraction, 6);
  j += ",\"per_scan\":{\"points\":" + json_array(s.per_scan_points) +
       ",\"ground_fraction\":" + json_array(s.per_scan_ground) + "}";
  j += ",\"intensity\":{\"mean\":" + fmt(s.intensity_mean, 6) +
       ",\"fraction_zero\":" + fmt(s.intensity_zero, 6) +
       ",\"histogram\":" + json_array(s.intensity_hist) + "}";
  return j + "}";
}

// "sim - KITTI", and relative to KITTI for quantities that are counts or fractions.
std::string difference(double sim, double real, bool relative) {
  std::string s = sim >= real ? "+" : "";
  s += fmt(sim - real, 4);
  if (relative && real != 0) {
    s += sim >= real ? " (+" : " (";
    s += fmt(100.0 * (sim - real) / real, 3);
    s += " %)";
  }
  return s;
}

// The bird's-eye pictures of both, side by side at the same scale.
rt::Status draw_pair(const std::vector<P>& sim, const std::string& sim_label,
                     const std::vector<P>& real, const std::string& real_label,
                     const std::filesystem::path& dir) {
  pictures::BirdsEyeOptions bo;
  bo.range_m = 40.0;
  bo.size_px = 520;
  const std::filesystem::path a = dir / "birds_eye_sim.png", b = dir / "birds_eye_kitti.png";
  for (int k = 0; k < 2; ++k) {
    pictures::BirdsEye pic(bo);
    const auto& pts = k == 0 ? sim : real;
    for (const P& p : pts) pic.add_point(p.x, p.y, p.z);
    pic.add_legend(k == 0 ? sim_label : real_label);
    pic.add_legend(std::to_string(pts.size()) + " points");
    if (auto r = pic.save(k == 0 ? a : b); !r) return r;
  }
  return pictures::save_side_by_side(a, b, dir / "birds_eye_side_by_side.png");
}

}  // namespace

rt::Status run_sim_compare_job(const SimCompareJobOptions& o, const JobOutput& output) {
  auto settings = load_velodyne_settings(config_path(o.config));
  if (!settings) return rt::make_error(settings.error().message);
  const std::filesystem::path calib =
      o.calib.empty() ? settings->calibration : std::filesystem::path(o.calib);
  if (calib.empty())
    return rt::make_error(
        "stac sim-compare needs the calibration of the simulated unit: pass --calib");
  auto calibration = velodyne::load_calibration(calib);
  if (!calibration) return rt::make_error(calibration.error().message);
  auto files = kitti_files(o.kitti);
  if (!files) return rt::make_error(files.error().message);
  std::error_code ec;
  std::filesystem::create_directories(o.report, ec);
  if (ec) return rt::make_error(o.report + ": cannot create the report folder: " + ec.message());

  // Real scans.
  Stats real;
  real.name = "KITTI (real)";
  int real_rings = 0;
  std::vector<P> real_pic;
  for (const auto& f : *files) {
    int rings = 0;
    auto pts = read_kitti(f, rings);
    if (!pts) return rt::make_error(pts.error().message);
    real.add(*pts, o);
    real_rings = std::max(real_rings, rings);
    if (real_pic.empty()) real_pic = std::move(*pts);
  }
  real.finish();

  // Simulated scans, decoded as `stac decode` does.
  auto reader = io::PcapReader::open(
      o.sim, io::PcapFilter{.udp_dst_port = settings->port, .udp_src_port = {}});
  if (!reader) return rt::make_error(reader.error().message);
  velodyne::ScanStream stream(*calibration, settings->assembler, 2);
  Stats sim;
  sim.name = "stac sim";
  int sim_rings = 0;
  std::vector<P> sim_pic, pts;
  std::uint64_t pic_scan = 0;
  auto drain = [&] {
    while (const velodyne::Scan* scan = stream.take()) {
      if (scan->header.complete() &&
          (o.max_scans == 0 || sim.scans < static_cast<std::size_t>(o.max_scans))) {
        pts.clear();
        std::array<bool, kRings> seen{};
        for (const auto& p : scan->points) {
          pts.push_back({p.x, p.y, p.z, p.intensity / 255.0f, p.ring});
          seen[p.ring % kRings] = true;
        }
        sim.add(pts, o);
        sim_rings =
            std::max(sim_rings, static_cast<int>(std::count(seen.begin(), seen.end(), true)));
        if (sim_pic.empty() || sim.scans == 6) {  // a scan a little way into the drive
          sim_pic = pts;
          pic_scan = scan->header.sequence;
        }
      }
      stream.release();
    }
  };
  io::Datagram d;
  while (reader->next(d)) {
    if (stream.add_packet(d.payload, d.stamp_ns)) drain();
  }
  (void)stream.finish();
  drain();
  if (!reader->error().empty()) return rt::make_error(capture_breaks_off(reader->error()));
  if (sim.scans == 0) {
    return rt::make_error(o.sim + ": no complete scan decoded (simulate at least 0.3 s, port " +
                          std::to_string(settings->port) + ")");
  }
  sim.finish();

  // Report.
  const std::filesystem::path dir(o.report);
  std::ostringstream json;
  json << "{\"sim_capture\":\"" << o.sim << "\",\"kitti_scans\":" << files->size()
       << ",\"rules\":{\"mount_height_m\":" << fmt(o.mount_height_m)
       << ",\"ground_below_z_m\":" << fmt(-o.mount_height_m + o.ground_margin_m)
       << ",\"intensity\":\"KITTI reflectance as stored (0..0.99); HDL-64E intensity byte / 255\""
       << ",\"range\":\"3-D distance from the sensor origin\",\"range_bin_m\":" << fmt(kRangeBinM)
       << ",\"intensity_bins\":" << kIntensityBins << "}"
       << ",\"sim\":" << json_stats(sim, sim_rings) << ",\"kitti\":" << json_stats(real, real_rings)
       << "}\n";
  if (auto w = formats::write_text_durably(dir / "realism.json", json.str()); !w)
    return rt::make_error(w.error().message);

  std::ostringstream md;
  md << "# Simulated vs real HDL-64E scans\n\n"
     << "Simulated: " << sim.scans << " complete scans decoded from `" << o.sim
     << "`. Real: " << files->size() << " KITTI scans from `" << o.kitti << "`.\n"
     << "Ground: z < " << fmt(-o.mount_height_m + o.ground_margin_m)
     << " m in the sensor frame (mounted " << fmt(o.mount_height_m) << " m above the ground, "
     << fmt(o.ground_margin_m) << " m margin), the same rule on both.\n"
     << "Intensity: KITTI reflectance as stored (0..0.99 in steps of 0.01); simulated HDL-64E "
        "intensity byte / 255.\n\n"
     << "| quantity | sim | KITTI | sim - KITTI |\n|---|---|---|---|\n";
  auto row = [&](const std::string& what, double a, double b, bool relative = true) {
    md << "| " << what << " | " << fmt(a, 6) << " | " << fmt(b, 6) << " | "
       << difference(a, b, relative) << " |\n";
  };
  row("points per scan (mean)", sim.points_mean, real.points_mean);
  row("points per scan (min)", sim.points_min, real.points_min);
  row("points per scan (max)", sim.points_max, real.points_max);
  const double low = 0.8 * real.points_mean;
  const auto sim_low = std::count_if(sim.per_scan_points.begin(), sim.per_scan_points.end(),
                                     [&](double v) { return v < low; });
  const auto real_low = std::count_if(real.per_scan_points.begin(), real.per_scan_points.end(),
                                      [&](double v) { return v < low; });
  row("scans with < 80 % of KITTI's mean points", static_cast<double>(sim_low),
      static_cast<double>(real_low), false);
  row("rings found", sim_rings, real_rings, false);
  row("points in the lowest ring", sim.ring_points[0], real.ring_points[0]);
  row("points in the highest ring", sim.ring_points[kRings - 1], real.ring_points[kRings - 1]);
  row("lowest ring elevation (deg)", sim.ring_elevation[0], real.ring_elevation[0], false);
  row("highest ring elevation (deg)", sim.ring_elevation[kRings - 1],
      real.ring_elevation[kRings - 1], false);
  row("range median (m)", sim.range_median, real.range_median);
  row("range mean (m)", sim.range_mean, real.range_mean);
  row("fraction beyond 50 m", sim.beyond_50m, real.beyond_50m);
  row("ground fraction", sim.ground_fraction, real.ground_fraction);
  row("intensity mean (0..1)", sim.intensity_mean, real.intensity_mean);
  row("intensity fraction at 0", sim.intensity_zero, real.intensity_zero);
  md << "\n![points per scan](points_per_scan.png)\n![points per "
        "ring](points_per_ring.png)\n![ring "
        "elevation](ring_elevation.png)\n![range](range_histogram.png)\n"
     << "![intensity](intensity_histogram.png)\n![bird's-eye](birds_eye_side_by_side.png)\n";
  if (auto w = formats::write_text_durably(dir / "realism.md", md.str()); !w)
    return rt::make_error(w.error().message);

  auto series = [](const std::string& name, auto first, std::size_t n, double x0, double dx) {
    pictures::ChartSeries s;
    s.name = name;
    for (std::size_t i = 0; i < n; ++i) {
      s.x.push_back(x0 + dx * static_cast<double>(i));
      s.y.push_back(first[i]);
    }
    return s;
  };
  pictures::Chart rings{
      "Points per ring (mean per scan), ring 0 = lowest beam", "ring", "points", {}, 640, 340};
  rings.series = {series("stac sim", sim.ring_points.begin(), kRings, 0, 1),
                  series("KITTI", real.ring_points.begin(), kRings, 0, 1)};
  pictures::Chart per_scan{
      "Points per scan, in scan order (KITTI: its scans)", "scan", "points", {}, 640, 340};
  per_scan.series = {
      series("stac sim", sim.per_scan_points.begin(), sim.per_scan_points.size(), 0, 1),
      series("KITTI", real.per_scan_points.begin(), real.per_scan_points.size(), 0, 1)};
  pictures::Chart elevation{
      "Elevation of each ring (median, deg)", "ring", "deg + 25", {}, 640, 340};
  elevation.series = {series("stac sim", sim.ring_elevation.begin(), kRings, 0, 1),
                      series("KITTI", real.ring_elevation.begin(), kRings, 0, 1)};
  for (auto& ser : elevation.series) {
    for (double& y : ser.y) y += 25.0;  // the chart's y axis starts at 0
  }
  pictures::Chart range{
      "Range histogram (fraction of points per 2 m)", "range (m)", "fraction", {}, 640, 340};
  range.series = {
      series("stac sim", sim.range_hist.begin(), kRangeBins, kRangeBinM / 2, kRangeBinM),
      series("KITTI", real.range_hist.begin(), kRangeBins, kRangeBinM / 2, kRangeBinM)};
  pictures::Chart inten{"Intensity histogram (KITTI reflectance vs HDL-64E byte / 255)",
                        "intensity (0..1)",
                        "fraction",
                        {},
                        640,
                        340};
  inten.series = {series("stac sim", sim.intensity_hist.begin(), kIntensityBins, 0.025, 0.05),
                  series("KITTI", real.intensity_hist.begin(), kIntensityBins, 0.025, 0.05)};
  for (auto [chart, name] :
       {std::pair{&rings, "points_per_ring.png"}, std::pair{&per_scan, "points_per_scan.png"},
        std::pair{&elevation, "ring_elevation.png"}, std::pair{&range, "range_histogram.png"},
        std::pair{&inten, "intensity_histogram.png"}}) {
    if (auto r = pictures::save_chart(*chart, dir / name); !r)
      return rt::make_error(r.error().message);
  }
  if (auto r = draw_pair(sim_pic, "stac sim, scan " + std::to_string(pic_scan), real_pic,
                         "KITTI " + files->front().filename().string(), dir);
      !r) {
    return rt::make_error(r.error().message);
  }
  output.say(rt::formatted(
      "stac sim-compare: %zu simulated scans vs %zu KITTI scans -> %s/realism.md\n"
      "  points/scan  sim %.0f, KITTI %.0f; rings sim %d, KITTI %d\n"
      "  ground       sim %.3f, KITTI %.3f; range median sim %.1f m, KITTI %.1f m\n",
      sim.scans, real.scans, o.report.c_str(), sim.points_mean, real.points_mean, sim_rings,
      real_rings, sim.ground_fraction, real.ground_fraction, sim.range_median, real.range_median));
  if (sim.bad_points + real.bad_points > 0)
    output.say(rt::formatted(
        "  left out     %llu simulated and %llu KITTI points that are NaN, infinite or "
        "beyond %.0f m (a damaged file?)\n",
        static_cast<unsigned long long>(sim.bad_points),
        static_cast<unsigned long long>(real.bad_points), kMaxRangeM));
  return {};
}

}  // namespace stac::offline

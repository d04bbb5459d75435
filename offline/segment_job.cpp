// The segment job (segment_job.hpp): one scan read (a KITTI file, or scan N of a recorded drive),
// segmented, and what was asked for written.
#include "offline/segment_job.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/velodyne/scan_stream.hpp"
#include "formats/kitti_files.hpp"
#include "formats/recorded_drive.hpp"
#include "perception/segmentation/segmenter.hpp"
#include "pictures/birds_eye.hpp"
#include "rt/clock.hpp"
#include "rt/formatted.hpp"
#include "settings/settings.hpp"

namespace stac::offline {

using namespace stac::settings;
using namespace stac::formats;
namespace {

rt::Status write_csv(const std::string& path, const segmentation::Segments& out) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return rt::make_error(path + ": cannot write (is the folder there?)");
  std::fprintf(f,
               "id,points,centroid_x,centroid_y,centroid_z,box_x,box_y,length,width,height,yaw,z_"
               "min,z_max\n");
  for (std::size_t i = 0; i < out.segments.size(); ++i) {
    const auto& s = out.segments[i];
    std::fprintf(f, "%zu,%u,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.3f,%.3f\n", i, s.count,
                 s.centroid[0], s.centroid[1], s.centroid[2], s.box.cx, s.box.cy, s.box.length,
                 s.box.width, s.box.height, s.box.yaw, s.z_min, s.z_max);
  }
  if (std::fclose(f) != 0) return rt::make_error(path + ": write failed");
  return {};
}

// Segments one scan and writes what was asked for.
rt::Status report(const SegmentJobOptions& o, const JobOutput& output,
                  const segmentation::SegmenterConfig& config,
                  const segmentation::PointView& points, const std::string& what) {
  segmentation::Segmenter segmenter(config);
  segmentation::Segments out = segmenter.make_segments();
  segmenter.segment(points, out);  // warm-up: first touch of the grids
  const auto t0 = std::chrono::steady_clock::now();
  const std::int64_t cpu0 = rt::thread_cpu_ns();
  segmenter.segment(points, out);
  const double cpu = static_cast<double>(rt::thread_cpu_ns() - cpu0) * 1e-6;
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  if (!o.out.empty()) {
    if (auto r = write_csv(o.out, out); !r) return rt::make_error(r.error().message);
  }
  const auto& k = out.counters;
  if (!o.png.empty()) {
    pictures::BirdsEye picture(
        pictures::BirdsEyeOptions{.range_m = o.view_range_m, .size_px = 1000, .height_bar = false});
    std::vector<int> owner(points.count, -1);
    for (std::size_t i = 0; i < out.segments.size(); ++i) {
      for (const std::uint32_t p : out.indices(out.segments[i])) owner[p] = static_cast<int>(i);
    }
    for (std::size_t i = 0; i < points.count; ++i) {
      float x, y, z;
      points.read(i, x, y, z);
      if (owner[i] < 0) picture.add_point(x, y, pictures::Bgr{90, 90, 90});
    }
    for (std::size_t i = 0; i < points.count; ++i) {
      float x, y, z;
      points.read(i, x, y, z);
      if (owner[i] >= 0)
        picture.add_point(x, y, pictures::segment_colour(static_cast<std::size_t>(owner[i])));
    }
    for (std::size_t i = 0; i < out.segments.size(); ++i) {
      const auto& b = out.segments[i].box;
      const pictures::Bgr c = pictures::segment_colour(i);
      picture.add_box(b.cx, b.cy, std::max(b.length, 0.1f), std::max(b.width, 0.1f), b.yaw, c);
    }
    picture.add_legend(what);
    picture.add_legend(std::to_string(out.segments.size()) +
                       " segments (coloured, oriented boxes), " +
                       std::to_string(config.cell_m).substr(0, 4) + " m cells");
    picture.add_legend("grey: ground and points in no segment");
    picture.add_legend("rings every 10 m; x forward is up");
    if (auto r = picture.save(o.png); !r) return rt::make_error(r.error().message);
  }
  output.say(rt::formatted(
      "stac segment: %s\n"
      "  points     %llu in: ground %llu, obstacle %llu (in segments %zu), above %llu,\n"
      "             below ground %llu, out of range %llu, invalid %llu\n"
      "  cells      %llu occupied, %llu obstacle\n"
      "  segments   %zu of %llu clusters (%llu more parts split off),\n"
      "             dropped: too small %llu, too large %llu\n"
      "  overflow   points %llu, cells %llu, segments %llu\n"
      "  time       %.2f ms wall, %.2f ms CPU (one thread, after a warm-up scan)\n",
      what.c_str(), static_cast<unsigned long long>(k.points_in),
      static_cast<unsigned long long>(k.ground_points),
      static_cast<unsigned long long>(k.obstacle_points), out.point_indices.size(),
      static_cast<unsigned long long>(k.ignored_above),
      static_cast<unsigned long long>(k.ignored_below),
      static_cast<unsigned long long>(k.ignored_out_of_range),
      static_cast<unsigned long long>(k.ignored_invalid),
      static_cast<unsigned long long>(k.occupied_cells),
      static_cast<unsigned long long>(k.obstacle_cells), out.segments.size(),
      static_cast<unsigned long long>(k.clusters),
      static_cast<unsigned long long>(k.split_segments),
      static_cast<unsigned long long>(k.dropped_too_small),
      static_cast<unsigned long long>(k.dropped_too_large),
      static_cast<unsigned long long>(k.ignored_over_capacity),
      static_cast<unsigned long long>(k.dropped_cell_overflow),
      static_cast<unsigned long long>(k.dropped_segment_overflow), ms, cpu));
  return {};
}

// Scan `o.scan` of a recorded drive (a capture, decoded with the project's driver, or a KITTI raw
// drive folder; formats/recorded_drive.hpp), segmented as it was recorded (no deskew).
rt::Status segment_drive(const SegmentJobOptions& o, const JobOutput& output,
                         const segmentation::SegmenterConfig& config) {
  auto settings = load_pipeline_settings(config_path(o.config));
  if (!settings) return rt::make_error(settings.error().message);
  auto drive = RecordedDrive::open(o.in, *settings, {o.calib, "", false});
  if (!drive) return rt::make_error(drive.error().message);
  std::optional<rt::Status> done;
  auto read = drive->for_each_scan([&](velodyne::Scan& scan, std::int64_t) {
    if (drive->scans() - 1 != static_cast<std::uint64_t>(o.scan)) return true;
    const segmentation::PointView view{&scan.points.data()->x, scan.points.size(),
                                       sizeof(velodyne::Point)};
    done = report(o, output, config, view,
                  o.in + " scan " + std::to_string(o.scan) + " (sequence " +
                      std::to_string(scan.header.sequence) + ")");
    return false;
  });
  if (!read) return rt::make_error(read.error().message);
  if (done) return *done;
  if (drive->scans() == 0) return rt::make_error(drive->nothing_decoded());
  return rt::make_error(o.in + ": holds " + std::to_string(drive->scans()) +
                        " complete scans; --scan " + std::to_string(o.scan) +
                        " is not among them (scans count from 0)");
}

// A pcap or pcapng file by its first four bytes (whatever its name); anything else is read as a
// KITTI scan, which checks its size.
bool is_capture(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char m[4] = {};
  if (!in.read(reinterpret_cast<char*>(m), 4)) return false;
  const std::uint32_t le =
      m[0] | (m[1] << 8) | (m[2] << 16) | (static_cast<std::uint32_t>(m[3]) << 24);
  for (const std::uint32_t magic : {0xa1b2c3d4u, 0xa1b23c4du, 0x0a0d0d0au}) {
    const std::uint32_t swapped = ((magic & 0xffu) << 24) | ((magic & 0xff00u) << 8) |
                                  ((magic >> 8) & 0xff00u) | (magic >> 24);
    if (le == magic || le == swapped) return true;
  }
  return false;
}

}  // namespace

rt::Status run_segment_job(const SegmentJobOptions& o, const JobOutput& output) {
  auto config = load_segmentation_settings(config_path(o.config));
  if (!config) return rt::make_error(config.error().message);
  if (o.scan < 0) return rt::make_error("--scan must be >= 0");
  if (o.view_range_m <= 0) return rt::make_error("--view-range must be > 0");
  if (is_capture(o.in) || std::filesystem::is_directory(o.in))
    return segment_drive(o, output, *config);
  auto cloud = load_kitti_scan(o.in);
  if (!cloud) return rt::make_error(cloud.error().message);
  const segmentation::PointView view{cloud->data(), cloud->size() / 4, 4 * sizeof(float)};
  return report(o, output, *config, view, o.in);
}

}  // namespace stac::offline

#include "formats/recorded_drive.hpp"

#include <utility>

#include "formats/capture_input.hpp"
#include "formats/capture_sensor.hpp"
#include "rt/clock.hpp"

namespace stac::formats {
rt::Result<RecordedDrive> RecordedDrive::open(const std::filesystem::path& in,
                                              settings::PipelineSettings& settings,
                                              const RecordedDriveOptions& options) {
  settings::VelodyneSettings& vs = settings.velodyne;
  RecordedDrive d;
  d.in_ = in;
  if (is_kitti_raw_drive(in)) {
    auto k = open_kitti_raw_drive(in);
    if (!k) return rt::Unexpected<rt::Error>{k.error()};
    d.kitti_ = std::move(*k);
  } else if (std::filesystem::is_directory(in)) {
    return rt::make_error(in.string() +
                          ": a folder but not a KITTI raw drive (it has no "
                          "velodyne_points/data/ of NNNNNNNNNN.bin scans); give a capture or a "
                          "drive folder");
  }
  if (!options.calib.empty())
    vs.calibration =
        options.calib == "stream" ? std::filesystem::path{} : std::filesystem::path(options.calib);
  if (auto m = apply_sensor_option(vs, options.sensor, !options.calib.empty()); !m)
    return rt::make_error("--sensor: " + m.error().message);
  std::optional<velodyne::Calibration> calibration;
  if (!d.kitti_) {
    auto c = capture_sensor(vs, in, !options.calib.empty());
    if (!c) return rt::Unexpected<rt::Error>{c.error()};
    calibration = std::move(*c);
  }
  if (options.deskew && !d.kitti_) {
    auto p = load_capture_poses(in, settings.ego);
    if (!p) return rt::Unexpected<rt::Error>{p.error()};
    d.poses_ = std::move(*p);
  } else if (options.deskew && d.kitti_->has_oxts) {
    // The OXTS records are its INS, its calib_imu_to_velo.txt the mounting.
    auto p = load_kitti_raw_poses(in, settings.ego);
    if (!p) return rt::Unexpected<rt::Error>{p.error()};
    d.poses_ = std::move(*p);
  }
  if (!d.kitti_) {
    auto r = io::PcapReader::open(in, io::PcapFilter{.udp_dst_port = vs.port, .udp_src_port = {}});
    if (!r) return rt::Unexpected<rt::Error>{r.error()};
    d.reader_.emplace(std::move(*r));
    d.stream_ = std::make_unique<velodyne::ScanStream>(*calibration, vs.assembler, 2);
    d.port_ = vs.port;
  }
  return d;
}

rt::Status RecordedDrive::for_each_scan(
    const std::function<bool(velodyne::Scan&, std::int64_t)>& on_scan,
    const std::function<void(double, double)>& progress) {
  const auto report = [&](double done, double total) {
    if (progress) progress(done, total);
  };
  if (kitti_) {
    velodyne::Scan scan(kitti_->max_points);  // the one scan, reused
    const auto n = static_cast<double>(kitti_->scans.size());
    for (std::size_t i = 0; i < kitti_->scans.size(); ++i) {
      const std::int64_t c0 = rt::thread_cpu_ns();
      auto c = load_kitti_drive_scan(*kitti_, i, scan);
      if (!c) return rt::Unexpected<rt::Error>{c.error()};
      kitti_points_.points += c->points;
      kitti_points_.refused += c->refused;
      ++scans_;
      const bool more = on_scan(scan, rt::thread_cpu_ns() - c0);
      report(static_cast<double>(i + 1), n);
      if (!more) return {};
    }
    return {};
  }
  const auto size = static_cast<double>(std::filesystem::file_size(in_));
  std::int64_t decode_ns = 0;  // since the last scan handed on
  io::Datagram d;
  bool more = true;
  while (more && reader_->next(d)) {
    const std::int64_t c0 = rt::thread_cpu_ns();
    const bool closed = stream_->add_packet(d.payload, d.stamp_ns);
    decode_ns += rt::thread_cpu_ns() - c0;
    if (closed) {
      while (velodyne::Scan* scan = stream_->take()) {
        if (more && scan->header.complete()) {
          ++scans_;
          more = on_scan(*scan, decode_ns);
          decode_ns = 0;
        }
        stream_->release();
      }
    }
    report(static_cast<double>(reader_->bytes_read()), size);
  }
  return {};
}

std::string RecordedDrive::nothing_decoded() const {
  if (!reader_) return in_.string() + ": no scan in the drive";
  return nothing_decoded_reason(in_.string(), reader_->counters(), stream_->assembler().counters(),
                                port_);
}

}  // namespace stac::formats

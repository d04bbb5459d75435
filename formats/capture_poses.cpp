#include "formats/capture_poses.hpp"

#include <algorithm>
#include <variant>

#include "drivers/applanix/capture_reader.hpp"
#include "formats/kitti_raw.hpp"

namespace stac::formats {

rt::Result<std::optional<CapturePoses>> load_capture_poses(const std::filesystem::path& capture,
                                                           const settings::EgoSettings& settings) {
  // First pass: how many fixes, to size the history for the whole drive.
  std::uint64_t group1 = 0;
  {
    auto reader = applanix::CaptureReader::open(capture, settings.ins_port);
    if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
    applanix::Parsed m;
    while (reader->next(m)) group1 += std::holds_alternative<applanix::Group1>(m.content) ? 1 : 0;
    if (!reader->error().empty()) return rt::make_error(reader->error());
    const applanix::ParserCounters& pc = reader->parser().counters();
    const std::uint64_t bad = pc.bad_checksum + pc.bad_length + pc.bad_terminator + pc.malformed;
    if (group1 == 0 && bad > 0)
      return rt::make_error(capture.string() + ": the INS stream on port " +
                            std::to_string(settings.ins_port) + " has " + std::to_string(bad) +
                            " messages dropped (" + std::to_string(pc.bad_checksum) +
                            " bad checksums) and no valid Group 1: it is corrupt; --no-deskew "
                            "processes the scans without it");
  }
  if (group1 == 0) return std::optional<CapturePoses>{};

  CapturePoses out;
  out.group1 = group1;
  out.frame = std::make_unique<ego::LocalFrame>(settings.origin);
  ego::PoseHistoryConfig hc = settings.history;
  hc.capacity = std::max<std::size_t>(hc.capacity, static_cast<std::size_t>(group1) + 16);
  out.history = std::make_unique<ego::PoseHistory>(hc);
  ego::EgoEstimator estimator(settings.estimator, *out.frame, *out.history);
  auto reader = applanix::CaptureReader::open(capture, settings.ins_port);
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  applanix::Parsed m;
  while (reader->next(m)) estimator.add_ins(m, reader->parser());
  out.counters = estimator.counters();
  out.parser = reader->parser().counters();
  return std::optional<CapturePoses>{std::move(out)};
}

rt::Result<CapturePoses> load_kitti_raw_poses(const std::filesystem::path& drive,
                                              settings::EgoSettings& settings) {
  auto records = read_kitti_oxts(drive);
  if (!records) return rt::Unexpected<rt::Error>{records.error()};
  CapturePoses out;
  if (const std::filesystem::path calib = find_kitti_imu_to_velo(drive); !calib.empty()) {
    auto velo_T_imu = read_kitti_imu_to_velo(calib);
    if (!velo_T_imu) return rt::Unexpected<rt::Error>{velo_T_imu.error()};
    settings.deskew.vehicle_T_sensor = velo_T_imu->inverse();
    out.mounting = calib.string();
  } else {
    out.mounting = "the config's ego extrinsics (no calib_imu_to_velo.txt in the drive or above)";
  }
  out.group1 = records->size();
  out.frame = std::make_unique<ego::LocalFrame>(settings.origin);
  ego::PoseHistoryConfig hc = settings.history;
  hc.capacity = std::max<std::size_t>(hc.capacity, records->size() + 16);
  // A synced drive has a record per scan, at 10 Hz (about 103 ms apart in KITTI's), not the
  // Applanix's 200 Hz: interpolated across up to 2.5 periods.
  hc.max_gap_ns = std::max<std::int64_t>(hc.max_gap_ns, 250'000'000);
  out.history = std::make_unique<ego::PoseHistory>(hc);
  ego::EgoEstimator estimator(settings.estimator, *out.frame, *out.history);
  for (const OxtsRecord& r : *records) estimator.add_fix(oxts_fix(r));
  out.counters = estimator.counters();
  return out;
}

}  // namespace stac::formats

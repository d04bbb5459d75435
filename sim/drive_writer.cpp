// A simulated drive written as the real devices' bytes (pcap) plus its ground truth (stac sim).
#include "sim/drive_writer.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>

#include "drivers/can/candump.hpp"
#include "drivers/can/config.hpp"
#include "drivers/io/pcap_writer.hpp"
#include "drivers/velodyne/decoder.hpp"
#include "drivers/velodyne/position.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "drivers/velodyne/status.hpp"
#include "ego/ego_estimator.hpp"
#include "formats/kitti_raw.hpp"
#include "formats/kitti_tracklets.hpp"
#include "rt/formatted.hpp"
#include "settings/settings.hpp"
#include "sim/ins.hpp"
#include "sim/run.hpp"
#include "sim/vehicle_can.hpp"

namespace stac::sim {

using namespace stac::settings;
namespace {

using rt::formatted;

// The POS LV's Real-Time Data stream (port 5602) into the pcap: one TCP connection from the
// vehicle computer (handshake just before the first message), then each message as one segment
// from the POS; or with --ins-udp each message as one broadcast datagram to port 5602.
class InsPcapStream {
 public:
  static constexpr std::uint32_t kPosIp = 0xC0A83564;        // 192.168.53.100, the POS LV
  static constexpr std::uint32_t kHostIp = 0xC0A8350A;       // 192.168.53.10, the vehicle computer
  static constexpr std::uint32_t kBroadcastIp = 0xC0A835FF;  // 192.168.53.255
  static constexpr std::uint16_t kPort = 5602;               // Real-Time Data
  static constexpr std::uint16_t kHostPort = 50'602;
  static constexpr std::uint8_t kTcpPsh = 0x08;

  InsPcapStream(io::PcapWriter& pcap, bool udp) : pcap_(pcap), udp_(udp) {}

  rt::Status write(const sim::InsMessage& m) {
    if (udp_) {
      io::Datagram d;
      d.payload = m.bytes;
      d.stamp_ns = m.stamp_ns;
      d.src_ip = kPosIp;
      d.dst_ip = kBroadcastIp;
      d.src_port = d.dst_port = kPort;
      return pcap_.write_udp(d);
    }
    if (!connected_) {
      connected_ = true;
      const std::uint32_t host_isn = 0x0BADC0DE;
      for (auto w :
           {pcap_.write_tcp(segment(m.stamp_ns - 3'000'000, false, host_isn, io::kTcpSyn)),
            pcap_.write_tcp(
                segment(m.stamp_ns - 2'000'000, true, kPosIsn, io::kTcpSyn | io::kTcpAck)),
            pcap_.write_tcp(segment(m.stamp_ns - 1'000'000, false, host_isn + 1, io::kTcpAck))}) {
        if (!w) return w;
      }
    }
    io::TcpSegment s = segment(m.stamp_ns, true, seq_, io::kTcpAck | kTcpPsh);
    s.payload = m.bytes;
    seq_ += static_cast<std::uint32_t>(m.bytes.size());
    return pcap_.write_tcp(s);
  }

 private:
  static constexpr std::uint32_t kPosIsn = 0x1A2B3C4D;
  static io::TcpSegment segment(std::int64_t stamp_ns, bool from_pos, std::uint32_t seq,
                                std::uint8_t flags) {
    io::TcpSegment s;
    s.stamp_ns = stamp_ns;
    s.src_ip = from_pos ? kPosIp : kHostIp;
    s.dst_ip = from_pos ? kHostIp : kPosIp;
    s.src_port = from_pos ? kPort : kHostPort;
    s.dst_port = from_pos ? kHostPort : kPort;
    s.seq = seq;
    s.flags = flags;
    return s;
  }

  io::PcapWriter& pcap_;
  bool udp_;
  bool connected_ = false;
  std::uint32_t seq_ = kPosIsn + 1;  // the SYN takes one sequence number
};

// The vehicle CAN bus of the run and its candump log, opened before the simulation so that a
// bad can: configuration or an unwritable path stops it at once.
struct CanLog {
  sim::VehicleCanSim bus;
  can::CandumpWriter log;
};

rt::Result<CanLog> open_can_log(const DriveOptions& o, const sim::SimRun& run,
                                const sim::RunConfig& rc) {
  const auto config = load_can_settings(config_path(o.config));
  if (!config) return rt::Unexpected<rt::Error>{config.error()};
  const auto db = can::load_dbc(config->dbc);
  if (!db) return rt::Unexpected<rt::Error>{db.error()};
  sim::VehicleCanConfig vc;
  vc.start_ns = rc.start_ns;
  auto bus =
      sim::VehicleCanSim::create(*db, config->signals, vc, [&run](double t) { return run.ego(t); });
  if (!bus)
    return rt::make_error(config->dbc.string() + ": " + bus.error().message +
                          " (see can: in the configuration)");
  auto log = can::CandumpWriter::open(o.can, config->socketcan.interface);
  if (!log) return rt::Unexpected<rt::Error>{log.error()};
  return CanLog{std::move(*bus), std::move(*log)};
}

// Writes the vehicle CAN frames of the whole run; says what it wrote.
rt::Status write_can_log(CanLog& c, const std::string& path, const sim::RunConfig& rc,
                         const DriveOutput& out) {
  const std::int64_t end_ns = rc.start_ns + std::llround(rc.duration_s * 1e9);
  can::Frame f;
  while (c.bus.next_stamp_ns() <= end_ns) {
    if (c.bus.next(f) && !c.log.write(f)) return rt::make_error(path + ": write failed");
  }
  if (!c.log.close()) return rt::make_error(path + ": write failed");
  std::string line =
      formatted("  CAN: %llu frames -> %s",
                static_cast<unsigned long long>(c.bus.counters().frames), path.c_str());
  if (c.bus.counters().unencodable > 0) {
    line += formatted(" (%llu values outside their DBC signal's range not sent)",
                      static_cast<unsigned long long>(c.bus.counters().unencodable));
  }
  out.summary(line);
  return {};
}

// A truth scan's sweep and the cars, pedestrians and bicyclists in it.
struct SweepTruth {
  std::int64_t start_ns = 0, end_ns = 0;
  std::vector<std::pair<std::uint32_t, sim::ObjectClass>> objects;
};

// A KITTI frame: its sweep (which starts and ends facing backward) and its time (facing forward).
struct KittiFrame {
  std::int64_t start_ns = 0, mid_ns = 0, end_ns = 0;
};

// KITTI raw's labels of a simulated drive: every car, pedestrian and bicyclist of the truth scans
// whose sweeps overlap a KITTI frame's sweep (the truth scans start facing forward, half a turn
// from the frame's), posed at the frame's time in the velodyne's frame (the centre of its box's
// bottom, its yaw), one tracklet per run of consecutive frames.
std::vector<formats::Tracklet> sim_tracklets(const sim::SimRun& run, const sim::RunConfig& rc,
                                             const std::vector<SweepTruth>& sweeps,
                                             const std::vector<KittiFrame>& frames) {
  const auto& actors = run.world().actors();
  std::map<std::uint32_t, std::size_t> index;  // actor id -> index
  for (std::size_t i = 0; i < actors.size(); ++i) index[actors[i].id] = i;
  std::vector<formats::Tracklet> out;
  std::map<std::uint32_t, std::pair<std::size_t, std::size_t>> open;  // id -> (tracklet, frame)
  std::size_t s = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const std::int64_t mid = frames[f].mid_ns;
    while (s < sweeps.size() && sweeps[s].end_ns < frames[f].start_ns) ++s;
    std::map<std::uint32_t, sim::ObjectClass> seen;  // in the truth scans the sweep overlaps
    for (std::size_t k = s; k < sweeps.size() && sweeps[k].start_ns <= frames[f].end_ns; ++k)
      for (const auto& [id, cls] : sweeps[k].objects) seen.emplace(id, cls);
    if (seen.empty()) continue;
    const double t = static_cast<double>(mid - rc.start_ns) * 1e-9;
    const sim::EgoState e = run.ego(t);
    const Eigen::Isometry3d world_T_sensor = Eigen::Translation3d(e.x, e.y, e.z) *
                                             Eigen::AngleAxisd(e.yaw, Eigen::Vector3d::UnitZ()) *
                                             Eigen::AngleAxisd(e.pitch, Eigen::Vector3d::UnitY()) *
                                             Eigen::AngleAxisd(e.roll, Eigen::Vector3d::UnitX()) *
                                             Eigen::Translation3d(0, 0, rc.lidar.mount_height_m);
    const Eigen::Isometry3d sensor_T_world = world_T_sensor.inverse();
    for (const auto& [id, cls] : seen) {
      const auto it = index.find(id);
      if (it == index.end()) continue;
      const sim::Actor& a = actors[it->second];
      const sim::Pose p = run.world().actor_pose(it->second, t);
      const Eigen::Vector3d bottom = sensor_T_world * Eigen::Vector3d(p.x, p.y, p.z);
      const Eigen::Vector3d heading =
          sensor_T_world.linear() * Eigen::Vector3d(std::cos(p.yaw), std::sin(p.yaw), 0);
      formats::TrackletPose pose;
      pose.tx = bottom.x(), pose.ty = bottom.y(), pose.tz = bottom.z();
      pose.rz = std::atan2(heading.y(), heading.x());
      auto o = open.find(id);
      if (o == open.end() || o->second.second + 1 != f) {
        formats::Tracklet tr;
        tr.object_type = cls == sim::ObjectClass::kCar          ? "Car"
                         : cls == sim::ObjectClass::kPedestrian ? "Pedestrian"
                                                                : "Cyclist";
        tr.h = a.size.z, tr.w = a.size.y, tr.l = a.size.x;
        tr.first_frame = static_cast<std::uint32_t>(f);
        out.push_back(std::move(tr));
        o = open.insert_or_assign(id, std::pair{out.size() - 1, f}).first;
      }
      out[o->second.first].poses.push_back(pose);
      o->second.second = f;
    }
  }
  return out;
}

// The virtual sensor: an HDL-64E S2.1 (S3 in dual return) unless --model names another, with its
// settings and the calibration it casts with.
struct VirtualSensor {
  VelodyneSettings settings;
  velodyne::Model model;
  velodyne::Calibration calibration;
};

rt::Result<VirtualSensor> virtual_sensor(const DriveOptions& o) {
  auto settings = load_velodyne_settings(config_path(o.config));
  if (!settings) return rt::make_error(settings.error().message);
  velodyne::Model model = o.dual_return ? velodyne::Model::kS3 : velodyne::Model::kS2_1;
  if (!o.model.empty()) {
    const auto m = velodyne::parse_model(o.model);
    if (!m)
      return rt::make_error("--model '" + o.model + "': use " +
                            std::string(velodyne::model_names()));
    model = *m;
    if (o.dual_return && !velodyne::traits(model).supports_dual_return)
      return rt::make_error("--dual-return: the " + std::string(velodyne::traits(model).name) +
                            " has no dual-return mode (the S3, HDL-32E, VLP-16 and VLP-32C have)");
  }
  if (auto u = use_velodyne_model(*settings, model, !o.calib.empty()); !u)
    return rt::make_error(u.error().message);
  const std::filesystem::path calib_path =
      o.calib.empty() ? settings->calibration : std::filesystem::path(o.calib);
  if (calib_path.empty()) return rt::make_error("stac sim needs a calibration file: pass --calib");
  auto loaded = velodyne::load_calibration(calib_path);
  if (!loaded) return rt::make_error(loaded.error().message);
  if (auto fits = velodyne::check_calibration_for(*loaded, model); !fits)
    return rt::make_error(fits.error().message);
  return VirtualSensor{std::move(*settings), model, velodyne::lasers_of(*loaded, model)};
}

// The run's configuration from the options and the sensor.
rt::Result<sim::RunConfig> run_config(const DriveOptions& o, const VirtualSensor& sensor) {
  sim::RunConfig rc;
  rc.scenario = o.scenario;
  for (const std::string& kind : o.without) {
    sim::ObjectClass c{};
    if (!sim::class_from_name(kind, c))
      return rt::make_error(
          "--without " + kind +
          ": not a simulator kind (car, pedestrian, bicyclist, building, wall, fence, "
          "tree, bush, pole, sign, bin, clutter)");
    rc.without.push_back(c);
  }
  rc.seed = o.seed;
  rc.duration_s = o.duration_s;
  rc.cut_angle = sensor.settings.assembler.cut_angle;
  rc.lidar.seed = o.seed;
  rc.lidar.dual_return = o.dual_return;
  rc.lidar.model = sensor.model;
  return rc;
}

// --kitti-raw: the packets decoded as a driver would, each complete scan written with the OXTS
// record of its mid-sweep time (the sim's Group 1 there) and the sensor's mounting.
rt::Status open_kitti_raw(const DriveOptions& o, const sim::RunConfig& rc,
                          const VirtualSensor& sensor,
                          std::optional<formats::KittiRawWriter>& kitti,
                          std::optional<velodyne::ScanStream>& kitti_scans) {
  Eigen::Isometry3d velo_T_imu = Eigen::Isometry3d::Identity();
  velo_T_imu.translation() = Eigen::Vector3d(0, 0, -rc.lidar.mount_height_m);
  auto w = formats::KittiRawWriter::create(o.kitti_raw, velo_T_imu);
  if (!w) return rt::make_error(w.error().message);
  kitti.emplace(std::move(*w));
  // KITTI's sweeps start and end facing backward (timestamps_start/_end.txt), facing
  // forward at the frame's time (timestamps.txt).
  velodyne::ScanAssemblerConfig sweep_framing = sensor.settings.assembler;
  sweep_framing.cut_angle = 18000;
  kitti_scans.emplace(sensor.calibration, sweep_framing, 2);
  return {};
}

// The last 6 bytes of each data packet. An S2.1/S3 sends GPS time past the hour and the status
// cycle, with the calibration the sim casts with in its dump (so `--calib stream` decodes the
// capture); an HDL-32E / VLP sends GPS time, its return mode and product id instead
// (docs/velodyne.md).
class PacketTrailer {
 public:
  static rt::Result<PacketTrailer> create(const DriveOptions& o, const VirtualSensor& sensor,
                                          const sim::RunConfig& rc) {
    PacketTrailer p;
    p.model_ = sensor.model;
    p.dual_return_ = o.dual_return;
    p.factory_ = velodyne::traits(sensor.model).trailer == velodyne::TrailerKind::kFactory;
    if (p.factory_) return p;
    velodyne::SensorStatus status;
    status.gps_raw = 'A';  // PPS and NMEA
    status.temperature_c = 42;
    status.firmware = 0x47;
    velodyne::UnitParameters unit;
    unit.upper_noise_threshold = unit.lower_noise_threshold = 24;
    unit.calibration_date = velodyne::DateTime{2025, 6, 2, 10, 30, 0};
    unit.humidity = 30;
    unit.rpm = static_cast<std::uint16_t>(std::lround(rc.lidar.rpm));
    unit.fov_end = 36000;
    unit.run_hours = 1200;
    unit.ip_source = {192, 168, 3, 43};
    unit.ip_destination = {255, 255, 255, 255};
    unit.return_mode =
        o.dual_return ? velodyne::ReturnMode::kDual : velodyne::ReturnMode::kStrongest;
    unit.power_level = 0xA8;
    unit.warnings = 0x60;  // PPS and GPS time present
    auto t = velodyne::StatusTrailerWriter::create(sensor.model, status, unit, sensor.calibration);
    if (!t)
      return rt::make_error("the calibration cannot be sent in the status cycle: " +
                            t.error().message);
    p.status_.emplace(std::move(*t));
    return p;
  }
  // An HDL-32E / VLP (factory bytes), which also sends position packets.
  [[nodiscard]] bool factory() const noexcept { return factory_; }
  void write(std::uint8_t* t, std::int64_t utc_ns) {
    if (!factory_) return status_->write(t, utc_ns);
    velodyne::store_u32(t, velodyne::usec_past_hour(utc_ns));
    t[4] = dual_return_ ? velodyne::kReturnDual : velodyne::kReturnStrongest;
    t[5] = velodyne::traits(model_).product_id;
  }

 private:
  velodyne::Model model_{};
  bool dual_return_ = false;
  bool factory_ = false;
  std::optional<velodyne::StatusTrailerWriter> status_;
};

// An HDL-32E / VLP position packet (port 8308) at utc_ns: its GPS time and the receiver's
// $GPRMC, here the INS's fix; `position` is the packet's buffer.
rt::Status write_position(io::PcapWriter& pcap, const sim::InsSim& ins, std::int64_t start_ns,
                          std::int64_t utc_ns,
                          std::array<std::uint8_t, velodyne::kPositionPacketSize>& position) {
  const applanix::Group1 g = ins.group1_at(static_cast<double>(utc_ns - start_ns) * 1e-9);
  velodyne::NmeaFix fix;
  fix.valid = true;
  const std::int64_t day_ns = 86'400'000'000'000LL;
  const std::int64_t days = utc_ns >= 0 ? utc_ns / day_ns : (utc_ns - day_ns + 1) / day_ns;
  fix.time_of_day_ns = utc_ns - days * day_ns;
  const std::chrono::year_month_day ymd{std::chrono::sys_days{std::chrono::days{days}}};
  fix.date = velodyne::NmeaDate{static_cast<int>(ymd.year()),
                                static_cast<int>(static_cast<unsigned>(ymd.month())),
                                static_cast<int>(static_cast<unsigned>(ymd.day()))};
  fix.latitude_deg = g.latitude_deg;
  fix.longitude_deg = g.longitude_deg;
  fix.speed_mps = std::max(0.0, static_cast<double>(g.speed_mps));
  fix.course_deg = std::fmod(static_cast<double>(g.track_deg) + 360.0, 360.0);
  if (auto w = velodyne::write_position_packet(velodyne::usec_past_hour(utc_ns),
                                               velodyne::PpsStatus::kLocked, fix, position);
      !w) {
    return rt::make_error(std::string("position packet: ") + velodyne::to_string(w.error()));
  }
  io::Datagram p;
  p.payload = position;
  p.stamp_ns = utc_ns;
  p.src_ip = 0xC0A801C9;  // 192.168.1.201, a VLP's factory address
  p.dst_ip = 0xFFFFFFFF;
  p.src_port = velodyne::kPortPosition;
  p.dst_port = velodyne::kPortPosition;
  return pcap.write_udp(p);
}

// Data packet `bytes` as the sensor sends it, received at stamp_ns.
io::Datagram data_datagram(const std::array<std::uint8_t, velodyne::kPacketSize>& bytes,
                           std::int64_t stamp_ns, bool factory) {
  io::Datagram d;
  d.payload = bytes;
  d.stamp_ns = stamp_ns;
  d.src_ip = factory ? 0xC0A801C9 : 0xC0A8032B;  // 192.168.1.201 (VLP) / 192.168.3.43 (64E)
  d.dst_ip = 0xFFFFFFFF;
  d.src_port = velodyne::kPortData;
  d.dst_port = velodyne::kPortData;
  return d;
}

// Where a drive's packets and scans go besides the pcap: the truth file, the INS stream in the
// pcap and the KITTI raw folder, with what was written.
struct DriveRecorder {
  DriveRecorder(const sim::RunConfig& rc_in, const sim::InsConfig& ic, std::ofstream& truth_in,
                std::optional<formats::KittiRawWriter>& kitti_in,
                std::optional<velodyne::ScanStream>& kitti_scans_in, sim::InsSim& ins_in)
      : rc(rc_in),
        origin_lat_lon_alt{ic.origin.lat_deg, ic.origin.lon_deg, ic.origin.alt_m},
        truth(truth_in),
        kitti(kitti_in),
        kitti_scans(kitti_scans_in),
        ins(ins_in) {}

  // A truth scan closed: its line in the truth file (and its sweep for the tracklets).
  void on_scan(const sim::TruthScan& s) {
    truth << sim::to_json(s, origin_lat_lon_alt) << '\n';
    if (kitti) {
      SweepTruth& w = sweeps.emplace_back();
      w.start_ns = s.start_ns, w.end_ns = s.end_ns;
      for (const sim::TruthObject& obj : s.objects)
        if (sim::is_foreground(obj.cls)) w.objects.emplace_back(obj.id, obj.cls);
    }
    ++scans;
    points += s.points;
  }
  // The INS messages up to stamp_ns into the pcap.
  rt::Status write_ins_until(std::int64_t stamp_ns) {
    while (ins_out && ins.next_stamp_ns() <= stamp_ns) {
      if (auto w = ins_out->write(ins.next()); !w) return w;
      ++ins_messages;
    }
    return {};
  }
  // The complete scans the KITTI framing gave, each with the OXTS record of its mid-sweep time.
  rt::Status write_kitti_scans() {
    while (velodyne::Scan* scan = kitti_scans->take()) {
      if (scan->header.complete()) {
        const std::int64_t mid =
            scan->header.stamp_ns + (scan->header.end_stamp_ns - scan->header.stamp_ns) / 2;
        const applanix::Group1 g = ins.group1_at(static_cast<double>(mid - rc.start_ns) * 1e-9);
        kitti_frames.push_back({scan->header.stamp_ns, mid, scan->header.end_stamp_ns});
        if (auto a = kitti->add(*scan, mid, formats::oxts_record(ego::ins_fix(g, mid))); !a) {
          kitti_scans->release();
          return a;
        }
      }
      kitti_scans->release();
    }
    return {};
  }

  const sim::RunConfig& rc;
  const double origin_lat_lon_alt[3];
  std::ofstream& truth;
  std::optional<formats::KittiRawWriter>& kitti;
  std::optional<velodyne::ScanStream>& kitti_scans;
  sim::InsSim& ins;
  std::optional<InsPcapStream> ins_out;
  std::uint64_t scans = 0, points = 0, ins_messages = 0;
  std::vector<SweepTruth> sweeps;        // --kitti-raw: for its tracklets
  std::vector<KittiFrame> kitti_frames;  // the KITTI scans' sweeps and times
};

// Every data packet of the run (with the INS messages before it, its trailer, and an HDL-32E's
// or VLP's position packets) into the pcap and the KITTI framing.
rt::Status write_packets(sim::SimRun& run, std::int64_t span_ns, PacketTrailer& trailer,
                         std::optional<io::PcapWriter>& pcap, DriveRecorder& rec,
                         const DriveOutput& out) {
  const bool factory = trailer.factory();
  const std::uint32_t n = run.packet_count();
  const auto on_scan = [&rec](const sim::TruthScan& s) { rec.on_scan(s); };
  std::array<std::uint8_t, velodyne::kPositionPacketSize> position{};
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  for (std::uint32_t k = 0; k < n; ++k) {
    std::int64_t first_ns = 0;
    run.packet(k, bytes, first_ns, on_scan);
    if (auto w = rec.write_ins_until(first_ns + span_ns); !w)
      return rt::make_error(w.error().message);
    trailer.write(bytes.data() + velodyne::kPacketSize - 6, first_ns);
    // Received right after its last firing.
    const io::Datagram d = data_datagram(bytes, first_ns + span_ns, factory);
    if (pcap) {
      if (auto w = pcap->write_udp(d); !w) return rt::make_error(w.error().message);
    }
    // An HDL-32E / VLP also sends a position packet (port 8308) for about every 14 data packets
    // (VLP-16 manual).
    if (pcap && factory && k % 14 == 13) {
      if (auto w = write_position(*pcap, rec.ins, rec.rc.start_ns, d.stamp_ns, position); !w)
        return rt::make_error(w.error().message);
    }
    if (rec.kitti_scans && rec.kitti_scans->add_packet(d.payload, d.stamp_ns)) {
      if (auto w = rec.write_kitti_scans(); !w) return rt::make_error(w.error().message);
    }
    out.progress(k, n);
  }
  (void)run.finish(on_scan);
  return {};
}

// The summary lines of a written drive (wall: seconds it took).
void summarize(const DriveOptions& o, const sim::SimRun& run, const DriveRecorder& rec, bool pcap,
               double wall, const DriveOutput& out) {
  out.summary(formatted(
      "stac sim: %s seed %llu, %.1f s: %u packets, %llu scans, %llu points -> %s, %s\n"
      "  %zu objects in the world; simulated %.2fx real time (%.1f s)",
      o.scenario.c_str(), static_cast<unsigned long long>(o.seed), o.duration_s, run.packet_count(),
      static_cast<unsigned long long>(rec.scans), static_cast<unsigned long long>(rec.points),
      o.out.empty() ? "(no pcap)" : o.out.c_str(), o.truth.c_str(), run.world().actors().size(),
      o.duration_s / wall, wall));
  if (pcap)
    out.summary(
        formatted("  INS: %llu Applanix messages (Group 1 at 200 Hz, Groups 2 and 3 at 1 Hz), GPS "
                  "week %u, %s port %u",
                  static_cast<unsigned long long>(rec.ins_messages), rec.ins.gps_week(),
                  o.ins_udp ? "UDP" : "TCP", static_cast<unsigned>(InsPcapStream::kPort)));
  if (rec.kitti)
    out.summary(
        formatted("  KITTI raw: %zu complete scans with their OXTS records in %s (velodyne_points, "
                  "oxts, calib_imu_to_velo.txt, tracklet_labels.xml)",
                  rec.kitti->scans(), o.kitti_raw.c_str()));
}

}  // namespace

rt::Status write_drive(const DriveOptions& o, const DriveOutput& given) {
  const DriveOutput out{given.summary ? given.summary : [](const std::string&) {},
                        given.progress ? given.progress : [](std::uint32_t, std::uint32_t) {}};
  auto sensor = virtual_sensor(o);
  if (!sensor) return rt::make_error(sensor.error().message);
  auto run_cfg = run_config(o, *sensor);
  if (!run_cfg) return rt::make_error(run_cfg.error().message);
  const sim::RunConfig& rc = *run_cfg;
  sim::InsConfig ic;
  if (!o.origin.empty()) {
    auto origin = parse_origin(o.origin);
    if (!origin) return rt::make_error(origin.error().message);
    ic.origin = *origin;
  }
  ic.start_ns = rc.start_ns;
  auto run = sim::SimRun::create(sensor->calibration, rc);
  if (!run) return rt::make_error(run.error().message);
  std::optional<CanLog> can_log;
  if (!o.can.empty()) {
    auto c = open_can_log(o, **run, rc);
    if (!c) return rt::make_error(c.error().message);
    can_log.emplace(std::move(*c));
  }
  if (o.out.empty() && o.kitti_raw.empty())
    return rt::make_error("nothing to write: give --out RUN.pcap, --kitti-raw DIR, or both");
  std::optional<io::PcapWriter> pcap;
  if (!o.out.empty()) {
    auto p = io::PcapWriter::open(o.out);
    if (!p) return rt::make_error(p.error().message);
    pcap.emplace(std::move(*p));
  }
  std::optional<formats::KittiRawWriter> kitti;
  std::optional<velodyne::ScanStream> kitti_scans;
  if (!o.kitti_raw.empty()) {
    if (auto k = open_kitti_raw(o, rc, *sensor, kitti, kitti_scans); !k) return k;
  }
  std::ofstream truth(o.truth);
  if (!truth) return rt::make_error(o.truth + ": cannot create the truth file");
  auto trailer = PacketTrailer::create(o, *sensor, rc);
  if (!trailer) return rt::make_error(trailer.error().message);

  const velodyne::PacketDecoder timing(sensor->calibration,
                                       velodyne::DecoderConfig{.model = rc.lidar.model});
  const std::int64_t span_ns = timing.packet_span_ns(o.dual_return);
  const auto wall0 = std::chrono::steady_clock::now();
  sim::InsSim ins(ic, [r = run->get()](double t) { return r->ego(t); });
  DriveRecorder rec(rc, ic, truth, kitti, kitti_scans, ins);
  if (pcap) rec.ins_out.emplace(*pcap, o.ins_udp);
  if (auto w = write_packets(**run, span_ns, *trailer, pcap, rec, out); !w) return w;
  if (kitti) {
    if (auto f = kitti->finish(); !f) return rt::make_error(f.error().message);
    const auto labels = sim_tracklets(**run, rc, rec.sweeps, rec.kitti_frames);
    const std::filesystem::path xml = std::filesystem::path(o.kitti_raw) / "tracklet_labels.xml";
    std::ofstream(xml) << formats::format_kitti_tracklets(labels);
    if (!std::filesystem::exists(xml)) return rt::make_error(xml.string() + ": cannot write");
  }
  if (auto w = rec.write_ins_until(rc.start_ns + std::llround(rc.duration_s * 1e9)); !w)
    return rt::make_error(w.error().message);
  const std::uint32_t n = (*run)->packet_count();
  out.progress(n, n);
  if (pcap) {
    if (auto c = pcap->close(); !c) return rt::make_error(c.error().message);
  }
  truth.close();
  if (!truth) return rt::make_error(o.truth + ": write failed");
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  summarize(o, **run, rec, pcap.has_value(), wall, out);
  if (can_log) return write_can_log(*can_log, o.can, rc, out);
  return {};
}

}  // namespace stac::sim

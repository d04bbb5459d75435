// stac sim: a simulated drive written as the real devices' bytes (pcap) plus its ground truth.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "drivers/io/pcap_writer.hpp"
#include "drivers/velodyne/decoder.hpp"
#include "drivers/velodyne/status.hpp"
#include "sim/run.hpp"
#include "tools/commands.hpp"
#include "tools/progress.hpp"
#include "tools/settings.hpp"

namespace stac::tools {
namespace {

struct SimOptions {
  std::string scenario = "urban";
  std::uint64_t seed = 1;
  double duration_s = 10.0;
  std::string out;
  std::string truth;
  std::string calib;
  std::string config;
  bool dual_return = false;
};

int run_sim(const SimOptions& o) {
  auto settings = load_velodyne_settings(config_path(o.config));
  if (!settings) return fail(settings.error().message);
  const std::filesystem::path calib_path = o.calib.empty() ? settings->calibration : std::filesystem::path(o.calib);
  if (calib_path.empty()) return fail("stac sim needs a calibration file: pass --calib");
  auto calibration = velodyne::load_calibration(calib_path);
  if (!calibration) return fail(calibration.error().message);

  sim::RunConfig rc;
  rc.scenario = o.scenario;
  rc.seed = o.seed;
  rc.duration_s = o.duration_s;
  rc.cut_angle = settings->assembler.cut_angle;
  rc.lidar.seed = o.seed;
  rc.lidar.dual_return = o.dual_return;
  rc.lidar.model = o.dual_return ? velodyne::Model::kS3 : velodyne::Model::kS2_1;
  auto run = sim::SimRun::create(*calibration, rc);
  if (!run) return fail(run.error().message);
  auto pcap = io::PcapWriter::open(o.out);
  if (!pcap) return fail(pcap.error().message);
  std::ofstream truth(o.truth);
  if (!truth) return fail(o.truth + ": cannot create the truth file");

  // The trailer an S2.1/S3 sends: GPS time past the hour and the status cycle, with the
  // calibration the sim casts with in its dump (so `--calib stream` decodes the capture).
  velodyne::SensorStatus sensor;
  sensor.gps_raw = 'A';  // PPS and NMEA
  sensor.temperature_c = 42;
  sensor.firmware = 0x47;
  velodyne::UnitParameters unit;
  unit.upper_noise_threshold = unit.lower_noise_threshold = 24;
  unit.calibration_date = velodyne::DateTime{2025, 6, 2, 10, 30, 0};
  unit.humidity = 30;
  unit.rpm = static_cast<std::uint16_t>(std::lround(rc.lidar.rpm));
  unit.fov_end = 36000;
  unit.run_hours = 1200;
  unit.ip_source = {192, 168, 3, 43};
  unit.ip_destination = {255, 255, 255, 255};
  unit.return_mode = o.dual_return ? velodyne::ReturnMode::kDual : velodyne::ReturnMode::kStrongest;
  unit.power_level = 0xA8;
  unit.warnings = 0x60;  // PPS and GPS time present
  auto trailer = velodyne::StatusTrailerWriter::create(rc.lidar.model, sensor, unit, *calibration);
  if (!trailer) return fail("the calibration cannot be sent in the status cycle: " + trailer.error().message);

  const velodyne::PacketDecoder timing(*calibration, velodyne::DecoderConfig{.model = rc.lidar.model});
  const std::int64_t span_ns = timing.packet_span_ns(o.dual_return);
  std::uint64_t scans = 0, points = 0;
  auto on_scan = [&](const sim::TruthScan& s) {
    truth << sim::to_json(s) << '\n';
    ++scans;
    points += s.points;
  };
  const std::uint32_t n = (*run)->packet_count();
  Progress progress("sim " + o.scenario, n);
  const auto wall0 = std::chrono::steady_clock::now();
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  for (std::uint32_t k = 0; k < n; ++k) {
    std::int64_t first_ns = 0;
    (*run)->packet(k, bytes, first_ns, on_scan);
    trailer->write(bytes.data() + velodyne::kPacketSize - 6, first_ns);
    io::Datagram d;
    d.payload = bytes;
    d.stamp_ns = first_ns + span_ns;  // received right after its last firing
    d.src_ip = 0xC0A8032B;            // 192.168.3.43, the HDL-64E's factory address
    d.dst_ip = 0xFFFFFFFF;
    d.src_port = velodyne::kPortData;
    d.dst_port = velodyne::kPortData;
    if (auto w = pcap->write_udp(d); !w) return fail(w.error().message);
    progress.update(k);
  }
  (void)(*run)->finish(on_scan);
  progress.finish();
  if (auto c = pcap->close(); !c) return fail(c.error().message);
  truth.close();
  if (!truth) return fail(o.truth + ": write failed");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::fprintf(stderr,
               "stac sim: %s seed %llu, %.1f s: %u packets, %llu scans, %llu points -> %s, %s\n"
               "  %zu objects in the world; simulated %.2fx real time (%.1f s)\n",
               o.scenario.c_str(), static_cast<unsigned long long>(o.seed), o.duration_s, n,
               static_cast<unsigned long long>(scans), static_cast<unsigned long long>(points),
               o.out.c_str(), o.truth.c_str(), (*run)->world().actors().size(), o.duration_s / wall, wall);
  return 0;
}

}  // namespace

void add_sim_command(CLI::App& app) {
  auto o = std::make_shared<SimOptions>();
  CLI::App* cmd = app.add_subcommand("sim", "Simulate a drive: HDL-64E packets in a pcap plus ground truth");
  cmd->description(
      "Simulate a drive: a virtual HDL-64E (each laser cast at its firing time with the angles and\n"
      "offsets of a real calibration) in a street scene, written as the sensor's UDP packets in a\n"
      "pcap, with the ground truth of every scan as JSON lines (ego pose; per object id, class,\n"
      "box, velocity and points hit). Same scenario and seed give byte-identical files.");
  std::string names;
  for (const auto& n : sim::scenario_names()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--scenario", o->scenario, "one of: " + names)
      ->check(CLI::IsMember(sim::scenario_names()))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed of the world and the sensor noise")->capture_default_str();
  cmd->add_option("--duration", o->duration_s, "seconds to simulate")->check(CLI::Range(0.1, 7200.0))->capture_default_str();
  cmd->add_option("--out", o->out, "pcap file to write")->required();
  cmd->add_option("--truth", o->truth, "truth file to write (JSON lines, one per scan)")->required();
  cmd->add_option("--calib", o->calib, "calibration of the virtual unit (default: the config's)");
  cmd->add_option("--config", o->config, "configuration file (default: $STAC_CONFIG or config/stac.yaml)");
  cmd->add_flag("--dual-return", o->dual_return, "an S3 in dual-return mode (strongest and last)");
  cmd->callback([o] {
    if (const int code = run_sim(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

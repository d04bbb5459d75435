// stac status: what an HDL-64E S2.1/S3 says about itself in its packets' status bytes.
#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <string>

#include "drivers/velodyne/packet.hpp"
#include "drivers/velodyne/position.hpp"
#include "formats/capture_input.hpp"
#include "formats/capture_sensor.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"

namespace stac::tools {

using namespace stac::settings;
using namespace stac::formats;

namespace {

struct StatusOptions {
  std::string config;
  std::string in;
  std::string model;
  std::string calib_out;
  int port = -1;
};

std::string ip(const std::array<std::uint8_t, 4>& a) {
  return std::to_string(a[0]) + "." + std::to_string(a[1]) + "." + std::to_string(a[2]) + "." +
         std::to_string(a[3]);
}

// An HDL-32E / VLP: the factory bytes of its data packets and its position packets (port 8308)
// with the GPS receiver's NMEA sentence.
int run_family_status(const StatusOptions& o, std::uint16_t port, velodyne::Model model) {
  auto reader = io::PcapReader::open(o.in, io::PcapFilter{});
  if (!reader) return fail(reader.error().message);
  std::uint64_t data = 0, other_model = 0, positions = 0, position_errors = 0;
  std::map<std::uint8_t, std::uint64_t> modes;
  std::map<std::string, std::uint64_t> errors;
  std::optional<velodyne::PositionPacket> last;
  std::optional<velodyne::Hdl32eMotion> motion;
  io::Datagram d;
  while (reader->next(d)) {
    if (d.dst_port == port && d.payload.size() == velodyne::kPacketSize) {
      ++data;
      const velodyne::PacketIdentity id = velodyne::identify_packet(d.payload);
      if (!velodyne::identity_matches(id, model)) ++other_model;
      if (id.kind == velodyne::PacketIdentity::Kind::kFactory) ++modes[id.return_mode];
    } else if (d.dst_port == velodyne::kPortPosition) {
      ++positions;
      auto p = velodyne::parse_position_packet(d.payload);
      if (!p) {
        ++position_errors;
        ++errors[velodyne::to_string(p.error())];
        continue;
      }
      last = *p;
      if (model == velodyne::Model::kHdl32e) motion = velodyne::parse_hdl32e_motion(d.payload);
    }
  }
  if (!reader->error().empty()) return fail(capture_breaks_off(reader->error()));
  if (data == 0) {
    return fail(o.in + ": no " + std::string(velodyne::traits(model).name) +
                " data packet to port " + std::to_string(port) + " (wrong --port?)");
  }
  const std::string name(velodyne::traits(model).name);
  std::printf("%s: %llu %s data packets (%llu whose factory bytes name another model)\n",
              o.in.c_str(), static_cast<unsigned long long>(data), name.c_str(),
              static_cast<unsigned long long>(other_model));
  std::printf("return mode");
  for (const auto& [mode, count] : modes) {
    std::printf(" %s %llu",
                mode == velodyne::kReturnDual   ? "dual"
                : mode == velodyne::kReturnLast ? "last"
                                                : "strongest",
                static_cast<unsigned long long>(count));
  }
  std::printf("\nposition     %llu packets on port %u, %llu unreadable",
              static_cast<unsigned long long>(positions), velodyne::kPortPosition,
              static_cast<unsigned long long>(position_errors));
  for (const auto& [why, count] : errors)
    std::printf(" (%s: %llu)", why.c_str(), static_cast<unsigned long long>(count));
  std::printf("\n");
  if (last) {
    const velodyne::NmeaFix& f = last->fix;
    std::printf("last fix     PPS %s, %.*s\n", velodyne::to_string(last->pps),
                static_cast<int>(last->sentence_length), last->sentence.data());
    if (const auto utc = velodyne::nmea_utc_ns(f)) {
      const auto t =
          std::chrono::sys_time<std::chrono::seconds>(std::chrono::seconds(*utc / 1'000'000'000));
      const std::chrono::year_month_day ymd{std::chrono::floor<std::chrono::days>(t)};
      const std::chrono::hh_mm_ss hms{t - std::chrono::floor<std::chrono::days>(t)};
      std::printf(
          "             %04d-%02u-%02u %02ld:%02ld:%02lld UTC, %s, %.7f %.7f deg, %.1f m/s\n",
          static_cast<int>(ymd.year()), static_cast<unsigned>(ymd.month()),
          static_cast<unsigned>(ymd.day()), static_cast<long>(hms.hours().count()),
          static_cast<long>(hms.minutes().count()), static_cast<long long>(hms.seconds().count()),
          f.valid ? "valid" : "no fix", f.latitude_deg.value_or(0.0), f.longitude_deg.value_or(0.0),
          f.speed_mps.value_or(0.0));
    }
  }
  const bool motion_sent =
      motion && (motion->gyro_deg_per_s != std::array<double, 3>{} ||
                 motion->temperature_c != std::array<double, 3>{25.0, 25.0, 25.0});
  if (motion_sent) {
    std::printf("motion       gyro %.2f %.2f %.2f deg/s, temperature %.1f %.1f %.1f C\n",
                motion->gyro_deg_per_s[0], motion->gyro_deg_per_s[1], motion->gyro_deg_per_s[2],
                motion->temperature_c[0], motion->temperature_c[1], motion->temperature_c[2]);
  }
  if (!o.calib_out.empty()) {
    return fail("--calib-out: the " + name +
                " sends no calibration in its packets; its calibration is a file (VeloView xml "
                "or ROS yaml)");
  }
  return 0;
}

int run_status(const StatusOptions& o) {
  auto settings = load_velodyne_settings(config_path(o.config));
  if (!settings) return fail(settings.error().message);
  velodyne::Model model = settings->assembler.decoder.model;
  if (o.port == 0 || o.port > 65535) return fail("--port must be 1..65535");
  const auto port = o.port > 0 ? static_cast<std::uint16_t>(o.port) : settings->port;
  if (o.model == "auto" || (o.model.empty() && settings->model_auto)) {
    auto id = capture_identity(o.in, port);
    if (!id) return fail(id.error().message);
    if (id->model) model = *id->model;
    if (id->kind == velodyne::PacketIdentity::Kind::kHdl64 && !velodyne::is_hdl64(model))
      model = velodyne::Model::kS2_1;
  } else if (!o.model.empty()) {
    const auto m = velodyne::parse_model(o.model);
    if (!m) return fail("--model '" + o.model + "': use " + std::string(velodyne::model_names()));
    model = *m;
  }
  if (velodyne::traits(model).trailer == velodyne::TrailerKind::kFactory)
    return run_family_status(o, port, model);
  auto read = read_capture_status(o.in, port, model, false);
  if (!read) return fail(read.error().message);
  if (read->packets == 0) {
    return fail(o.in + ": no HDL-64E packet to port " + std::to_string(port) + " (wrong --port?)");
  }
  const velodyne::StatusDecoder& st = read->status;
  const auto& c = st.counters();
  const velodyne::SensorStatus& s = st.sensor();
  std::printf("%s: %llu packets, %llu status cycles, %llu out of sequence\n", o.in.c_str(),
              static_cast<unsigned long long>(read->packets),
              static_cast<unsigned long long>(c.cycles),
              static_cast<unsigned long long>(c.out_of_sequence));
  if (s.valid) {
    std::printf(
        "last cycle   %04d-%02d-%02d %02d:%02d:%02d UTC, GPS %s, %d deg C, firmware %d.%02x\n",
        s.time.year, s.time.month, s.time.day, s.time.hour, s.time.minute, s.time.second,
        velodyne::to_string(s.gps), s.temperature_c, s.firmware >> 4, s.firmware & 0x0F);
  } else {
    std::printf("last cycle   no complete H..V sequence with a valid date\n");
  }
  std::printf(
      "calibration  %llu dumps accepted, %llu broken by lost/reordered packets, %llu bad "
      "checksum, %llu bad layout, %llu not confirmed (an S2.1 dump, having no CRC, is used once "
      "the next is the same)\n",
      static_cast<unsigned long long>(c.dumps), static_cast<unsigned long long>(c.dumps_broken),
      static_cast<unsigned long long>(c.bad_checksum),
      static_cast<unsigned long long>(c.bad_layout),
      static_cast<unsigned long long>(c.unconfirmed));
  if (st.has_calibration()) {
    const velodyne::UnitParameters& u = st.unit();
    std::string date = "not set";
    if (u.calibration_date) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%04d-%02d-%02d", u.calibration_date->year,
                    u.calibration_date->month, u.calibration_date->day);
      date = buf;
    }
    std::printf(
        "unit         %u rpm, FOV %.2f..%.2f deg, return mode %s, power 0x%02X, "
        "%u run hours, calibrated %s\n"
        "             %s -> %s, noise thresholds %u/%u, warnings 0x%02X%s\n",
        u.rpm, u.fov_start / 100.0, u.fov_end / 100.0, velodyne::to_string(u.return_mode),
        u.power_level, u.run_hours, date.c_str(), ip(u.ip_source).c_str(),
        ip(u.ip_destination).c_str(), u.upper_noise_threshold, u.lower_noise_threshold, u.warnings,
        u.crc_checked ? ", CRC ok" : "");
  }
  if (!o.calib_out.empty()) {
    auto calibration = st.calibration();
    if (!calibration) return fail(o.in + ": " + calibration.error().message);
    if (auto w = velodyne::save_ros_yaml(*calibration, o.calib_out); !w)
      return fail(w.error().message);
    std::printf("calibration  written to %s (ROS yaml)\n", o.calib_out.c_str());
  }
  return 0;
}

}  // namespace

void add_status_command(CLI::App& app) {
  auto o = std::make_shared<StatusOptions>();
  CLI::App* cmd = app.add_subcommand(
      "status",
      "Show what an HDL-64E S2.1/S3 reports in its status bytes (extract its calibration), or an "
      "HDL-32E/VLP in its position packets");
  cmd->description(
      "Reads the status cycle in the last two bytes of every packet of a capture: GPS date and\n"
      "time, GPS state, temperature and firmware every 16 packets, and the calibration dump "
      "(lasers,\n"
      "RPM, FOV, addresses, return mode) every 4160. --calib-out writes the calibration the unit\n"
      "sent as a ROS yaml file; 'stac decode --calib stream' uses it directly.\n"
      "An HDL-32E, VLP-16, Puck or VLP-32C (--model) has no status cycle: its data packets' "
      "return\n"
      "mode and product bytes are counted, and its position packets (port 8308) read: PPS state\n"
      "and the GPS receiver's NMEA sentence (UTC date and time, position, speed).");
  cmd->add_option("--in", o->in, "pcap capture of the sensor's packets")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--calib-out", o->calib_out, "write the unit's calibration here (ROS yaml)");
  cmd->add_option("--model", o->model,
                  "the sensor (default: the config's velodyne.model): S2.1 or S3, or an HDL-32E, "
                  "VLP-16, Puck or VLP-32C, whose factory bytes and position packets (port 8308, "
                  "NMEA) are shown instead; auto: the model the packets name");
  cmd->add_option("--port", o->port, "UDP data port in the capture (default: the config's, 2368)");
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->callback([o] {
    if (const int code = run_status(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

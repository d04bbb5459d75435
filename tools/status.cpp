// stac status: what an HDL-64E S2.1/S3 says about itself in its packets' status bytes.
#include "tools/status.hpp"

#include <cstdio>
#include <string>

#include "drivers/velodyne/packet.hpp"
#include "formats/capture_input.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"

namespace stac::tools {

using namespace stac::settings;
using namespace stac::formats;

rt::Result<CaptureStatus> read_capture_status(const std::filesystem::path& capture,
                                              std::uint16_t port, velodyne::Model model,
                                              bool until_calibration) {
  if (velodyne::traits(model).trailer != velodyne::TrailerKind::kGpsStatus) {
    return rt::make_error(std::string("the HDL-64E ") + std::string(velodyne::traits(model).name) +
                          " sends no status cycle (only the S2.1 and S3 do); set --model or "
                          "'velodyne.model'");
  }
  auto reader =
      io::PcapReader::open(capture, io::PcapFilter{.udp_dst_port = port, .udp_src_port = {}});
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  CaptureStatus out{velodyne::StatusDecoder(model), 0, {}};
  io::Datagram d;
  while (reader->next(d)) {
    const velodyne::RawPacket* packet = velodyne::as_packet(d.payload);
    if (packet == nullptr) continue;
    ++out.packets;
    out.status.add(packet->trailer[4], packet->trailer[5]);
    if (until_calibration && out.status.has_calibration()) break;
  }
  if (!reader->error().empty()) return rt::make_error(capture_breaks_off(reader->error()));
  out.pcap = reader->counters();
  return out;
}

rt::Result<velodyne::Calibration> stream_calibration(const std::filesystem::path& capture,
                                                     std::uint16_t port, velodyne::Model model) {
  auto status = read_capture_status(capture, port, model, true);
  if (!status) return rt::Unexpected<rt::Error>{status.error()};
  auto calibration = status->status.calibration();
  if (!calibration) {
    return rt::make_error(capture.string() + ": " + calibration.error().message +
                          "; pass --calib with the unit's db.xml or ROS yaml instead");
  }
  return calibration;
}

rt::Result<velodyne::Calibration> capture_calibration(const std::filesystem::path& calibration_file,
                                                      const std::filesystem::path& capture,
                                                      std::uint16_t port, velodyne::Model model) {
  return calibration_file.empty() ? stream_calibration(capture, port, model)
                                  : velodyne::load_calibration(calibration_file);
}

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

int run_status(const StatusOptions& o) {
  auto settings = load_velodyne_settings(config_path(o.config));
  if (!settings) return fail(settings.error().message);
  velodyne::Model model = settings->assembler.decoder.model;
  if (!o.model.empty()) {
    const auto m = velodyne::parse_model(o.model);
    if (!m) return fail("--model '" + o.model + "': use S2.1 or S3");
    model = *m;
  }
  if (o.port == 0 || o.port > 65535) return fail("--port must be 1..65535");
  const auto port = o.port > 0 ? static_cast<std::uint16_t>(o.port) : settings->port;
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
      "Show what an HDL-64E S2.1/S3 reports in its status bytes; extract its calibration");
  cmd->description(
      "Reads the status cycle in the last two bytes of every packet of a capture: GPS date and\n"
      "time, GPS state, temperature and firmware every 16 packets, and the calibration dump "
      "(lasers,\n"
      "RPM, FOV, addresses, return mode) every 4160. --calib-out writes the calibration the unit\n"
      "sent as a ROS yaml file; 'stac decode --calib stream' uses it directly.");
  cmd->add_option("--in", o->in, "pcap capture of the sensor's packets")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--calib-out", o->calib_out, "write the unit's calibration here (ROS yaml)");
  cmd->add_option("--model", o->model, "S2.1 or S3 (default: the config's)");
  cmd->add_option("--port", o->port, "UDP data port in the capture (default: the config's, 2368)");
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->callback([o] {
    if (const int code = run_status(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

// stac decode: a pcap capture of Velodyne packets -> calibrated, timed points (csv or KITTI bins).
#include "tools/decode.hpp"

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "formats/capture_input.hpp"
#include "formats/capture_sensor.hpp"
#include "formats/scan_writers.hpp"
#include "pictures/birds_eye.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"
#include "tools/support/progress.hpp"

namespace stac::tools {

using namespace stac::settings;
using namespace stac::formats;
namespace {

// Applies the command line over the configuration file's velodyne section.
rt::Result<VelodyneSettings> settings_for(const DecodeOptions& o) {
  const std::filesystem::path config = config_path(o.config);
  auto s = load_velodyne_settings(config);
  if (!s) return s;
  if (!o.calib.empty())
    s->calibration = o.calib == "stream" ? std::filesystem::path{} : std::filesystem::path(o.calib);
  if (auto m = apply_sensor_option(*s, o.model, !o.calib.empty()); !m)
    return rt::make_error("--model: " + m.error().message);
  if (o.port >= 0) {
    if (o.port == 0 || o.port > 65535) return rt::make_error("--port must be 1..65535");
    s->port = static_cast<std::uint16_t>(o.port);
  }
  if (o.cut_angle_deg >= 0.0) {
    if (o.cut_angle_deg >= 360.0) return rt::make_error("--cut-angle must be in [0, 360)");
    s->assembler.cut_angle =
        static_cast<std::uint16_t>(std::lround(o.cut_angle_deg * 100.0) % 36000);
  }
  return s;
}

}  // namespace

int run_decode(const DecodeOptions& o) {
  auto settings = settings_for(o);
  if (!settings) return fail(settings.error().message);
  auto& s = *settings;
  auto calibration = capture_sensor(s, o.in, !o.calib.empty());
  if (!calibration) return fail(calibration.error().message);
  auto writer = make_scan_writer(o.format, o.out);
  if (!writer) return fail(writer.error().message);
  auto reader =
      io::PcapReader::open(o.in, io::PcapFilter{.udp_dst_port = s.port, .udp_src_port = {}});
  if (!reader) return fail(reader.error().message);

  velodyne::ScanStream stream(*calibration, s.assembler, 2);
  std::optional<pictures::BirdsEye> picture;
  if (!o.png.empty()) picture.emplace(pictures::BirdsEyeOptions{});
  std::uint64_t scans = 0, complete = 0, points = 0;
  Progress progress("decode", static_cast<double>(std::filesystem::file_size(o.in)));
  auto drain = [&]() -> rt::Status {
    while (const velodyne::Scan* scan = stream.take()) {
      auto w = (*writer)->write(*scan);
      if (!w) return w;
      ++scans;
      complete += scan->header.complete() ? 1 : 0;
      points += scan->points.size();
      if (picture && scan->header.complete() && complete == 1) {
        for (const auto& p : scan->points) picture->add_point(p.x, p.y, p.z);
        picture->add_legend("scan " + std::to_string(scan->header.sequence) + " of " + o.in);
        picture->add_legend(std::to_string(scan->points.size()) + " points");
      }
      stream.release();
    }
    return {};
  };
  io::Datagram d;
  while (reader->next(d)) {
    if (stream.add_packet(d.payload, d.stamp_ns)) {
      if (auto r = drain(); !r) return fail(r.error().message);
    }
    progress.update(static_cast<double>(reader->bytes_read()));
  }
  progress.finish();
  const std::string capture_error = reader->error();
  (void)stream.finish();
  if (auto r = drain(); !r) return fail(r.error().message);
  if (auto r = (*writer)->close(); !r) return fail(r.error().message);
  if (picture) {
    if (complete == 0) return fail("--png: the capture holds no complete scan to draw");
    if (auto r = picture->save(o.png); !r) return fail(r.error().message);
  }

  const auto& a = stream.assembler().counters();
  const auto& dc = stream.assembler().decode_counters();
  const auto& pc = reader->counters();
  std::fprintf(stderr,
               "stac decode: %s -> %s (%s)\n"
               "  capture   %s\n"
               "  scans     %llu (%llu complete, framed at %.2f deg)\n"
               "  points    %llu (no return %llu, out of range %llu, of lasers the calibration "
               "disables %llu)\n"
               "  dropped   %s\n",
               o.in.c_str(), o.out.c_str(), o.format.c_str(),
               capture_frames_summary(pc, a.packets, s.port).c_str(),
               static_cast<unsigned long long>(scans), static_cast<unsigned long long>(complete),
               s.assembler.cut_angle / 100.0, static_cast<unsigned long long>(points),
               static_cast<unsigned long long>(dc.no_return),
               static_cast<unsigned long long>(dc.out_of_range),
               static_cast<unsigned long long>(dc.disabled), packet_drops_summary(a).c_str());
  if (!capture_error.empty()) return fail(capture_breaks_off(capture_error));
  if (scans == 0) return fail(nothing_decoded_reason(o.in, pc, a, s.port));
  return 0;
}

void add_decode_command(CLI::App& app) {
  auto o = std::make_shared<DecodeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "decode", "Decode a pcap capture of Velodyne packets into calibrated, timed points");
  cmd->description(
      "Decode a pcap capture of Velodyne packets (HDL-64E, HDL-32E, VLP-16, VLP-32C) into "
      "calibrated, timed points.\n"
      "Scans are framed where the azimuth crosses the cut angle. csv: one row per point with\n"
      "columns scan,laser,azimuth (0.01 deg),distance (m),x,y,z (m; x forward, y left, z up),\n"
      "intensity,time (s). kitti: one float32 x,y,z,reflectance(0..1) file per scan in --out/.");
  // --in/--out are checked in the callback, not marked required, so that the `applanix`
  // subcommand (stac decode applanix --in ...) parses without them.
  cmd->add_option("--in", o->in,
                  "pcap capture to read (Ethernet, Linux cooked or raw IP) (required)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out,
                  "output: a .csv file, or a folder for --format kitti (required)");
  cmd->add_option("--calib", o->calib,
                  "calibration of the unit: Velodyne db.xml, ROS yaml, or 'stream' for the one an "
                  "S2.1/S3 sends in its status bytes. Default: the config's");
  cmd->add_option("--format", o->format, "csv or kitti")->check(CLI::IsMember({"csv", "kitti"}));
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option(
      "--model", o->model,
      "the sensor: S2, S2.1, S3 (HDL-64E), HDL-32E, VLP-16, Puck LITE, Puck Hi-Res, VLP-32C, or "
      "auto (the model the packets name; default: the config's velodyne.model)");
  cmd->add_option("--port", o->port, "UDP data port in the capture (default: the config's, 2368)");
  cmd->add_option("--cut-angle", o->cut_angle_deg,
                  "scan cut angle in degrees (default: the config's)")
      ->check(finite_range(0.0, 359.99));
  needs_pictures(cmd->add_option("--png", o->png,
                                 "also draw the first complete scan from above into this PNG"));
  CLI::App* applanix = add_decode_applanix_command(*cmd);
  cmd->callback([o, applanix] {
    if (applanix->parsed()) return;
    if (o->in.empty()) throw CLI::RequiredError("--in");
    if (o->out.empty()) throw CLI::RequiredError("--out");
    if (const int code = run_decode(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

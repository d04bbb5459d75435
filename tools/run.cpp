// stac run: the live component (runtime/component.hpp, docs/run.md) from the command line: the
// options override the config file's values; SIGINT/SIGTERM stop it, SIGHUP reloads the model.
#include <cstdio>
#include <filesystem>
#include <string>

#include "formats/capture_sensor.hpp"
#include "formats/durable_file.hpp"
#include "runtime/component.hpp"
#include "settings/dds_settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"

namespace stac::tools {

using namespace stac::settings;
namespace {

struct RunOptions {
  std::string config, calib, ins, ins_address, bind, model, dds_config, sensor;
  std::string summary_json;  // --summary-json: the summary as JSON too
  double seconds = 0;
  std::uint64_t scans = 0;
  int domain = -1, port = -1, ins_port = -1, point_cloud_stride = -1;
};

int run_live(const RunOptions& o) {
  auto settings = runtime::load_component_settings(config_path(o.config));
  if (!settings) return fail(settings.error().message);
  runtime::ComponentSettings& s = *settings;
  VelodyneSettings& vs = s.pipeline.velodyne;
  // Command-line overrides.
  if (!o.calib.empty()) vs.calibration = o.calib;
  if (auto m = formats::apply_sensor_option(vs, o.sensor, !o.calib.empty()); !m)
    return fail("--sensor: " + m.error().message);
  if (o.port >= 0) vs.port = static_cast<std::uint16_t>(o.port);
  if (!o.bind.empty()) vs.bind_address = o.bind;
  stac::settings::override_dds(s.dds, o.domain, o.dds_config);
  if (o.point_cloud_stride >= 0)
    s.dds.point_cloud_stride = static_cast<std::uint32_t>(o.point_cloud_stride);
  if (!o.ins.empty()) {
    auto t = parse_ins_transport(o.ins);
    if (!t) return fail("--ins: " + t.error().message);
    s.run.ins = *t;
  }
  if (!o.ins_address.empty()) s.run.ins_address = o.ins_address;
  if (o.ins_port >= 0) s.pipeline.ego.ins_port = static_cast<std::uint16_t>(o.ins_port);
  s.model = o.model;
  s.stop_after_s = o.seconds;
  s.stop_after_scans = o.scans;
  auto component = runtime::Component::create(s);
  if (!component) return fail(component.error().message);
  runtime::run_with_signals(**component);
  const runtime::Summary summary = (*component)->summary();
  runtime::print_summary(summary, s.name, stderr);
  if (!o.summary_json.empty()) {
    if (auto w = formats::write_text_durably(o.summary_json, runtime::summary_json(summary)); !w)
      return fail("--summary-json: " + w.error().message);
  }
  return 0;
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd =
      app.add_subcommand("run", "The live component: sensor UDP -> perception -> DDS topics");
  cmd->description(
      "Receives the lidar's UDP packets (HDL-64E, HDL-32E, VLP-16, VLP-32C: --sensor), the "
      "Applanix INS (TCP or UDP) and optionally the\n"
      "vehicle CAN bus (SocketCAN, a gs_usb adapter or a cannelloni gateway over UDP:\n"
      "can.transport), runs every complete scan through deskew -> segment -> track -> classify\n"
      "on its own thread and publishes\n"
      "tracked_objects, segments, ego_pose and health on DDS, watching the deadline\n"
      "(run.deadline_ms) and the inputs. The published tracks are classified before publication\n"
      "while the scan is younger than run.classify_budget_ms; the rest after it. Stops on\n"
      "Ctrl-C/SIGTERM, --seconds or --scans and prints a summary: scans, drops by cause, classes\n"
      "classified before and after publication, deadline misses, latencies (docs/run.md).\n"
      "SIGHUP reads the model file again and swaps it in between scans (same classes; health's\n"
      "model_hash says which model is in use; a bad file is refused and the model kept).");
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--seconds", o->seconds, "stop after this many seconds")
      ->check(finite_range(0.001, 1e9));
  cmd->add_option("--scans", o->scans, "stop after this many scans are published")
      ->check(finite_range(1, 1e12));
  cmd->add_option("--summary-json", o->summary_json,
                  "also write the summary printed at the end to this file, as JSON (the same "
                  "counts, for programs: stac demo reads it)");
  cmd->add_option("--domain", o->domain, "DDS domain (default: dds.domain_id)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--point-cloud-stride", o->point_cloud_stride,
                  "publish point_cloud: every segment return and every Nth other one; 0: none "
                  "(default: dds.point_cloud_stride)")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--dds-config", o->dds_config, "Cyclone DDS XML (default: dds.config_file)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--port", o->port, "Velodyne UDP port (default: velodyne.port; 0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--bind", o->bind,
                  "Velodyne UDP address to bind (default: velodyne.bind_address)");
  cmd->add_option("--calib", o->calib, "calibration file (default: velodyne.calibration)");
  cmd->add_option("--sensor", o->sensor,
                  "the lidar model (default: velodyne.model): S2, S2.1, S3, HDL-32E, VLP-16, Puck "
                  "LITE, Puck Hi-Res or VLP-32C; its calibration from velodyne.model_calibrations "
                  "unless --calib");
  cmd->add_option(
      "--model", o->model,
      "track classifier model (`stac train`) or 'none' (default: classification.model)");
  cmd->add_option("--ins", o->ins, "INS transport: tcp, udp or none (default: run.ins)");
  cmd->add_option("--ins-address", o->ins_address,
                  "INS TCP server IPv4 address (default: run.ins_address)");
  cmd->add_option("--ins-port", o->ins_port, "INS port (default: es.ins_port)")
      ->check(CLI::Range(1, 65535));
  cmd->callback([o] {
    if (const int code = run_live(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

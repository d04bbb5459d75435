// stac sim: a simulated drive written as the real devices' bytes (pcap) plus its ground truth
// (sim/drive_writer.hpp does the work).
#include "tools/sim.hpp"

#include <cstdio>
#include <memory>
#include <string>

#include "settings/settings.hpp"
#include "sim/scenario.hpp"
#include "tools/commands.hpp"
#include "tools/support/progress.hpp"

namespace stac::tools {

int run_sim(const sim::DriveOptions& options) {
  Progress progress("sim " + options.scenario, 1.0);
  const sim::DriveOutput output{
      [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); },
      [&](std::uint32_t done, std::uint32_t total) {
        progress.set_total(total);
        progress.update(done);
        if (done == total) progress.finish();
      }};
  if (auto w = sim::write_drive(options, output); !w) return fail(w.error().message);
  return 0;
}

void add_sim_command(CLI::App& app) {
  auto o = std::make_shared<sim::DriveOptions>();
  CLI::App* cmd =
      app.add_subcommand("sim", "Simulate a drive: HDL-64E packets in a pcap plus ground truth");
  cmd->description(
      "Simulate a drive: a virtual HDL-64E (each laser cast at its firing time with the angles "
      "and\n"
      "offsets of a real calibration) in a street scene, written as the sensor's UDP packets in a\n"
      "pcap, with the ground truth of every scan as JSON lines (ego pose; per object id, class,\n"
      "box, velocity and points hit). The same pcap carries the Applanix POS LV Real-Time Data\n"
      "stream of the ego trajectory (port 5602, TCP: Group 1 at 200 Hz, Groups 2 and 3 at 1 Hz,\n"
      "GPS time); --can writes the vehicle's speed and yaw rate as CAN frames (candump log).\n"
      "Same scenario and seed give byte-identical files.");
  std::string names;
  for (const auto& n : sim::scenario_names()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--scenario", o->scenario, "one of: " + names)
      ->check(CLI::IsMember(sim::scenario_names()))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed of the world and the sensor noise")
      ->capture_default_str();
  cmd->add_option("--duration", o->duration_s, "seconds to simulate")
      ->check(CLI::Range(0.1, 7200.0))
      ->capture_default_str();
  cmd->add_option("--out", o->out, "pcap file to write");
  cmd->add_option("--kitti-raw", o->kitti_raw,
                  "also (or, without --out, only) write the drive as a KITTI raw drive folder: "
                  "velodyne_points (each complete scan's points, not deskewed), oxts (a record at "
                  "each scan's mid-sweep time), calib_imu_to_velo.txt");
  cmd->add_option("--truth", o->truth, "truth file to write (JSON lines, one per scan)")
      ->required();
  cmd->add_option("--calib", o->calib, "calibration of the virtual unit (default: the config's)");
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_flag("--dual-return", o->dual_return,
                "dual-return mode (strongest and last): an S3, or the --model's");
  cmd->add_option("--model", o->model,
                  "the virtual sensor: S2.1 (default; S3 with --dual-return), S2, S3, HDL-32E, "
                  "VLP-16, Puck LITE, Puck Hi-Res or VLP-32C, with velodyne.model_calibrations' "
                  "calibration for it unless --calib is given (docs/velodyne.md)");
  cmd->add_option("--origin", o->origin,
                  "geodetic anchor of the sim world LAT,LON,ALT (deg, deg, m ellipsoidal; default "
                  "44.2449408681,-76.5096210157,77)");
  cmd->add_option("--without", o->without,
                  "leave this kind out of the world (repeatable; e.g. pole: a street known to hold "
                  "none, the background set when a new class is taught)");
  cmd->add_flag("--ins-udp", o->ins_udp,
                "send the Applanix stream as UDP datagrams to port 5602 (default: TCP)");
  cmd->add_option("--can", o->can,
                  "also write the vehicle's speed and yaw-rate CAN frames to this candump log "
                  "(DBC signal map of the config's can: section)");
  cmd->callback([o] {
    if (const int code = run_sim(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

// stac process: a capture (or a KITTI raw drive folder) through the whole per-scan pipeline,
// offline (offline/process_job.hpp): the options, a progress bar, the summary on stderr.
#include <cstdio>
#include <memory>
#include <string>

#include "offline/process_job.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"
#include "tools/support/terminal_output.hpp"

namespace stac::tools {

void add_process_command(CLI::App& app) {
  auto o = std::make_shared<offline::ProcessJobOptions>();
  CLI::App* cmd = app.add_subcommand(
      "process", "Run a capture through decode, deskew, segmentation and tracking");
  cmd->description(
      "Runs a capture through the per-scan pipeline as fast as possible, deterministically:\n"
      "decode -> deskew (with the capture's Applanix INS stream, when it has one) -> segment ->\n"
      "track -> classify (with a model), and writes one JSON line per scan (segments and tracks in "
      "the world frame,\n"
      "docs/evaluation.md). With --truth (a `stac sim` truth file) each segment also says which\n"
      "truth objects its points fall in, for `stac eval`. Prints CPU time per stage at the end.\n"
      "The input may also be a KITTI raw drive folder (velodyne_points/data/*.bin, with\n"
      "velodyne_points/timestamps.txt when it has one): its oxts/ records are the INS (tracks in\n"
      "the world, real speeds; the mounting from calib_imu_to_velo.txt, in the folder or the one\n"
      "above), or without oxts/ (or with --no-deskew) it is processed without a pose (parked).");
  cmd->add_option("capture", o->in,
                  "pcap capture (HDL-64E UDP, optionally the POS LV stream), or a KITTI raw drive "
                  "folder")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--tracks", o->tracks, "output: the tracks file (JSON lines)")->required();
  cmd->add_option("--truth", o->truth, "truth file of a simulated drive (adds segment composition)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--calib", o->calib, "calibration file or 'stream' (default: the config's)");
  cmd->add_option("--sensor", o->sensor,
                  "the lidar model (default: the config's velodyne.model): S2, S2.1, S3, HDL-32E, "
                  "VLP-16, Puck LITE, Puck Hi-Res, VLP-32C, or auto (the model the capture's "
                  "packets name); its calibration from velodyne.model_calibrations unless --calib");
  cmd->add_option(
      "--origin", o->origin,
      "LAT,LON,ALT of the world frame (default: the truth's, else the config's ego.origin)");
  needs_pictures(cmd->add_option("--pictures", o->pictures,
                                 "write a bird's-eye picture of each scan into this folder "
                                 "(scan_NNNNNN.png: points, segments, tracks)"));
  cmd->add_flag("--no-deskew", o->no_deskew,
                "ignore the INS stream: no deskew, sensor frame = world");
  cmd->add_option("--model", o->model,
                  "track classifier model (`stac train`) or 'none' (default: the config's "
                  "classification.model): every track gets a class and log odds (ADBF)");
  cmd->add_flag(
      "--dds", o->dds,
      "also publish every scan's tracked_objects, segments, ego_pose (and point_cloud) on "
      "DDS (the config's dds:)");
  cmd->add_option("--domain", o->domain, "DDS domain with --dds (default: dds.domain_id)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--point-cloud-stride", o->point_cloud_stride,
                  "with --dds, publish point_cloud: every segment return and every Nth other one; "
                  "0: none (default: dds.point_cloud_stride)")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--dds-config", o->dds_config,
                  "with --dds: Cyclone DDS XML, e.g. a secure one of deploy/dds-security.sh "
                  "(default: dds.config_file)")
      ->check(CLI::ExistingFile);
  cmd->add_option(
         "--dds-wait", o->dds_wait_s,
         "with --dds: wait up to S seconds (a day at most) for a tracked_objects reader before "
         "the first scan")
      ->check(finite_range(0, 86'400));
  cmd->callback([o] {
    TerminalOutput terminal;
    const rt::Status done = offline::run_process_job(*o, terminal.output());
    terminal.finish();
    if (!done) throw CLI::RuntimeError(fail(done.error().message));
  });
}

}  // namespace stac::tools

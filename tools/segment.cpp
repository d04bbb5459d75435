// stac segment: one scan (a KITTI .bin, or scan N of a pcap capture or a KITTI raw drive folder)
// -> segments (offline/segment_job.hpp): the options, the summary on stderr.
#include <memory>
#include <string>

#include "offline/segment_job.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"
#include "tools/support/terminal_output.hpp"

namespace stac::tools {

void add_segment_command(CLI::App& app) {
  auto o = std::make_shared<offline::SegmentJobOptions>();
  CLI::App* cmd =
      app.add_subcommand("segment", "Segment one scan into obstacles (csv, picture, summary)");
  cmd->description(
      "Segment one scan into obstacle segments: ground by a local ground grid, obstacle cells on "
      "a\n"
      "2D grid, 8-connected flood fill (docs/segmentation.md). Input: a KITTI velodyne .bin\n"
      "(float32 x,y,z,reflectance), a pcap capture of Velodyne packets or a KITTI raw drive\n"
      "folder (--scan N picks the scan).\n"
      "csv: one row per segment: id,points,centroid_x,centroid_y,centroid_z,box_x,box_y,length,\n"
      "width,height,yaw (rad, from x, counter-clockwise),z_min,z_max (m, sensor frame).");
  cmd->add_option("--in", o->in,
                  "KITTI .bin scan, a pcap/pcapng capture (told apart by their first bytes), or a "
                  "KITTI raw drive folder")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--out", o->out, "write the segments as csv");
  needs_pictures(cmd->add_option("--png", o->png,
                                 "draw the scan from above with the segments coloured and boxed"));
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--scan", o->scan,
                  "a capture or drive folder: which complete scan to segment, from 0 (default 0)");
  cmd->add_option("--calib", o->calib,
                  "pcap: calibration file or 'stream' (default: the config's)");
  cmd->add_option("--view-range", o->view_range_m, "picture: half width in metres (default 50)")
      ->check(finite_range(1.0, 1000.0));
  cmd->callback([o] {
    TerminalOutput terminal;
    const rt::Status done = offline::run_segment_job(*o, terminal.output());
    terminal.finish();
    if (!done) throw CLI::RuntimeError(fail(done.error().message));
  });
}

}  // namespace stac::tools

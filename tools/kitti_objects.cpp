// stac kitti-objects: the real KITTI object frames through the segmenter and the track classifier
// (offline/kitti_objects_job.hpp): the options, the tables.
#include <memory>
#include <string>

#include "offline/kitti_objects_job.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"
#include "tools/support/terminal_output.hpp"

namespace stac::tools {

void add_kitti_objects_command(CLI::App& app) {
  auto o = std::make_shared<offline::KittiObjectsJobOptions>();
  CLI::App* cmd = app.add_subcommand(
      "kitti-objects", "Segment and classify the labelled objects of KITTI object frames");
  cmd->description(
      "Runs each frame of a KITTI object folder (velodyne/*.bin, calib/, label_2/) through the\n"
      "segmenter and, for every labelled object within --max-range, finds the segment holding\n"
      "most of the obstacle points in its box: segmented (that segment holds most of them and is\n"
      "mostly the object), under-segmented (mostly something else), over-segmented (the object\n"
      "is split), missed (no point in a segment) or no points. That segment is classified by the\n"
      "model's segment classifier and by the ADBF as a track's first update (single frames: no\n"
      "motion). Prints a table per object and per KITTI type; --report writes objects.csv,\n"
      "metrics.json and a picture from above per frame (docs/classification.md).");
  cmd->add_option("--dir", o->dir, "KITTI object folder")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--model", o->model, "track classifier model (default: classification.model)");
  cmd->add_option("--max-range", o->max_range_m, "objects within this range of the sensor (m)")
      ->check(finite_range(0.1, 1000.0));
  cmd->add_option("--margin", o->margin_m, "label boxes are grown by this for point membership (m)")
      ->check(finite_range(0.0, 10.0));
  cmd->add_option("--report", o->report, "folder for objects.csv, metrics.json and the pictures");
  cmd->callback([o] {
    TerminalOutput terminal;
    const rt::Status done = offline::run_kitti_objects_job(*o, terminal.output());
    terminal.finish();
    if (!done) throw CLI::RuntimeError(fail(done.error().message));
  });
}

}  // namespace stac::tools

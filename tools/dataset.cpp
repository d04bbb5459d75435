// stac dataset: labelled tracks from simulated drives, for `stac train` and `stac eval --classes`
// (offline/dataset_job.hpp): the options, a progress bar per drive, the counts.
#include <cstdio>
#include <memory>
#include <string>

#include "offline/dataset_job.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/terminal_output.hpp"

namespace stac::tools {

void add_dataset_command(CLI::App& app) {
  auto o = std::make_shared<offline::DatasetJobOptions>();
  CLI::App* cmd = app.add_subcommand(
      "dataset", "Track descriptors from drives: labelled (stac train) or not (stac induct)");
  cmd->description(
      "Runs each capture through the per-scan pipeline (as `stac process`), describes every\n"
      "segment each track is updated with and the track's holistic descriptor after it, labels\n"
      "each track by the majority truth class of its segments' points (car, pedestrian,\n"
      "bicyclist, each --class kind, else background), keeps tracks of at least 10 segments with "
      "one over 75\n"
      "points, counts per track the segments that are tracking or under-segmentation errors\n"
      "(over 10%: inconsistent, left out by `stac train` and `stac eval --classes`, as in the\n"
      "thesis), and writes DIR/tracks.bin and DIR/manifest.json (docs/classification.md).\n"
      "A KITTI raw drive folder is an input too (its oxts/ records the INS, docs/kitti.md).\n"
      "Without --truth (any capture, a real drive too) the tracks are unlabeled: data for\n"
      "`stac induct --unlabeled` (or --background for drives without the taught classes).\n"
      "--merge DIR... joins datasets made apart (one per capture, e.g. by the Slurm job\n"
      "array deploy/slurm-dataset.sh) into one.");
  cmd->add_option("--in", o->in,
                  "pcap capture or KITTI raw drive folder (repeatable): a `stac sim` drive (or "
                  "its --kitti-raw folder), or any with no --truth")
      ->check(CLI::ExistingPath);
  cmd->add_option("--truth", o->truth,
                  "its truth file (one per --in, same order); without: unlabeled tracks, for "
                  "`stac induct --unlabeled` or --background")
      ->check(CLI::ExistingFile);
  cmd->add_option("--merge", o->merge,
                  "instead of --in: datasets (folders) to join into one, in this order; their "
                  "classes must match, all labelled or all not (repeatable)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", o->out, "output folder")->required();
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--calib", o->calib, "calibration file or 'stream' (default: the config's)");
  cmd->add_option("--class", o->extra_classes,
                  "a simulator background kind (pole, sign, bin, tree, ...) labelled as a class "
                  "of its own after car, pedestrian, bicyclist (repeatable; up to 8 classes)");
  cmd->add_flag("--no-deskew", o->no_deskew,
                "ignore the INS stream: no deskew, sensor frame = world");
  cmd->callback([o] {
    TerminalOutput terminal;
    const rt::Status done = offline::run_dataset_job(*o, terminal.output());
    terminal.finish();
    if (!done) throw CLI::RuntimeError(fail(done.error().message));
  });
}

}  // namespace stac::tools

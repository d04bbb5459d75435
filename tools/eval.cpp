// stac eval: segmentation and tracking metrics of a tracks file against the truth (offline/
// eval_job.hpp), or with --classes a classifier on datasets (offline/class_eval_job.hpp): the
// options, a progress bar, the results. Definitions: docs/evaluation.md.
#include <memory>
#include <string>

#include "offline/class_eval_job.hpp"
#include "offline/eval_job.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/terminal_output.hpp"

namespace stac::tools {
namespace {

struct EvalOptions {
  offline::EvalJobOptions job;  // its report from --report
  std::string report;
  bool classes = false;
  offline::ClassEvalJobOptions class_options;
};

}  // namespace

void add_eval_command(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Segmentation and tracking metrics (CLEAR MOT, HOTA) of a tracks file against the truth");
  cmd->add_option("--truth", o->job.truth,
                  "truth JSON lines written by `stac sim --truth` (required without --classes)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--tracklets", o->job.tracklets,
                  "instead of --truth: a KITTI raw drive's tracklet_labels.xml (Car, Van, Truck, "
                  "Tram -> car; Pedestrian, Person_sitting -> pedestrian; Cyclist -> bicyclist; "
                  "Misc and DontCare left out), placed in the world by the drive's poses")
      ->check(CLI::ExistingFile);
  cmd->add_option("--drive", o->job.drive,
                  "with --tracklets: the drive folder (default: the tracklets file's folder)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--config", o->job.config_file,
                  std::string(stac::settings::kConfigOptionHelp) +
                      " (with --tracklets: the mounting when the drive has no "
                      "calib_imu_to_velo.txt)");
  cmd->add_option(
         "--tracks", o->job.tracks,
         "tracks JSON lines written by `stac process --tracks` (required without --classes)")
      ->check(CLI::ExistingFile);
  cmd->add_flag(
      "--classes", o->classes,
      "classification instead (thesis Table 1.2): needs --data and --model, not --truth/--tracks");
  cmd->add_option("--data", o->class_options.data,
                  "with --classes: a `stac dataset` folder (repeatable)");
  cmd->add_option("--model", o->class_options.model,
                  "with --classes: the model file of `stac train`");
  cmd->add_option("--report", o->report, "folder for report.md, metrics.json and the plots");
  cmd->add_option("--max-range", o->job.config.max_range_m,
                  "evaluate truth objects within this range of the ego (m)")
      ->capture_default_str();
  cmd->add_option("--min-points", o->job.config.min_points,
                  "evaluate truth objects with at least this many points")
      ->capture_default_str();
  cmd->add_flag("--with-coasting", o->job.config.count_coasting,
                "count coasting tracks (predicted, not updated in the scan) as outputs too");
  cmd->footer(
      "Metric definitions: docs/evaluation.md.\nExample:\n"
      "  stac eval --truth run.truth.jsonl --tracks run.tracks.jsonl --report eval/\n"
      "  stac eval --tracklets drive/tracklet_labels.xml --tracks drive.tracks.jsonl  # KITTI raw\n"
      "  stac eval --classes --data test/ --model model.stac --report cls/  # classification");
  cmd->callback([o] {
    int code = 0;
    if (o->classes) {
      if (!o->job.truth.empty() || !o->job.tracks.empty()) {
        code = fail(
            "--classes evaluates a classifier on --data and --model; --truth/--tracks are for "
            "tracking");
      } else if (o->class_options.data.empty() || o->class_options.model.empty()) {
        code = fail(
            "--classes needs --data DIR (a `stac dataset` folder) and --model MODEL (`stac train "
            "--out`)");
      } else {
        o->class_options.report = o->report;
        TerminalOutput terminal;
        const rt::Status done = offline::run_class_eval_job(o->class_options, terminal.output());
        terminal.finish();
        if (!done) code = fail(done.error().message);
      }
    } else if (!o->job.truth.empty() && !o->job.tracklets.empty()) {
      code = fail("--truth or --tracklets, not both");
    } else if ((o->job.truth.empty() && o->job.tracklets.empty()) || o->job.tracks.empty()) {
      code = fail(
          "--truth (or --tracklets) and --tracks are required (or --classes with --data and "
          "--model)");
    } else if (!o->class_options.data.empty() || !o->class_options.model.empty()) {
      code = fail("--data and --model go with --classes");
    } else {
      offline::EvalJobOptions job = o->job;
      job.report = o->report;
      TerminalOutput terminal;
      const rt::Status done = offline::run_eval_job(job, terminal.output());
      terminal.finish();
      if (!done) code = fail(done.error().message);
    }
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

// The tracking evaluation job (`stac eval`): a tracks file (`stac process --tracks`) against the
// truth, a simulator's truth file or a KITTI raw drive's tracklet labels: segmentation metrics,
// CLEAR MOT and HOTA overall, by range band and by class (docs/evaluation.md), with a markdown
// report, metrics.json and plots on request.
#pragma once

#include <string>

#include "evaluation/evaluation.hpp"
#include "offline/job_output.hpp"
#include "rt/expected.hpp"

namespace stac::offline {

struct EvalJobOptions {
  std::string truth;        // a `stac sim --truth` file, or
  std::string tracklets;    // a KITTI raw drive's tracklet_labels.xml,
  std::string drive;        // with its drive folder (default: the tracklets file's folder)
  std::string config_file;  // the configuration (the mounting, for tracklets without one)
  std::string tracks;       // the tracks file evaluated
  std::string report;       // a folder for report.md, metrics.json, range.png, classes.png
  evaluation::EvalConfig config;
};

// Runs the job: the summary table as its result, notes as its text, the files read as progress
// ("eval: reading"). An error says what to fix.
rt::Status run_eval_job(const EvalJobOptions& options, const JobOutput& output = {});

}  // namespace stac::offline

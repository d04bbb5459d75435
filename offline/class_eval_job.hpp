// The classification evaluation job (`stac eval --classes`): Table 1.2 of the thesis on `stac
// dataset` folders with a trained model (docs/classification.md "Evaluation"): accuracy per class
// and filter, track-wise and segment-wise, and with a report folder metrics.json, tracks.csv,
// confusion.png and pr.png.
#pragma once

#include <string>
#include <vector>

#include "offline/job_output.hpp"
#include "rt/expected.hpp"

namespace stac::offline {

struct ClassEvalJobOptions {
  std::vector<std::string> data;  // dataset folders
  std::string model, report;
};

// The table as its result, the tracks classified as progress ("eval: classifying"); an error says
// what to fix.
rt::Status run_class_eval_job(const ClassEvalJobOptions& options, const JobOutput& output = {});

}  // namespace stac::offline

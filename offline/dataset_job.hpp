// The dataset job (`stac dataset`): track descriptors from drives, labelled by their truth (for
// `stac train` and `stac eval --classes`) or unlabeled (for `stac induct`), written as a dataset
// folder (formats/dataset_file.hpp); or datasets made apart joined into one (--merge). Its text:
// each drive's counts; its result: the dataset written; its progress: each drive read.
#pragma once

#include <string>
#include <vector>

#include "offline/job_output.hpp"
#include "rt/expected.hpp"

namespace stac::offline {

struct DatasetJobOptions {
  std::vector<std::string> in;     // captures or KITTI raw drive folders
  std::vector<std::string> truth;  // one truth file per input, or none (unlabeled tracks)
  std::vector<std::string> merge;  // instead of `in`: datasets to join, in order
  std::string out;                 // the dataset folder written
  std::string config, calib;
  std::vector<std::string> extra_classes;  // simulator kinds labelled as classes of their own
  bool no_deskew = false;
};

// Runs the job; an error says what to fix (an option, a file).
rt::Status run_dataset_job(const DatasetJobOptions& options, const JobOutput& output = {});

}  // namespace stac::offline

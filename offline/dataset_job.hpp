// The dataset job (`stac dataset`): track descriptors from drives, labelled by their truth (for
// `stac train` and `stac eval --classes`) or unlabeled (for `stac induct`), written as a dataset
// folder (formats/dataset_file.hpp); or datasets made apart joined into one (--merge).
#pragma once

#include <functional>
#include <string>
#include <vector>

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

struct DatasetJobOutput {
  std::function<void(const std::string&)> text;    // what it did, whole lines (a person's)
  std::function<void(const std::string&)> result;  // the dataset written and its counts
  // The drive being read (its label, e.g. "dataset drive.pcap") and how far.
  std::function<void(const std::string& label, double done, double total)> progress;
};

// Runs the job; an error says what to fix (an option, a file).
rt::Status run_dataset_job(const DatasetJobOptions& options, const DatasetJobOutput& output = {});

}  // namespace stac::offline

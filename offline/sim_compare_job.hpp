// The simulator's realism job (`stac sim-compare`): how close simulated scans come to real ones.
// It decodes a `stac sim` capture with the project's decoder and reads real KITTI HDL-64E scans
// (float32 x,y,z,reflectance, sensor frame, stored ring by ring), computes the same statistics on
// both, and writes a report (realism.md, realism.json, charts and a bird's-eye picture of each,
// same scale).
#pragma once

#include <string>

#include "offline/job_output.hpp"
#include "rt/expected.hpp"

namespace stac::offline {

struct SimCompareJobOptions {
  std::string sim;               // a `stac sim` capture
  std::string kitti;             // a KITTI .bin scan, a folder of them, or a KITTI raw drive folder
  std::string report;            // the report folder
  std::string calib;             // the simulated unit's calibration (empty: the configuration's)
  std::string config;            // empty: the default configuration
  double mount_height_m = 1.73;  // KITTI's HDL-64E and the simulator's default
  double ground_margin_m = 0.3;  // ground: z below -mount height + this
  int max_scans = 0;             // 0: every complete scan
};

// The summary as its text; an error says what to fix.
rt::Status run_sim_compare_job(const SimCompareJobOptions& options, const JobOutput& output = {});

}  // namespace stac::offline

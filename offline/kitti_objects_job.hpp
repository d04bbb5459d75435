// The KITTI objects job (`stac kitti-objects`): the real KITTI object frames through the segmenter
// and the track classifier, per labelled object within range: was it segmented (one segment
// holding most of its obstacle points, mostly its own) and what was it classified as (the segment
// classifier alone, and the ADBF after that one segment, as a track's first update would be).
// Single frames: no motion, so the holistic evidence is that of a standing object.
#pragma once

#include <string>

#include "offline/job_output.hpp"
#include "rt/expected.hpp"

namespace stac::offline {

struct KittiObjectsJobOptions {
  std::string dir;     // a KITTI object folder: velodyne/*.bin, calib/, label_2/
  std::string config;  // empty: the default configuration
  std::string model;   // empty: the configuration's classification.model
  std::string report;  // a folder for objects.csv, metrics.json and a picture per frame
  double max_range_m = 40.0;
  double margin_m = 0.1;  // label boxes grown by this for point membership
};

// The tables as its result; an error says what to fix.
rt::Status run_kitti_objects_job(const KittiObjectsJobOptions& options,
                                 const JobOutput& output = {});

}  // namespace stac::offline

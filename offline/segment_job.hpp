// The segment job (`stac segment`): one scan, a KITTI .bin file or complete scan N of a capture
// or a KITTI raw drive folder (formats/recorded_drive.hpp; not deskewed), through the segmenter
// with the configuration's segmentation: section; the segments as csv and a picture on request,
// and a summary of the point, cell and segment counts and the time it took.
#pragma once

#include <string>

#include "offline/job_output.hpp"
#include "rt/expected.hpp"

namespace stac::offline {

struct SegmentJobOptions {
  std::string in;              // a KITTI .bin scan, a capture, or a KITTI raw drive folder
  std::string out;             // the segments as csv (empty: none)
  std::string png;             // the scan from above with its segments (empty: none)
  std::string config;          // empty: the default configuration
  std::string calib;           // a capture's calibration, or "stream" (empty: the configuration's)
  int scan = 0;                // of a capture or a drive folder, from 0
  double view_range_m = 50.0;  // the picture's half width
};

// The summary as its text; an error says what to fix.
rt::Status run_segment_job(const SegmentJobOptions& options, const JobOutput& output = {});

}  // namespace stac::offline

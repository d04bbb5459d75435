// The offline process job (`stac process`): a capture or a KITTI raw drive folder through the
// whole per-scan pipeline, as fast as possible and deterministic: decode -> (INS poses) deskew ->
// segment -> track -> classify -> a tracks file (evaluation/tracks_jsonl.hpp), with the truth's
// segment composition when a truth file is given, a bird's-eye picture of each scan on request,
// the results published on DDS on request, and a summary with per-stage CPU time statistics.
#pragma once

#include <string>

#include "offline/job_output.hpp"
#include "rt/expected.hpp"

namespace stac::offline {

struct ProcessJobOptions {
  std::string in;        // a capture (pcap) or a KITTI raw drive folder
  std::string tracks;    // the tracks file written
  std::string truth;     // a truth file (stac sim): segment composition and the frame's origin
  std::string config;    // empty: the default configuration
  std::string calib;     // a calibration to use instead of the configuration's
  std::string origin;    // "lat,lon,alt": the ENU frame's origin
  std::string model;     // a model file instead of the configuration's
  std::string pictures;  // a folder for scan_NNNNNN.png, one per scan
  std::string sensor;    // the Velodyne model, or "auto"
  bool no_deskew = false;
  // DDS: publish every scan's results as stac run does.
  bool dds = false;
  int domain = -1;              // -1: the configuration's
  std::string dds_config;       // a Cyclone XML instead of the configuration's
  int point_cloud_stride = -1;  // -1: the configuration's
  double dds_wait_s = 0;        // wait up to this long for a reader before the first scan
};

// Runs the job; an error says what to fix (after the summary when the run itself went through).
// Its text: the summary (and DDS errors); its progress: the input read ("process").
rt::Status run_process_job(const ProcessJobOptions& options, const JobOutput& output = {});

}  // namespace stac::offline

// The decode job, shared by `stac decode` and `stac demo`.
#pragma once

#include <string>

namespace stac::tools {

struct DecodeOptions {
  std::string config;  // empty: default_config_path()
  std::string calib;   // empty: the config's; "stream": from the status bytes
  std::string in;      // pcap capture
  std::string out;     // csv file or kitti folder
  std::string format = "csv";
  std::string model;            // empty: the config's
  std::string png;              // empty: no picture
  int port = -1;                // < 0: the config's
  double cut_angle_deg = -1.0;  // < 0: the config's
};

// Prints a summary on stderr; returns the process exit code (0 ok, 1 with a message printed).
int run_decode(const DecodeOptions& options);

}  // namespace stac::tools

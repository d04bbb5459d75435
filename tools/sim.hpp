// The simulate job, shared by `stac sim` and `stac demo`: a simulated drive written as the real
// devices' bytes (pcap: HDL-64E UDP and the Applanix stream; optionally a candump log) plus its
// ground truth per scan (docs/simulator.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace stac::tools {

struct SimOptions {
  std::string scenario = "urban";
  std::uint64_t seed = 1;
  double duration_s = 10.0;
  std::string out;
  std::string truth;
  std::string calib;
  std::string config;
  bool dual_return = false;
  std::string model;   // the virtual sensor (velodyne::parse_model); empty: an HDL-64E S2.1 (S3
                       // with dual_return)
  std::string origin;  // "LAT,LON,ALT"; empty: sim::InsConfig's default
  bool ins_udp = false;
  std::string can;                   // candump log to write; empty: none
  std::vector<std::string> without;  // kinds left out of the world (sim::RunConfig::without)
  std::string kitti_raw;  // also (or only, without `out`) the drive in KITTI raw's layout here
};

// Prints a summary on stderr; returns the process exit code (0 ok, 1 with a message printed).
int run_sim(const SimOptions& options);

}  // namespace stac::tools

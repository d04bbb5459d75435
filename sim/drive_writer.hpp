// A simulated drive written as the real devices' bytes (pcap: the Velodyne's UDP and the Applanix
// stream; optionally a candump log and the drive in KITTI raw's layout) plus its ground truth per
// scan (docs/simulator.md): `stac sim`, `stac demo`, and the tests that need a drive.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::sim {

struct DriveOptions {
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

// What the writer tells the person waiting for it (both optional).
struct DriveOutput {
  std::function<void(const std::string&)> summary;  // lines of its summary, at the end
  std::function<void(std::uint32_t done, std::uint32_t total)> progress;  // packets written
};

// Writes the drive OPTIONS describes; an error says what to fix (an option, a file).
rt::Status write_drive(const DriveOptions& options, const DriveOutput& output = {});

}  // namespace stac::sim

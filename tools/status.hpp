// Reading the HDL-64E S2.1/S3 status cycle out of a capture: for `stac status` and for
// `--calib stream` (the calibration the unit sends instead of a file).
#pragma once

#include <cstdint>
#include <filesystem>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/status.hpp"
#include "rt/expected.hpp"

namespace stac::tools {

struct CaptureStatus {
  velodyne::StatusDecoder status;
  std::uint64_t packets = 0;  // 1206-byte payloads on the data port
  io::PcapCounters pcap;
};

// Feeds every data packet's status bytes to a decoder; with `until_calibration` it stops at the
// first accepted calibration dump. Fails when the file cannot be read or the model sends no
// status cycle (S2).
rt::Result<CaptureStatus> read_capture_status(const std::filesystem::path& capture,
                                              std::uint16_t port, velodyne::Model model,
                                              bool until_calibration);

// The calibration carried in the capture's status bytes, or an error that says what to do.
rt::Result<velodyne::Calibration> stream_calibration(const std::filesystem::path& capture,
                                                     std::uint16_t port, velodyne::Model model);

// The calibration `settings` name for decoding `capture`: its file, or (empty path, 'stream')
// the one the unit sent in the capture's status bytes.
rt::Result<velodyne::Calibration> capture_calibration(const std::filesystem::path& calibration_file,
                                                      const std::filesystem::path& capture,
                                                      std::uint16_t port, velodyne::Model model);

}  // namespace stac::tools

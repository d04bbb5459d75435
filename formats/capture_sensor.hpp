// The sensor of a capture, for the commands that decode one: which model its packets name, and
// the calibration to decode them with (a file, or the one an HDL-64E S2.1/S3 sends in its status
// bytes: `--calib stream`); `stac status` reads the status cycle with it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/status.hpp"
#include "rt/expected.hpp"
#include "settings/settings.hpp"

namespace stac::formats {

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

// What the first data packets of a capture say about their sensor (velodyne::PacketIdentity of
// the first of up to 200 packets that says anything); kUnknown when none does.
rt::Result<velodyne::PacketIdentity> capture_identity(const std::filesystem::path& capture,
                                                      std::uint16_t port);

// A command line's sensor model over the configuration's: a model name (use_velodyne_model), or
// "auto" (the capture's packets name it: capture_sensor); empty: the configuration's.
rt::Status apply_sensor_option(settings::VelodyneSettings& settings, const std::string& option,
                               bool calibration_given);

// The sensor of a capture, for the commands that decode one: with 'velodyne.model: auto' the
// model its packets name (an HDL-64E's do not say which: S2.1 then, said so), else the
// configured one, with a warning when the packets name another; its calibration
// (capture_calibration, or velodyne.model_calibrations for an auto-detected model), checked to
// fit the model. Writes one line on stderr saying what it assumed when that is not plain.
rt::Result<velodyne::Calibration> capture_sensor(settings::VelodyneSettings& settings,
                                                 const std::filesystem::path& capture,
                                                 bool calibration_given);

}  // namespace stac::formats

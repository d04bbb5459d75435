// What the `can:` section of config/stac.yaml sets (loaded at the edge: settings/settings.hpp,
// load_can_settings). The DBC path is relative to the config file.
#pragma once

#include <filesystem>
#include <string>

#include "drivers/can/cannelloni.hpp"
#include "drivers/can/gs_usb_device.hpp"
#include "drivers/can/odometry.hpp"
#include "drivers/can/socketcan.hpp"

namespace stac::can {

enum class Transport : std::uint8_t { kSocketCan, kGsUsb, kCannelloni };

struct CanConfig {
  Transport transport = Transport::kSocketCan;
  SocketCanConfig socketcan;    // interface; filters are filled from the signal map
  GsUsbConfig gs_usb;           // bitrate, channel, listen-only
  CannelloniConfig cannelloni;  // UDP address and port
  std::filesystem::path dbc;
  OdometrySignalMap signals;
  DeadReckoningConfig dead_reckoning;
};

}  // namespace stac::can

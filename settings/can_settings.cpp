// The `can:` section of config/stac.yaml (see settings/settings.hpp).
#include <cmath>

#include "drivers/io/datagram.hpp"
#include "settings/config_section.hpp"
#include "settings/settings.hpp"

namespace stac::settings {

rt::Result<can::CanConfig> load_can_settings(const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "can");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& c = *section;

  using namespace can;
  CanConfig cfg;
#define STAC_GET(type, key, dst) STAC_CONFIG_GET(c, type, key, dst)
  std::string transport, dbc;
  long long bitrate = 0;
  int channel = 0, cannelloni_port = 0;
  double stale_s = 0;
  STAC_GET(std::string, "transport", transport);
  STAC_GET(std::string, "interface", cfg.socketcan.interface);
  STAC_GET(long long, "bitrate_bps", bitrate);
  STAC_GET(int, "gs_usb_channel", channel);
  STAC_GET(bool, "gs_usb_listen_only", cfg.gs_usb.listen_only);
  STAC_GET(std::string, "cannelloni_address", cfg.cannelloni.bind_address);
  STAC_GET(int, "cannelloni_port", cannelloni_port);
  STAC_GET(std::string, "dbc", dbc);
  STAC_GET(std::string, "speed_message", cfg.signals.speed_message);
  STAC_GET(std::string, "speed_signal", cfg.signals.speed_signal);
  STAC_GET(std::string, "yaw_rate_message", cfg.signals.yaw_rate_message);
  STAC_GET(std::string, "yaw_rate_signal", cfg.signals.yaw_rate_signal);
  STAC_GET(double, "yaw_rate_sign", cfg.signals.yaw_rate_sign);
  STAC_GET(double, "stale_timeout_s", stale_s);
#undef STAC_GET

  if (transport == "socketcan") {
    cfg.transport = Transport::kSocketCan;
  } else if (transport == "gs_usb") {
    cfg.transport = Transport::kGsUsb;
  } else if (transport == "cannelloni") {
    cfg.transport = Transport::kCannelloni;
  } else {
    return c.error("transport", "is '" + transport + "'; use socketcan, gs_usb or cannelloni");
  }
  if (std::uint32_t address = 0; !io::parse_ipv4(cfg.cannelloni.bind_address.c_str(), address)) {
    return c.error("cannelloni_address",
                   "is '" + cfg.cannelloni.bind_address +
                       "'; give a dotted IPv4 address (0.0.0.0: every interface)");
  }
  if (cannelloni_port < 0 || cannelloni_port > 65535)
    return c.error("cannelloni_port", "must be in 0..65535");
  cfg.cannelloni.port = static_cast<std::uint16_t>(cannelloni_port);
  if (cfg.socketcan.interface.empty() || cfg.socketcan.interface.size() > 15) {
    return c.error("interface", "must have 1..15 characters");
  }
  if (bitrate < 10'000 || bitrate > 1'000'000) {
    return c.error("bitrate_bps", "must be in 10000..1000000 (classic CAN)");
  }
  cfg.gs_usb.bitrate_bps = static_cast<std::uint32_t>(bitrate);
  if (channel < 0 || channel > 7) return c.error("gs_usb_channel", "must be in 0..7");
  cfg.gs_usb.channel = static_cast<std::uint8_t>(channel);
  if (cfg.signals.yaw_rate_sign != 1.0 && cfg.signals.yaw_rate_sign != -1.0) {
    return c.error("yaw_rate_sign", "must be 1 or -1");
  }
  if (!(stale_s > 0 && stale_s <= 10)) return c.error("stale_timeout_s", "must be in (0, 10]");
  cfg.dead_reckoning.stale_timeout_ns = std::llround(stale_s * 1e9);
  if (dbc.empty()) return c.error("dbc", "must name a DBC file");
  cfg.dbc = c.path(dbc);
  return cfg;
}

}  // namespace stac::settings

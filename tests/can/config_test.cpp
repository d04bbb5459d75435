#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "settings/settings.hpp"
#include "test_paths.hpp"

namespace stac::can {
namespace {

const std::filesystem::path kShipped =
    std::filesystem::path(::stac::testing::source_dir()) / "config/stac.yaml";

TEST(CanConfig, TheShippedConfigLoadsAndMapsTheShippedDbc) {
  const auto c = settings::load_can_settings(kShipped);
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->transport, Transport::kSocketCan);
  EXPECT_EQ(c->socketcan.interface, "can0");
  EXPECT_EQ(c->gs_usb.bitrate_bps, 500'000u);
  EXPECT_EQ(c->dead_reckoning.stale_timeout_ns, 200'000'000);
  const auto db = load_dbc(c->dbc);
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_TRUE(OdometryDecoder::create(*db, c->signals));
}

int serial = 0;

// Writes the shipped file with one line of the can: section replaced (or removed).
std::filesystem::path variant(const std::string& key, const std::string& replacement) {
  std::ifstream in(kShipped);
  std::stringstream text;
  text << in.rdbuf();
  const std::string edited = std::regex_replace(text.str(), std::regex("\n  " + key + ":[^\n]*"),
                                                replacement.empty() ? "" : "\n  " + replacement);
  const auto out = std::filesystem::temp_directory_path() / ("stac_can_config_" + key) /
                   ("stac" + std::to_string(++serial) + ".yaml");
  std::filesystem::create_directories(out.parent_path());
  std::ofstream(out) << edited;
  return out;
}

TEST(CanConfig, CannelloniIsATransportWithItsAddressAndPort) {
  const auto c = settings::load_can_settings(variant("transport", "transport: cannelloni"));
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->transport, Transport::kCannelloni);
  EXPECT_EQ(c->cannelloni.bind_address, "0.0.0.0");
  EXPECT_EQ(c->cannelloni.port, 20000);
}

TEST(CanConfig, EveryErrorNamesTheKey) {
  const std::pair<std::filesystem::path, std::string> cases[] = {
      {variant("stale_timeout_s", ""), "missing required key 'can.stale_timeout_s'"},
      {variant("transport", "transport: serial"), "'can.transport' is 'serial'"},
      {variant("bitrate_bps", "bitrate_bps: fast"), "'can.bitrate_bps' has the wrong type"},
      {variant("bitrate_bps", "bitrate_bps: 5000000"), "'can.bitrate_bps' must be in"},
      {variant("yaw_rate_sign", "yaw_rate_sign: 2"), "'can.yaw_rate_sign' must be 1 or -1"},
      {variant("interface", "interface: a_very_long_interface"), "'can.interface' must have"},
      {variant("cannelloni_address", "cannelloni_address: localhost"),
       "'can.cannelloni_address' is 'localhost'; give a dotted IPv4 address"},
      {variant("cannelloni_port", "cannelloni_port: 70000"),
       "'can.cannelloni_port' must be in 0..65535"},
  };
  for (const auto& [file, expected] : cases) {
    const auto c = settings::load_can_settings(file);
    ASSERT_FALSE(c) << expected;
    EXPECT_NE(c.error().message.find(expected), std::string::npos) << c.error().message;
    EXPECT_NE(c.error().message.find(file.string()), std::string::npos);
  }
}

}  // namespace
}  // namespace stac::can

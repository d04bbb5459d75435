// `stac-node --check` (issue 47): rc 0 only when the service can start with the configuration,
// so what the start refuses (an address the UDP receiver cannot parse, Cyclone XML Cyclone cannot
// use, an interface this machine does not have) is refused here, naming the file and the key.
// Loopback only: the Cyclone domain --check makes uses config/dds/loopback.xml (no participant).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "dds/dds_test_support.hpp"
#include "shared_data.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"

namespace stac::runtime {
namespace {

constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

struct Checked {
  std::filesystem::path config;
  stac::testing::CliResult result;
};

// `stac-node --check` of the shipped configuration with `edits` (tests/stac_cli.hpp), written to
// a folder of this test's own, on loopback DDS in a domain of its own.
Checked check_with(const std::string& test,
                   std::vector<std::pair<std::string, std::string>> edits) {
  (void)stac::testing::loopback_uri();  // this process's DDS_TEST_TAG, which stac-node inherits
  const auto dir = stac::testing::fresh_dir("stac_node_check_" + test);
  edits.emplace_back("domain_id", "171");
  std::string error;
  Checked c;
  c.config = stac::testing::shipped_config_with(dir, edits, &error);
  EXPECT_FALSE(c.config.empty()) << error;
  c.result = stac::testing::run_shell(std::string(::stac::testing::stac_node()) +
                                      " --check --config " + c.config.string());
  return c;
}

// A Cyclone XML file of `text` next to the test's configuration.
std::string xml_file(const std::string& test, const std::string& text) {
  const auto file = stac::testing::fresh_dir("stac_node_check_" + test + "_xml") / "cyclone.xml";
  std::ofstream(file) << text;
  return file.string();
}

TEST(NodeCheck, TheShippedConfigOnLoopbackIsComplete) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto [config, r] = check_with("complete", {});
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find(config.string() + " is complete: calibration "), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("DDS domain 171 with file://"), std::string::npos) << r.output;
}

TEST(NodeCheck, ABindAddressTheUdpReceiverCannotParseIsNamed) {
  const auto [config, r] = check_with("bind", {{"bind_address", "300.1.1.1"}});
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find(config.string() + ": 'velodyne.bind_address' is '300.1.1.1'; give a "
                                            "dotted IPv4 address"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("complete"), std::string::npos) << r.output;
}

// 192.0.2.1 (TEST-NET-1, RFC 5737) is an address no machine here has: the receiver could parse it
// but not bind it, so the service could not start.
TEST(NodeCheck, ABindAddressThisMachineDoesNotHaveIsNamed) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto [config, r] = check_with("bind_absent", {{"bind_address", "192.0.2.1"}});
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find(config.string() + ": 'velodyne.bind_address' is '192.0.2.1', which "
                                            "this machine cannot receive on (Cannot assign "
                                            "requested address)"),
            std::string::npos)
      << r.output;
  const auto [loopback_config, loopback] =
      check_with("bind_loopback", {{"bind_address", "127.0.0.1"}});
  EXPECT_EQ(loopback.code, 0) << loopback.output;
}

TEST(NodeCheck, CycloneXmlCycloneCannotParseIsNamed) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const std::string xml = xml_file("malformed", "<CycloneDDS><Domain><General>\n");
  const auto [config, r] = check_with("malformed", {{"config_file", xml}});
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find(config.string() +
                          ": 'dds.config_file': DDS domain 171: the Cyclone DDS "
                          "configuration file://" +
                          xml + " cannot be used (not Cyclone XML"),
            std::string::npos)
      << r.output;
}

TEST(NodeCheck, ACanInterfaceThisMachineDoesNotHaveIsNamed) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto [config, r] =
      check_with("can", {{"can", "true"}, {"transport", "socketcan"}, {"interface", "nosuchcan9"}});
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(
      r.output.find(config.string() + ": 'can.interface' is 'nosuchcan9', which this "
                                      "machine does not have: SocketCAN: no network "
                                      "interface 'nosuchcan9' (list them with `ip link show`"),
      std::string::npos)
      << r.output;
}

// No gs_usb adapter is plugged into a test machine: the check says so as the start would.
TEST(NodeCheck, AGsUsbAdapterThatIsNotPluggedInIsNamed) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto [config, r] = check_with("gs_usb", {{"can", "true"}, {"transport", "gs_usb"}});
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find(config.string() + ": 'can.transport' is gs_usb: gs_usb (1d50:606f): "),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("complete"), std::string::npos) << r.output;
}

TEST(NodeCheck, ACycloneInterfaceThisMachineDoesNotHaveIsNamed) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  std::ifstream in(std::filesystem::path(::stac::testing::source_dir()) /
                   "config/dds/loopback.xml");
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string lo = R"(name="lo")";
  ASSERT_NE(text.find(lo), std::string::npos);
  text.replace(text.find(lo), lo.size(), R"(name="nosuchif9")");
  const std::string xml = xml_file("interface", text);
  const auto [config, r] = check_with("interface", {{"config_file", xml}});
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("nosuchif9: does not match an available interface"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find(config.string() + ": 'dds.config_file': "), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace stac::runtime

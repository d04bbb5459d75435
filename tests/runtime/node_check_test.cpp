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

}  // namespace
}  // namespace stac::runtime

// deploy/stac.service: parsed as systemd reads it (sections, Key=Value) with the settings
// docs/run.md promises, and verified by `systemd-analyze verify` where that is installed (with
// ExecStart pointed at the stac-node just built, since verify checks that the command exists).
// deploy/60-stac-gs-usb.rules: the udev rule for the gs_usb adapter the driver opens;
// deploy/60-stac-cpu-latency.rules: the one for the PM QoS device of run.cpu_wake_latency_us.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/can/gs_usb.hpp"
#include "rt/scheduling.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"

namespace {

const std::string kUnit = std::string(::stac::testing::source_dir()) + "/deploy/stac.service";
const std::string kUdevRule =
    std::string(::stac::testing::source_dir()) + "/deploy/60-stac-gs-usb.rules";
const std::string kLatencyRule =
    std::string(::stac::testing::source_dir()) + "/deploy/60-stac-cpu-latency.rules";

std::string read(const std::string& path) {
  std::ifstream f(path);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// "Section.Key" -> value; fails the test on a line that is neither.
std::map<std::string, std::string> parse_unit(const std::string& text) {
  std::map<std::string, std::string> keys;
  std::string section;
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    std::smatch m;
    if (std::regex_match(line, m, std::regex(R"(\[(\w+)\])"))) {
      section = m[1];
    } else if (std::regex_match(line, m, std::regex(R"(([A-Za-z]+)=(.*))")) && !section.empty()) {
      keys[section + "." + m[1].str()] = m[2];
    } else {
      ADD_FAILURE() << "line " << n << " is neither a section nor Key=Value: " << line;
    }
  }
  return keys;
}

// `systemd-analyze verify` of `text` written to a unit file: its output (empty: no complaint).
std::string verify(const std::string& text) {
  const auto dir = stac::testing::fresh_dir("stac_unit_" + std::to_string(getpid()));
  const auto unit = dir / "stac.service";
  std::ofstream(unit) << text;
  FILE* p = popen(("systemd-analyze verify " + unit.string() + " 2>&1").c_str(), "r");
  std::string out;
  char buf[4096];
  while (std::size_t k = std::fread(buf, 1, sizeof(buf), p)) out.append(buf, k);
  pclose(p);
  std::filesystem::remove_all(dir);
  return out;
}

bool have_systemd_analyze() {
  return std::system("command -v systemd-analyze > /dev/null 2>&1") == 0;
}

TEST(SystemdUnit, RunsStacNodeWithTheVehicleConfigRestartsOnFailureAndAllowsRealTime) {
  const auto keys = parse_unit(read(kUnit));
  EXPECT_EQ(keys.at("Service.ExecStart"), "/usr/bin/stac-node --config /etc/stac/stac.yaml");
  EXPECT_EQ(keys.at("Service.Type"), "simple");
  EXPECT_EQ(keys.at("Service.Restart"), "on-failure");
  EXPECT_EQ(keys.at("Service.LimitMEMLOCK"), "infinity");  // run.lock_memory: mlockall
  // run.<thread>_priority up to 80 in the documented vehicle example; the rt DDS config uses 50.
  EXPECT_GE(std::stoi(keys.at("Service.LimitRTPRIO")), 80);
  EXPECT_LE(std::stoi(keys.at("Service.LimitRTPRIO")), 99);
  EXPECT_EQ(keys.at("Service.User"), "stac");
  EXPECT_EQ(keys.at("Install.WantedBy"), "multi-user.target");
  EXPECT_TRUE(keys.count("Unit.Description"));
  // The command line is one stac-node accepts.
  const auto help = stac::testing::run_shell(std::string(::stac::testing::stac_node()) + " --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.output.find("--config"), std::string::npos);
  const auto version =
      stac::testing::run_shell(std::string(::stac::testing::stac_node()) + " --version");
  EXPECT_EQ(version.code, 0);
  EXPECT_NE(version.output.find("stac-node "), std::string::npos) << version.output;
}

TEST(SystemdUnit, SystemdAnalyzeVerifiesItAndWouldNameAnError) {
  if (!have_systemd_analyze()) GTEST_SKIP() << "systemd-analyze not installed (the parse test ran)";
  std::string text = read(kUnit);
  text = std::regex_replace(text, std::regex("/usr/bin/stac-node"),
                            std::string(::stac::testing::stac_node()));
  EXPECT_EQ(verify(text), "");
  // The check can fail: a restart policy systemd does not know is named.
  const std::string broken =
      std::regex_replace(text, std::regex("Restart=on-failure"), "Restart=sometimes");
  EXPECT_NE(verify(broken).find("sometimes"), std::string::npos);
}

// Every rule line's KEY=="match" and KEY="assignment" pairs (comments and blank lines skipped);
// fails the test on a line with anything else.
std::vector<std::map<std::string, std::string>> parse_udev_rules(const std::string& text) {
  std::vector<std::map<std::string, std::string>> rules;
  std::istringstream in(text);
  const std::regex pair(R"re(\s*([A-Z]+(?:\{\w+\})?)\s*(==|\+=|=)\s*"([^"]*)"\s*(,|$))re");
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::map<std::string, std::string> rule;
    std::size_t at = 0;
    for (std::smatch m;
         at < line.size() &&
         std::regex_search(line.cbegin() + static_cast<std::ptrdiff_t>(at), line.cend(), m, pair,
                           std::regex_constants::match_continuous);
         at += static_cast<std::size_t>(m.length(0))) {
      rule[m[1].str() + m[2].str()] = m[3];
    }
    EXPECT_EQ(at, line.size()) << "not a udev rule from column " << at << ": " << line;
    rules.push_back(rule);
  }
  return rules;
}

TEST(UdevRule, GivesTheServiceGroupTheAdapterTheGsUsbDriverOpens) {
  const auto rules = parse_udev_rules(read(kUdevRule));
  ASSERT_EQ(rules.size(), 1u);
  const auto& r = rules[0];
  char vid[8], pid[8];
  std::snprintf(vid, sizeof vid, "%04x", stac::can::gs_usb::kVendorId);
  std::snprintf(pid, sizeof pid, "%04x", stac::can::gs_usb::kProductId);
  EXPECT_EQ(r.at("SUBSYSTEM=="), "usb");
  EXPECT_EQ(r.at("ATTR{idVendor}=="), vid);
  EXPECT_EQ(r.at("ATTR{idProduct}=="), pid);
  EXPECT_EQ(r.at("GROUP="), parse_unit(read(kUnit)).at("Service.Group"));  // the service's group
  EXPECT_EQ(r.at("MODE="), "0660");
  // The parser can fail: a rule with a broken assignment is named.
  EXPECT_NONFATAL_FAILURE(parse_udev_rules("SUBSYSTEM==\"usb\", GROUP stac\n"), "not a udev rule");
}

// deploy/60-stac-cpu-latency.rules: the PM QoS device that run.cpu_wake_latency_us opens.
TEST(UdevRule, GivesTheServiceGroupThePmQosDeviceTheRunHolds) {
  const auto rules = parse_udev_rules(read(kLatencyRule));
  ASSERT_EQ(rules.size(), 1u);
  const auto& r = rules[0];
  EXPECT_EQ("/dev/" + r.at("KERNEL=="), std::string(stac::rt::CpuLatencyRequest::kDevice));
  EXPECT_EQ(r.at("SUBSYSTEM=="), "misc");
  EXPECT_EQ(r.at("GROUP="), parse_unit(read(kUnit)).at("Service.Group"));
  EXPECT_EQ(r.at("MODE="), "0660");
}

}  // namespace

namespace {

// "<name> <version> (git <commit>)" of `<exe> --version`: the commit, or empty when the line
// is not of that form.
std::string commit_of(const std::string& exe, const std::string& name) {
  const auto r = stac::testing::run_shell(exe + " --version");
  EXPECT_EQ(r.code, 0) << r.output;
  std::smatch m;
  const std::regex line(name + " [0-9]+\\.[0-9]+\\.[0-9]+ \\(git ([^)]*)\\)\n");
  if (!std::regex_match(r.output, m, line)) {
    ADD_FAILURE() << exe << " --version printed: " << r.output;
    return "";
  }
  return m[1];
}

}  // namespace

TEST(Version, StacAndStacNodeNameTheVersionAndTheCommitTheyWereBuiltFrom) {
  const std::string of_stac = commit_of(::stac::testing::stac_cli(), "stac");
  const std::string of_node = commit_of(::stac::testing::stac_node(), "stac-node");
  EXPECT_EQ(of_stac, of_node);
  const std::string git = "git -C " + std::string(::stac::testing::source_dir());
  if (stac::testing::run_shell(git + " rev-parse --git-dir").code != 0) {
    EXPECT_EQ(of_stac.rfind("unknown", 0), 0u) << of_stac;
    GTEST_SKIP() << "not a git checkout: the commit is unknown, as printed";
  }
  // A commit of this repository (12 hex digits), "+changes" when tracked files differed.
  std::smatch m;
  ASSERT_TRUE(std::regex_match(of_stac, m, std::regex("([0-9a-f]{12})(\\+changes)?"))) << of_stac;
  EXPECT_EQ(stac::testing::run_shell(git + " cat-file -e " + m[1].str() + "^{commit}").code, 0)
      << m[1] << " is not a commit of " << ::stac::testing::source_dir();
}

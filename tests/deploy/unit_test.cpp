// deploy/stac.service: parsed as systemd reads it (sections, Key=Value) with the settings
// docs/run.md promises, and verified by `systemd-analyze verify` where that is installed (with
// ExecStart pointed at the stac just built, since verify checks that the command exists).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "stac_cli.hpp"

namespace {

const std::string kUnit = std::string(STAC_SOURCE_DIR) + "/deploy/stac.service";

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

TEST(SystemdUnit, RunsStacRunWithTheVehicleConfigRestartsOnFailureAndAllowsRealTime) {
  const auto keys = parse_unit(read(kUnit));
  EXPECT_EQ(keys.at("Service.ExecStart"), "/usr/local/bin/stac run --config /etc/stac/stac.yaml");
  EXPECT_EQ(keys.at("Service.Type"), "simple");
  EXPECT_EQ(keys.at("Service.Restart"), "on-failure");
  EXPECT_EQ(keys.at("Service.LimitMEMLOCK"), "infinity");  // run.lock_memory: mlockall
  // run.<thread>_priority up to 80 in the documented vehicle example; the rt DDS config uses 50.
  EXPECT_GE(std::stoi(keys.at("Service.LimitRTPRIO")), 80);
  EXPECT_LE(std::stoi(keys.at("Service.LimitRTPRIO")), 99);
  EXPECT_EQ(keys.at("Service.User"), "stac");
  EXPECT_EQ(keys.at("Install.WantedBy"), "multi-user.target");
  EXPECT_TRUE(keys.count("Unit.Description"));
  // The command line is one stac accepts.
  const auto help = stac::testing::stac("run --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.output.find("--config"), std::string::npos);
}

TEST(SystemdUnit, SystemdAnalyzeVerifiesItAndWouldNameAnError) {
  if (!have_systemd_analyze()) GTEST_SKIP() << "systemd-analyze not installed (the parse test ran)";
  std::string text = read(kUnit);
  text = std::regex_replace(text, std::regex("/usr/local/bin/stac"), std::string(STAC_CLI));
  EXPECT_EQ(verify(text), "");
  // The check can fail: a restart policy systemd does not know is named.
  const std::string broken = std::regex_replace(text, std::regex("Restart=on-failure"), "Restart=sometimes");
  EXPECT_NE(verify(broken).find("sometimes"), std::string::npos);
}

}  // namespace

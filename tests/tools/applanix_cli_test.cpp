// `stac decode applanix` run as a user would, on the real POS LV capture.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "shared_data.hpp"
#include "stac_cli.hpp"

namespace stac::tools {
namespace {

using stac::testing::CliResult;
using stac::testing::stac;

constexpr const char* kCapture = "applanix/clearpath_basic_data_smoke.pcap";

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(cell);
  return cells;
}

TEST(CliApplanix, DecodesTheRealCaptureIntoTheDocumentedCsv) {
  STAC_REQUIRE_SHARED_DATA(kCapture);
  const auto csv = std::filesystem::temp_directory_path() / "stac_cli_applanix.csv";
  const CliResult r = stac("decode applanix --in " + testing::shared_data(kCapture).string() +
                           " --out " + csv.string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(csv);
  std::string line, last;
  std::getline(in, line);
  EXPECT_EQ(line,
            "time1,time_types,lat,lon,alt,vn,ve,vd,roll,pitch,heading,wander,track,speed,"
            "rate_lon,rate_tra,rate_down,acc_lon,acc_tra,acc_down,alignment");
  std::size_t rows = 0;
  while (std::getline(in, line)) {
    ASSERT_EQ(split(line).size(), 21u) << line;
    last = line;
    ++rows;
  }
  EXPECT_EQ(rows, 82u);
  const auto v = split(last);
  ASSERT_EQ(v.size(), 21u);
  EXPECT_EQ(v[1], "1");  // time types 0x01: time1 GPS, time2 POS
  EXPECT_NEAR(std::stod(v[2]), 44.2449408681, 0.5e-10);
  EXPECT_NEAR(std::stod(v[3]), -76.5096210157, 0.5e-10);
  EXPECT_NEAR(std::stod(v[8]), 2.04550977266, 0.5e-11);
  EXPECT_NEAR(std::stod(v[9]), 1.3181307736, 0.5e-10);
  EXPECT_NEAR(std::stod(v[10]), 20.812475085, 0.5e-9);
  EXPECT_EQ(v[20], "4");
  // The summary names every group id with its count, and no rejects.
  for (const char* s :
       {"1:82", "2:80", "3:80", "4:80", "7:80", "8:80", "10:80", "12:73", "13:73", "21:80", "99:80",
        "20000:80", "2025 control messages", "GPS week 1694", "bad checksum 0"}) {
    EXPECT_NE(r.output.find(s), std::string::npos) << s << " missing from:\n" << r.output;
  }
  std::filesystem::remove(csv);
}

TEST(CliApplanix, WrongPortSaysNoSolutionWasFound) {
  STAC_REQUIRE_SHARED_DATA(kCapture);
  const auto csv = std::filesystem::temp_directory_path() / "stac_cli_applanix_port.csv";
  const CliResult r = stac("decode applanix --port 5602 --in " +
                           testing::shared_data(kCapture).string() + " --out " + csv.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("no Group 1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--port"), std::string::npos) << r.output;
  std::filesystem::remove(csv);
}

TEST(CliApplanix, SubcommandLeavesTheVelodyneDecodeUsageIntact) {
  const CliResult help = stac("decode --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.output.find("applanix"), std::string::npos) << help.output;
  const CliResult sub = stac("decode applanix --help");
  EXPECT_EQ(sub.code, 0);
  EXPECT_NE(sub.output.find("time_types"), std::string::npos) << sub.output;
  const CliResult no_in = stac("decode --out x.csv");
  EXPECT_NE(no_in.code, 0);
  EXPECT_NE(no_in.output.find("--in is required"), std::string::npos) << no_in.output;
  const CliResult no_out = stac("decode applanix --in /nonexistent.pcap");
  EXPECT_NE(no_out.code, 0);
}

}  // namespace
}  // namespace stac::tools

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <vector>

#include "drivers/can/candump.hpp"
#include "drivers/can/dbc.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"

namespace stac::can {
namespace {

using stac::testing::CliResult;
using stac::testing::stac;

std::vector<std::string> lines_of(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// Ten seconds of a 10 m/s, 36 deg/s left turn at 100 Hz, encoded with the shipped DBC, plus
// unrelated traffic and one CAN FD line.
std::filesystem::path write_circle_log(const std::filesystem::path& dir) {
  const auto db =
      load_dbc(std::filesystem::path(::stac::testing::source_dir()) / "config/can/vehicle.dbc");
  EXPECT_TRUE(db);
  const Message* wheel = db->find("WheelSpeeds");
  const Message* yaw = db->find("YawRate");
  const auto path = dir / "circle.log";
  auto w = CandumpWriter::open(path, "can0");
  EXPECT_TRUE(w);
  const std::int64_t t0 = 1'700'000'000'000'000'000;
  for (int i = 0; i <= 1000; ++i) {
    Frame s;
    s.stamp_ns = t0 + i * 10'000'000LL;
    s.id = wheel->id;
    s.dlc = 8;
    EXPECT_TRUE(wheel->find("VehicleSpeed")->encode(36.0, s.data));  // km/h
    EXPECT_TRUE(w->write(s));
    if (i == 1000) break;
    Frame r;
    r.stamp_ns = s.stamp_ns + 5'000'000;
    r.id = yaw->id;
    r.dlc = 8;
    EXPECT_TRUE(yaw->find("YawRate")->encode(36.0, r.data));
    EXPECT_TRUE(w->write(r));
    Frame other;
    other.stamp_ns = r.stamp_ns;
    other.id = 0x555;
    other.dlc = 1;
    EXPECT_TRUE(w->write(other));
  }
  EXPECT_TRUE(w->close());
  std::ofstream(path, std::ios::app) << "(1700000010.100000) can0 123##1AABB\n";
  return path;
}

TEST(CanCli, CandumpWritesSpeedYawRateAndTheDeadReckonedCircle) {
  const auto dir = std::filesystem::temp_directory_path() / "stac_can_cli";
  std::filesystem::create_directories(dir);
  const auto log = write_circle_log(dir);
  const auto csv = dir / "odometry.csv";
  const CliResult r = stac("candump --in " + log.string() + " --out " + csv.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("1 CAN FD skipped"), std::string::npos) << r.output;
  const auto lines = lines_of(csv);
  ASSERT_EQ(lines.size(),
            1u + 2000u);  // header + every speed and yaw frame after the first yaw frame
  EXPECT_EQ(lines[0], "time,speed_mps,yaw_rate_dps,x_m,y_m,yaw_deg,status");
  double t = 0, v = 0, w = 0, x = 0, y = 0, yaw = 0;
  char status[16] = {};
  ASSERT_EQ(std::sscanf(lines.back().c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%15s", &t, &v, &w, &x, &y,
                        &yaw, status),
            7)
      << lines.back();
  EXPECT_NEAR(t, 1'700'000'010.0, 1e-3);
  EXPECT_NEAR(v, 10.0, 1e-9);
  EXPECT_NEAR(w, 36.0, 1e-9);
  EXPECT_NEAR(x, 0.0, 0.1);  // a full circle brings the car back
  EXPECT_NEAR(y, 0.0, 0.1);
  EXPECT_STREQ(status, "ok");
  const double radius = 10.0 / (36.0 * std::numbers::pi / 180.0);
  ASSERT_EQ(std::sscanf(lines[1000].c_str(), "%lf,%lf,%lf,%lf,%lf", &t, &v, &w, &x, &y), 5);
  EXPECT_NEAR(y, 2 * radius, 0.1);  // half way: across the circle
}

// Issue 47: a log whose time runs back 100 s was decoded with status ok on every row.
TEST(CanCli, CandumpCountsFramesWhoseTimeRunsBackAndWritesNoRowForThem) {
  const auto dir = std::filesystem::temp_directory_path() / "stac_can_cli_back";
  std::filesystem::create_directories(dir);
  const auto log = write_circle_log(dir);
  const std::vector<std::string> lines = lines_of(log);
  {
    std::ofstream out(log, std::ios::app);
    for (std::size_t i = 100; i < 130; ++i) {  // 30 frames again, 100 s earlier
      const std::string& l = lines[i];
      const double t = std::stod(l.substr(1));
      char stamp[32];
      std::snprintf(stamp, sizeof stamp, "(%.6f)", t - 100.0);
      out << stamp << l.substr(l.find(')') + 1) << "\n";
    }
  }
  const auto csv = dir / "odometry.csv";
  const CliResult r = stac("candump --in " + log.string() + " --out " + csv.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("20 frames earlier than a frame before them"), std::string::npos)
      << r.output;                              // the 30 lines hold 10 speed and 10 yaw-rate frames
  EXPECT_EQ(lines_of(csv).size(), 1u + 2000u);  // no row for them
}

TEST(CanCli, CandumpErrorsNameTheFileAndLineOrTheSignal) {
  const auto dir = std::filesystem::temp_directory_path() / "stac_can_cli_bad";
  std::filesystem::create_directories(dir);
  const auto log = dir / "bad.log";
  std::ofstream(log) << "(1.000000) can0 1A0#0E10000000000000\n(1.000000) can0 1A0-0E10\n";
  const CliResult r = stac("candump --in " + log.string() + " --out " + (dir / "x.csv").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find(log.string() + ":2: expected <id>#<data>"), std::string::npos)
      << r.output;
  const auto dbc = dir / "other.dbc";
  std::ofstream(dbc) << "BO_ 1 Other: 8 X\n SG_ S : 0|8@1+ (1,0) [0|1] \"km/h\" X\n";
  const CliResult m = stac("candump --in " + log.string() + " --dbc " + dbc.string() + " --out " +
                           (dir / "x.csv").string());
  EXPECT_NE(m.code, 0);
  EXPECT_NE(m.output.find(dbc.string() + ": speed: no message 'WheelSpeeds'"), std::string::npos)
      << m.output;
  // A folder given as the DBC (issue 31: it said the DBC had no message).
  const CliResult folder = stac("candump --in " + log.string() + " --dbc " + dir.string() +
                                " --out " + (dir / "x.csv").string());
  EXPECT_NE(folder.code, 0);
  EXPECT_NE(folder.output.find("is a folder, not a DBC file"), std::string::npos) << folder.output;
  const auto empty = dir / "empty.log";
  std::ofstream(empty) << "";
  const CliResult e = stac("candump --in " + empty.string() + " --out " + (dir / "e.csv").string());
  EXPECT_EQ(e.code, 1);
  EXPECT_NE(e.output.find("empty.log: no CAN frame in the log"), std::string::npos) << e.output;
  const CliResult h = stac("candump --help");
  EXPECT_EQ(h.code, 0);
  EXPECT_NE(h.output.find("time (s, from the log),speed_mps,yaw_rate_dps"), std::string::npos)
      << h.output;
}

}  // namespace
}  // namespace stac::can

// `stac sim` end to end: the Applanix stream it writes into the pcap beside the HDL-64E packets,
// its candump log, and byte-identical output for the same scenario and seed. Every file is read
// back with the project's own readers (applanix::CaptureReader, `stac candump`, `stac decode`).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <variant>

#include "drivers/applanix/capture_reader.hpp"
#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/pcap_writer.hpp"
#include "ego/local_frame.hpp"
#include "ego/pose.hpp"
#include "shared_data.hpp"
#include "sim/ins.hpp"
#include "sim/run.hpp"
#include "stac_cli.hpp"

namespace stac::sim {
namespace {

using stac::testing::CliResult;
using stac::testing::stac;

constexpr const char* kCalib = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";
constexpr const char* kScenario = "urban";
constexpr std::uint64_t kSeed = 7;
constexpr double kSeconds = 2.5;

// One folder per test process: ctest runs each test in its own process, in parallel.
std::filesystem::path dir() {
  return std::filesystem::temp_directory_path() /
         ("stac_sim_sensors_" + std::to_string(::getpid()));
}
std::string calib() {
  return stac::testing::shared_data(kCalib).string();
}

std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

CliResult simulate(const std::string& name, const std::string& extra = "") {
  const auto d = dir();
  return stac(std::string("sim --scenario ") + kScenario + " --seed " + std::to_string(kSeed) +
              " --duration " + std::to_string(kSeconds) + " --calib " + calib() + " --out " +
              (d / (name + ".pcap")).string() + " --truth " + (d / (name + ".jsonl")).string() +
              " --can " + (d / (name + ".candump")).string() + " " + extra);
}

// The ego truth the sim drove (the same scenario, seed and duration).
std::unique_ptr<SimRun> truth_run() {
  auto cal = velodyne::load_calibration(calib());
  EXPECT_TRUE(cal);
  RunConfig rc;
  rc.scenario = kScenario;
  rc.seed = kSeed;
  rc.duration_s = kSeconds;
  rc.lidar.seed = kSeed;
  auto run = SimRun::create(*cal, rc);
  EXPECT_TRUE(run) << run.error().message;
  return std::move(*run);
}

class SimSensors : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!std::filesystem::exists(stac::testing::shared_data(kCalib))) return;
    std::filesystem::remove_all(dir());
    std::filesystem::create_directories(dir());
    const CliResult r = simulate("a");
    ok_ = r.code == 0;
    output_ = r.output;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir()); }
  void SetUp() override {
    STAC_REQUIRE_SHARED_DATA(kCalib);
    ASSERT_TRUE(ok_) << output_;
  }
  static inline bool ok_ = false;
  static inline std::string output_;
};

struct Group1Row {
  applanix::Group1 g;
  applanix::TimeDistance time;
  std::optional<std::int64_t> gps_ns;
};

// Every Group 1 of the pcap, decoded by the project's reader and placed by ego::LocalFrame, is
// the ego truth: position within 1 cm, attitude within 0.01 deg, speed; 200 Hz; Groups 2 and 3
// once per second; GPS week and time as the run's UTC start says.
TEST_F(SimSensors, PcapCarriesTheInsStreamOfTheEgoTruth) {
  auto reader = applanix::CaptureReader::open(dir() / "a.pcap");
  ASSERT_TRUE(reader) << reader.error().message;
  std::vector<Group1Row> rows;
  std::vector<std::uint16_t> others;
  applanix::Parsed p;
  std::uint32_t week = 0;
  double offset = 0;
  while (reader->next(p)) {
    if (const auto* g1 = std::get_if<applanix::Group1>(&p.content)) {
      rows.push_back({*g1, p.time, p.time1_gps_ns});
    } else if (std::holds_alternative<applanix::Group2>(p.content)) {
      others.push_back(2);
    } else if (const auto* g3 = std::get_if<applanix::Group3>(&p.content)) {
      others.push_back(3);
      week = g3->gps_week;
      offset = g3->gps_utc_offset_s;
    } else {
      others.push_back(0);
    }
  }
  EXPECT_TRUE(reader->error().empty()) << reader->error();
  EXPECT_EQ(reader->counters().datagrams, 0u) << "TCP by default";
  EXPECT_EQ(reader->tcp_counters().streams, 1u);
  EXPECT_EQ(reader->tcp_counters().gaps, 0u);
  EXPECT_EQ(reader->parser().counters().garbage_bytes, 0u);
  ASSERT_EQ(rows.size(), 501u);  // 0 .. 2.5 s every 5 ms
  EXPECT_EQ(others, (std::vector<std::uint16_t>{2, 3, 2, 3, 2, 3}));

  const RunConfig defaults;
  const std::int64_t start_gps = gps_ns_of_utc(defaults.start_ns);
  EXPECT_EQ(week, gps_time_of_gps_ns(start_gps).week);
  EXPECT_EQ(offset, 18.0);
  auto run = truth_run();
  ego::LocalFrame frame(InsConfig{}.origin);
  double moved = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Group1Row& r = rows[i];
    const std::int64_t gps = start_gps + static_cast<std::int64_t>(i) * 5'000'000;
    EXPECT_NEAR(r.time.time1_s, gps_time_of_gps_ns(gps).seconds_of_week, 1e-9);
    if (i > 0) {  // the first Group 1 comes before the first Group 3 gave the week
      ASSERT_TRUE(r.gps_ns.has_value());
      EXPECT_NEAR(static_cast<double>(*r.gps_ns - gps), 0.0, 1000.0);
    }
    const double t = static_cast<double>(i) * 0.005;
    const EgoState e = run->ego(t);
    ego::InsFix fix;
    fix.position = {r.g.latitude_deg, r.g.longitude_deg, r.g.altitude_m};
    fix.roll_deg = r.g.roll_deg;
    fix.pitch_deg = r.g.pitch_deg;
    fix.heading_deg = r.g.heading_deg;
    const ego::PoseSample pose = frame.pose(fix);
    EXPECT_LT((pose.position_m - Eigen::Vector3d(e.x, e.y, e.z)).norm(), 0.01) << "t " << t;
    const Eigen::Quaterniond truth = ego::from_roll_pitch_yaw(e.roll, e.pitch, e.yaw);
    EXPECT_LT(Eigen::AngleAxisd(truth.inverse() * pose.attitude).angle() * 180.0 / std::numbers::pi,
              0.01)
        << "t " << t;
    // Heading, roll and pitch one by one (the sim's pitch is nose-up negative).
    const double heading =
        std::remainder(90.0 - e.yaw * 180.0 / std::numbers::pi - r.g.heading_deg, 360.0);
    EXPECT_LT(std::abs(heading), 0.01) << "t " << t;
    EXPECT_NEAR(r.g.pitch_deg, -e.pitch * 180.0 / std::numbers::pi, 0.01);
    EXPECT_NEAR(r.g.roll_deg, e.roll * 180.0 / std::numbers::pi, 0.01);
    EXPECT_NEAR(r.g.speed_mps, e.speed, 0.01) << "t " << t;
    moved = std::max(moved, e.speed);
  }
  EXPECT_GT(moved, 1.0) << "the urban ego drives";
}

// One pcap, time-ordered: the TCP stream's frames sit between the HDL-64E datagrams.
TEST_F(SimSensors, PcapIsTimeOrderedWithTheInsInterleaved) {
  const std::string bytes = read_file(dir() / "a.pcap");
  ASSERT_GT(bytes.size(), 24u);
  std::uint32_t magic = 0;
  std::memcpy(&magic, bytes.data(), 4);
  ASSERT_EQ(magic, 0xA1B23C4Du) << "nanosecond pcap";
  std::size_t at = 24;
  std::int64_t last = 0;
  std::size_t udp = 0, tcp = 0, tcp_before_last_udp = 0, records = 0;
  while (at + 16 <= bytes.size()) {
    std::uint32_t h[4];
    std::memcpy(h, bytes.data() + at, 16);
    const std::int64_t stamp = static_cast<std::int64_t>(h[0]) * 1'000'000'000 + h[1];
    EXPECT_GE(stamp, last) << "record " << records;
    last = stamp;
    ASSERT_LE(at + 16 + h[2], bytes.size());
    const auto protocol = static_cast<std::uint8_t>(bytes[at + 16 + 14 + 9]);  // Ethernet, IPv4
    if (protocol == 17) {
      ++udp;
      tcp_before_last_udp = tcp;
    } else if (protocol == 6) {
      ++tcp;
    }
    at += 16 + h[2];
    ++records;
  }
  EXPECT_EQ(at, bytes.size());
  EXPECT_EQ(tcp, 3u + 501u + 6u);  // handshake, Group 1s, Groups 2 and 3
  EXPECT_GT(tcp_before_last_udp, 490u) << "interleaved, not appended";
  EXPECT_GT(udp, 8000u);
}

// The Velodyne decoding of the same pcap is unchanged: the TCP frames are skipped.
TEST_F(SimSensors, VelodyneDecodeIgnoresTheInsStream) {
  {
    auto in = io::PcapReader::open(dir() / "a.pcap",
                                   io::PcapFilter{.udp_dst_port = 2368, .udp_src_port = {}});
    ASSERT_TRUE(in);
    auto out = io::PcapWriter::open(dir() / "velodyne_only.pcap");
    ASSERT_TRUE(out);
    io::Datagram d;
    while (in->next(d)) ASSERT_TRUE(out->write_udp(d));
    EXPECT_EQ(in->counters().non_udp, 3u + 501u + 6u);
    ASSERT_TRUE(out->close());
  }
  const CliResult a = stac("decode --in " + (dir() / "a.pcap").string() + " --calib " + calib() +
                           " --out " + (dir() / "a.csv").string());
  const CliResult b = stac("decode --in " + (dir() / "velodyne_only.pcap").string() + " --calib " +
                           calib() + " --out " + (dir() / "b.csv").string());
  ASSERT_EQ(a.code, 0) << a.output;
  ASSERT_EQ(b.code, 0) << b.output;
  const std::string csv = read_file(dir() / "a.csv");
  EXPECT_GT(csv.size(), 1'000'000u);
  EXPECT_TRUE(csv == read_file(dir() / "b.csv")) << "the decoded points differ";
}

TEST_F(SimSensors, SameSeedGivesByteIdenticalPcapCandumpAndTruth) {
  const CliResult r = simulate("again");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* ext : {".pcap", ".candump", ".jsonl"}) {
    const std::string a = read_file(dir() / (std::string("a") + ext));
    EXPECT_GT(a.size(), 1000u) << ext;
    EXPECT_TRUE(a == read_file(dir() / (std::string("again") + ext))) << ext << " differs";
  }
}

// `stac candump` on the sim's log gives the ego speed and yaw rate within the DBC quantisation
// (0.01 km/h, 0.01 deg/s), and its dead-reckoned path follows the ego's.
TEST_F(SimSensors, CandumpGivesTheEgoSpeedYawRateAndPath) {
  const CliResult r = stac("candump --in " + (dir() / "a.candump").string() + " --out " +
                           (dir() / "can.csv").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("375 frames"), std::string::npos)
      << r.output;  // 125 speed + 250 yaw rate
  auto run = truth_run();
  const double start_s = static_cast<double>(RunConfig{}.start_ns / 1'000'000'000);
  std::ifstream csv(dir() / "can.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "time,speed_mps,yaw_rate_dps,x_m,y_m,yaw_deg,status");
  struct Row {
    double t, speed, yaw_rate, x, y, yaw_deg;
    std::string status;
  };
  std::vector<Row> rows;
  while (std::getline(csv, line)) {
    Row row{};
    char status[16] = {};
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%15s", &row.t, &row.speed,
                          &row.yaw_rate, &row.x, &row.y, &row.yaw_deg, status),
              7)
        << line;
    row.t -= start_s;
    row.status = status;
    rows.push_back(row);
  }
  ASSERT_GT(rows.size(), 300u);
  for (const Row& row : rows) {
    EXPECT_EQ(row.status, "ok");
    // Held values: the last speed frame is up to 20 ms old, the last yaw-rate frame 10 ms.
    auto near = [&](double value, double horizon, auto get, double tolerance) {
      for (double dt = 0; dt <= horizon; dt += 0.0001) {
        if (std::abs(value - get(run->ego(row.t - dt))) <= tolerance) return true;
      }
      return false;
    };
    EXPECT_TRUE(near(
        row.speed, 0.02, [](const EgoState& e) { return e.speed; }, 0.005 / 3.6 + 1e-4))
        << "t " << row.t << " speed " << row.speed;
    EXPECT_TRUE(near(
        row.yaw_rate, 0.01, [](const EgoState& e) { return e.yaw_rate * 180 / std::numbers::pi; },
        0.005 + 1e-4))
        << "t " << row.t << " yaw rate " << row.yaw_rate;
  }
  // Displacement from the first to the last row, in the vehicle frame of the first.
  const Row& a = rows.front();
  const Row& b = rows.back();
  const EgoState ea = run->ego(a.t), eb = run->ego(b.t);
  const double dx = eb.x - ea.x, dy = eb.y - ea.y;
  const double fwd = std::cos(ea.yaw) * dx + std::sin(ea.yaw) * dy;
  const double left = -std::sin(ea.yaw) * dx + std::cos(ea.yaw) * dy;
  const double yaw_a = a.yaw_deg * std::numbers::pi / 180;
  const double dr_fwd = std::cos(yaw_a) * (b.x - a.x) + std::sin(yaw_a) * (b.y - a.y);
  const double dr_left = -std::sin(yaw_a) * (b.x - a.x) + std::cos(yaw_a) * (b.y - a.y);
  EXPECT_GT(std::hypot(dx, dy), 2.0) << "the ego moved";
  EXPECT_NEAR(dr_fwd, fwd, 0.05);
  EXPECT_NEAR(dr_left, left, 0.05);
}

// --ins-udp sends each message as a datagram to port 5602 instead; --origin moves the anchor;
// a bad --origin or --can path is refused with a message naming it.
TEST_F(SimSensors, InsUdpOriginAndCanOptions) {
  const auto d = dir();
  const CliResult r =
      stac(std::string("sim --scenario ") + kScenario + " --seed 7 --duration 1 --calib " +
           calib() + " --out " + (d / "udp.pcap").string() + " --truth " +
           (d / "udp.jsonl").string() + " --ins-udp --origin 48.1375,11.575,519.5");
  ASSERT_EQ(r.code, 0) << r.output;
  auto reader = applanix::CaptureReader::open(d / "udp.pcap");
  ASSERT_TRUE(reader) << reader.error().message;
  applanix::Parsed p;
  std::size_t group1 = 0;
  ego::LocalFrame frame(ego::Geodetic{48.1375, 11.575, 519.5});
  RunConfig rc;
  rc.scenario = kScenario;
  rc.seed = kSeed;
  rc.duration_s = 1;
  auto cal = velodyne::load_calibration(calib());
  ASSERT_TRUE(cal);
  auto run = SimRun::create(*cal, rc);
  ASSERT_TRUE(run);
  while (reader->next(p)) {
    if (const auto* g = std::get_if<applanix::Group1>(&p.content)) {
      const EgoState e = (*run)->ego(static_cast<double>(group1) * 0.005);
      const Eigen::Vector3d at = frame.to_local({g->latitude_deg, g->longitude_deg, g->altitude_m});
      EXPECT_LT((at - Eigen::Vector3d(e.x, e.y, e.z)).norm(), 0.01);
      ++group1;
    }
  }
  EXPECT_EQ(group1, 201u);
  EXPECT_EQ(reader->counters().datagrams, 201u + 2u + 2u);
  EXPECT_EQ(reader->counters().segments, 0u);

  const CliResult bad = stac(std::string("sim --scenario empty --duration 0.2 --calib ") + calib() +
                             " --out " + (d / "bad.pcap").string() + " --truth " +
                             (d / "bad.jsonl").string() + " --origin 95,11,500");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("--origin '95,11,500'"), std::string::npos) << bad.output;
  // An unwritable candump path stops the run before it simulates anything.
  const CliResult no_log =
      stac(std::string("sim --scenario empty --duration 0.2 --calib ") + calib() + " --out " +
           (d / "nolog.pcap").string() + " --truth " + (d / "nolog.jsonl").string() + " --can " +
           (d / "missing" / "x.candump").string());
  EXPECT_NE(no_log.code, 0);
  EXPECT_NE(no_log.output.find("x.candump"), std::string::npos) << no_log.output;
  EXPECT_FALSE(std::filesystem::exists(d / "nolog.pcap"));
}

}  // namespace
}  // namespace stac::sim

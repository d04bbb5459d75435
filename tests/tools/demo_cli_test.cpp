// `stac demo` as a user runs it (the README's main job, shortened): a simulated urban drive
// replayed over loopback into `stac run`, the tracks read back from DDS, a summary and pictures.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "shared_data.hpp"
#include "stac_cli.hpp"

namespace stac::tools {
namespace {

constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

std::filesystem::path fresh_dir(const std::string& name) {
  return stac::testing::fresh_dir("stac_demo_" + name + "_" + std::to_string(getpid()));
}

std::uint64_t number(const std::string& out, const std::string& pattern) {
  std::smatch m;
  if (!std::regex_search(out, m, std::regex(pattern))) return ~0ull;
  return std::stoull(m[1].str());
}

struct ScanLine {
  std::uint64_t scan = 0;
  unsigned tracks = 0, confirmed = 0;
  std::string text;
};

std::vector<ScanLine> scan_lines(const std::string& out) {
  std::vector<ScanLine> lines;
  const std::regex line(R"(^scan +(\d+) +\+ *[0-9.]+ s +tracks +(\d+) \( *(\d+) confirmed\))");
  std::istringstream in(out);
  for (std::string l; std::getline(in, l);) {
    std::smatch m;
    if (std::regex_search(l, m, line))
      lines.push_back({std::stoull(m[1].str()), static_cast<unsigned>(std::stoul(m[2].str())),
                       static_cast<unsigned>(std::stoul(m[3].str())), l});
  }
  return lines;
}

TEST(DemoCli, ShortDriveGivesALinePerPublishedScanWithTracksASummaryThatAgreesAndPictures) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("drive");
  const auto r =
      stac::testing::stac("demo --seconds 3 --seed 5 --domain 146 --out " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string& out = r.output;

  // A line per scan, as the tracks arrived: scan indices 0..N-1, and confirmed tracks (shown
  // with id, class, position, speed) from the third scan on (tentative ones are not published).
  const std::vector<ScanLine> lines = scan_lines(out);
  const std::uint64_t published = number(out, R"((\d+) published,)");  // stac run's own summary
  ASSERT_EQ(lines.size(), published) << out;
  // 3 s at 10 Hz: ~28 complete scans, unless packets were lost, which must then be counted; a
  // scan perception had no room for (it falls behind under a sanitizer) is counted as a drop.
  const std::uint64_t slots_full = number(out, R"(scan slots full (\d+))");
  EXPECT_TRUE(published + slots_full >= 20u || number(out, R"((\d+) dropped by the kernel)") > 0)
      << out;
  const std::regex shown(
      R"(\| #\d+ (unknown|car|pedestrian|bicyclist|background) \(-?[0-9.]+, -?[0-9.]+\) [0-9.]+ m/s)");
  for (std::size_t i = 0; i < lines.size(); ++i) {
    EXPECT_EQ(lines[i].scan, i);
    EXPECT_LE(lines[i].confirmed, lines[i].tracks) << lines[i].text;
    if (i >= 2) {
      EXPECT_GT(lines[i].tracks, 0u) << lines[i].text;
      EXPECT_GT(lines[i].confirmed, 0u) << lines[i].text;
      EXPECT_TRUE(std::regex_search(lines[i].text, shown)) << lines[i].text;
    }
  }

  // The summary agrees with the lines and with stac run's summary.
  EXPECT_EQ(number(out, R"(scans +(\d+) received on tracked_objects)"), published) << out;
  EXPECT_EQ(number(out, R"(of (\d+) published by stac run)"), published) << out;
  EXPECT_EQ(number(out, R"(\((\d+) missing\))"), 0u) << out;
  EXPECT_EQ(number(out, R"(deadline +(\d+) misses)"), number(out, R"((\d+) misses of)")) << out;
  EXPECT_EQ(number(out, R"(\((\d+) scans, health\))"), published) << out;
  EXPECT_GT(number(out, R"(tracks +(\d+) ids)"), 0u) << out;
  EXPECT_TRUE(std::regex_search(
      out,
      std::regex(R"(end to end +last firing -> published: median [0-9.]+ ms, p99 [0-9.]+ ms)")))
      << out;
  EXPECT_TRUE(std::regex_search(
      out,
      std::regex(
          R"(DDS +publish -> receive \(tracked_objects\): median [0-9.]+ ms, p99 [0-9.]+ ms)")))
      << out;
  EXPECT_NE(out.find("drops "), std::string::npos) << out;
  // Published tracks classified before publication and one scan late, as stac run counted them.
  EXPECT_EQ(
      number(out, R"(classes +(\d+) published tracks classified before publication, \d+ one)"),
      number(out, R"((\d+) published tracks classified before publication, \d+ after)"))
      << out;
  EXPECT_EQ(number(out, R"((\d+) one scan late)"), number(out, R"((\d+) after it \(run)")) << out;
  // (under a sanitizer, perception falls behind the sensor and every class comes one scan late)
  EXPECT_GT(number(out, R"((\d+) published tracks classified before publication, \d+ one)") +
                (stac::testing::kSanitizerBuild ? number(out, R"((\d+) one scan late)") : 0u),
            0u)
      << out;

  // The files: the drive, the children's logs and two pictures of 1000 x 1000 pixels.
  for (const char* f : {"drive.pcap", "drive.truth.jsonl", "run.log", "replay.log"})
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / f)) << f;
  for (const char* f : {"demo_last_scan.png", "demo_tracks.png"}) {
    const cv::Mat png = cv::imread((dir / f).string());
    ASSERT_FALSE(png.empty()) << f;
    EXPECT_EQ(png.cols, 1000) << f;
    EXPECT_EQ(png.rows, 1000) << f;
    EXPECT_GT(cv::countNonZero(png.reshape(1) > 200), 1000) << f << ": boxes and paths drawn";
  }
  if (!HasFailure()) std::filesystem::remove_all(dir);
}

TEST(DemoCli, ABusyPortIsNamedBeforeAnythingRuns) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof(a);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
  ASSERT_EQ(getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len), 0);
  const std::string port = std::to_string(ntohs(a.sin_port));
  const auto dir = fresh_dir("busy");
  const auto r = stac::testing::stac("demo --seconds 1 --port " + port + " --out " + dir.string());
  close(fd);
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("UDP port " + port + " on 127.0.0.1 is not free"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("pass --port with another port"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "drive.pcap"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace stac::tools

// `stac replay` serving a simulated drive's Applanix TCP stream next to its Velodyne packets,
// read back by the project's own Applanix client and parser.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "drivers/applanix/capture_reader.hpp"
#include "drivers/applanix/stream_parser.hpp"
#include "drivers/applanix/tcp_client.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "shared_data.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"

namespace stac::tools {
namespace {

constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";
using stac::testing::CliResult;
using stac::testing::stac;

std::filesystem::path simulate(const std::string& name, double seconds) {
  const auto dir = std::filesystem::temp_directory_path() / ("stac_replay_cli_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto pcap = dir / "sim.pcap";
  const CliResult r = stac("sim --scenario urban --seed 3 --duration " + std::to_string(seconds) +
                           " --calib " + stac::testing::shared_data(kYaml).string() + " --out " +
                           pcap.string() + " --truth " + (dir / "sim.truth.jsonl").string());
  EXPECT_EQ(r.code, 0) << r.output;
  return pcap;
}

std::uint64_t group1_in_file(const std::filesystem::path& pcap) {
  auto reader = applanix::CaptureReader::open(pcap, std::uint16_t{5602});
  EXPECT_TRUE(reader) << reader.error().message;
  applanix::Parsed p;
  while (reader->next(p)) {
  }
  EXPECT_TRUE(reader->error().empty()) << reader->error();
  return reader->parser().groups_seen(1);
}

TEST(ReplayCli, ServesTheInsStreamCompleteNextToTheVelodynePackets) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto pcap = simulate("tcp", 0.5);
  const std::uint64_t expected_group1 = group1_in_file(pcap);
  ASSERT_GT(expected_group1, 90u);  // 200 Hz for 0.5 s

  io::UdpReceiverConfig uc;
  uc.bind_address = "127.0.0.1";
  uc.port = 0;
  uc.receive_buffer_bytes = 8 << 20;
  auto velodyne = io::UdpReceiver::open(uc);
  ASSERT_TRUE(velodyne);
  std::atomic<bool> done{false};
  std::uint64_t packets = 0;
  std::thread rx([&] {
    std::array<io::Datagram, 32> batch{};
    while (!done) packets += static_cast<std::uint64_t>(std::max(0, velodyne->receive(batch, 50)));
  });

  const std::string cmd = std::string(::stac::testing::stac_cli()) + " replay --in " +
                          pcap.string() + " --rate 4 --wait-tcp --tcp-port 5602:0 --port " +
                          std::to_string(velodyne->port()) + " 2>&1";
  FILE* out = popen(cmd.c_str(), "r");
  ASSERT_NE(out, nullptr);
  std::string output;
  char line[1024];
  int port = -1;
  const std::string key = "listening on 127.0.0.1:";
  while (port < 0 && std::fgets(line, sizeof(line), out) != nullptr) {
    output += line;
    const std::string l = line;
    if (const auto at = l.find(key); at != std::string::npos)
      port = std::stoi(l.substr(at + key.size()));
  }
  ASSERT_GT(port, 0) << output;

  applanix::TcpClientConfig cc;
  cc.address = "127.0.0.1";
  cc.port = static_cast<std::uint16_t>(port);
  auto client = applanix::TcpClient::open(cc);
  ASSERT_TRUE(client) << client.error().message;
  applanix::StreamParser parser(65536);
  std::array<std::uint8_t, 4096> buf{};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (client->counters().disconnects == 0 && std::chrono::steady_clock::now() < deadline) {
    const int n = client->receive(buf, 100);
    if (n <= 0) continue;
    parser.feed(std::span<const std::uint8_t>(buf.data(), static_cast<std::size_t>(n)));
    applanix::Parsed p;
    while (parser.next(p)) {
    }
  }
  client->stop();
  while (std::fgets(line, sizeof(line), out) != nullptr) output += line;
  const int status = pclose(out);
  done = true;
  rx.join();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << output;

  EXPECT_EQ(client->counters().connects, 1u);
  EXPECT_EQ(parser.groups_seen(1), expected_group1) << output;
  EXPECT_EQ(parser.counters().garbage_bytes, 0u);
  EXPECT_EQ(parser.counters().bad_checksum, 0u);
  EXPECT_NE(output.find("TCP stream of port 5602 served on 127.0.0.1:" + std::to_string(port)),
            std::string::npos)
      << output;
  EXPECT_NE(output.find(" 0 bytes unserved"), std::string::npos) << output;
  // The Velodyne packets went out on the same run, every one of them.
  EXPECT_NE(output.find(std::to_string(packets) + " packets,"), std::string::npos)
      << packets << "\n"
      << output;
  EXPECT_GT(packets, 1000u);
}

TEST(ReplayCli, AskingForATcpPortTheCaptureLacksIsAClearError) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto pcap = simulate("tcp_missing", 0.1);
  const CliResult r = stac("replay --in " + pcap.string() + " --tcp-port 5603:0");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("no TCP stream from port 5603"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("5602"), std::string::npos) << r.output;
  const CliResult bad = stac("replay --in " + pcap.string() + " --tcp-port 5602:x");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.output.find("--tcp-port 5602:x"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace stac::tools

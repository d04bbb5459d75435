#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <thread>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/pcap_writer.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "shared_data.hpp"
#include "stac_cli.hpp"
#include "velodyne/synthetic_stream.hpp"

namespace stac::tools {
namespace {

constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

using stac::testing::CliResult;
using stac::testing::stac;
using stac::testing::stac_within;

std::filesystem::path fresh_dir(const std::string& name) {
  return stac::testing::fresh_dir("stac_cli_" + name);
}

// Half a second of the synthetic rotating sensor (every return at 10 m) as a pcap.
std::filesystem::path write_capture(const std::filesystem::path& dir) {
  const auto path = dir / "capture.pcap";
  auto w = io::PcapWriter::open(path);
  EXPECT_TRUE(w);
  stac::testing::StreamSpec spec;
  spec.seconds = 0.5;
  for (const auto& p : stac::testing::make_stream(spec)) {
    io::Datagram d;
    d.payload = p.bytes;
    d.stamp_ns = p.stamp_ns + 285'660;  // received after the packet's last firing
    d.dst_port = 2368;
    EXPECT_TRUE(w->write_udp(d));
  }
  EXPECT_TRUE(w->close());
  return path;
}

TEST(Cli, HelpExplainsEveryCommand) {
  const CliResult r = stac("--help");
  EXPECT_EQ(r.code, 0);
  for (const char* word : {"decode", "record", "demo", "sim", "status", "candump", "replay",
                           "sim-compare", "Examples"}) {
    EXPECT_NE(r.output.find(word), std::string::npos) << word << " missing from:\n" << r.output;
  }
  const CliResult d = stac("decode --help");
  EXPECT_EQ(d.code, 0);
  EXPECT_NE(d.output.find("scan,laser,azimuth"), std::string::npos) << d.output;
  const CliResult none = stac("");
  EXPECT_NE(none.code, 0);  // a subcommand is required
}

// Issue 31: numbers a command cannot use are refused at once, naming the option; none hangs
// (each run is cut at 20 s by `timeout`, which the checks make moot).
TEST(Cli, NumbersOutOfRangeAreRefusedNamingTheOption) {
  const auto dir = fresh_dir("numbers");
  const std::string out = (dir / "x").string();
  // Inputs that exist, so that only the number is wrong.
  std::filesystem::copy_file(write_capture(dir), out + ".pcap");
  std::filesystem::create_directories(out);
  std::ofstream(out + ".bin") << "x";
  std::ofstream(out + ".jsonl") << "{}\n";
  const std::pair<std::string, std::string> cases[] = {
      {"run --seconds nan", "--seconds"},
      {"run --seconds inf", "--seconds"},
      {"run --seconds -1", "--seconds"},
      {"run --domain -1", "--domain"},
      {"record --out " + out + ".pcap --duration nan", "--duration"},
      {"record --out " + out + ".pcap --duration -1", "--duration"},
      {"record --out " + out + ".pcap --packets -1", "--packets"},
      {"decode --in " + out + ".pcap --out " + out + ".csv --cut-angle nan", "--cut-angle"},
      {"decode --in " + out + ".pcap --out " + out + ".csv --cut-angle -1", "--cut-angle"},
      {"replay --in " + out + ".pcap --rate 1e-300", "--rate"},
      {"kitti-objects --dir " + out + " --max-range nan", "--max-range"},
      {"echo health --timeout nan", "--timeout"},
      {"echo health --domain -1", "--domain"},
      {"segment --in " + out + ".bin --view-range nan", "--view-range"},
      {"sim --duration nan --out " + out + ".pcap --truth " + out + ".jsonl", "--duration"},
      {"induct --state " + out + " --classes car --eps nan", "--eps"},
      {"induct --state " + out + " --classes car --rounds -1", "--rounds"},
      {"eval --truth " + out + ".jsonl --tracks " + out + ".jsonl --max-range nan", "--max-range"},
      {"process " + out + ".pcap --dds --dds-wait inf", "--dds-wait"},
      {"process " + out + ".pcap --dds --dds-wait -1", "--dds-wait"},
      {"echo health --count -1", "--count"},
      {"run --scans 0", "--scans"},
  };
  for (const auto& [args, option] : cases) {
    const CliResult r = stac_within(20, args);
    EXPECT_NE(r.code, 0) << args << "\n" << r.output;
    EXPECT_NE(r.code, 137) << args << ": hung\n" << r.output;
    EXPECT_NE(r.output.find(option), std::string::npos) << args << "\n" << r.output;
    // The range is said as a person reads it (CLI11's own checks printed DBL_MAX's 309 digits).
    EXPECT_LT(r.output.size(), 400u) << args << "\n" << r.output;
  }
}

TEST(Cli, AnUnknownCommandIsNamedEvenWithHelp) {
  for (const char* args : {"nosuch --help", "nosuch"}) {
    const CliResult r = stac(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.output.find("unknown command 'nosuch'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("induct"), std::string::npos) << r.output;  // the list of commands
  }
}

TEST(Cli, DecodeWritesTheDocumentedCsv) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("csv");
  const auto pcap = write_capture(dir);
  const CliResult r = stac("decode --calib " + stac::testing::shared_data(kYaml).string() +
                           " --in " + pcap.string() + " --out " + (dir / "points.csv").string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "points.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "scan,laser,azimuth,distance,x,y,z,intensity,time");
  std::size_t rows = 0;
  long last_scan = 0;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 9u) << line;
    EXPECT_GE(static_cast<long>(v[0]), last_scan);
    last_scan = static_cast<long>(v[0]);
    EXPECT_GE(v[1], 0);
    EXPECT_LT(v[1], 64);
    EXPECT_GE(v[2], 0);
    EXPECT_LT(v[2], 36000);
    EXPECT_NEAR(v[3], 10.0, 2.0);  // raw 10 m plus the laser's distance correction
    EXPECT_NEAR(std::hypot(v[4], v[5], v[6]), v[3], 0.6);
    EXPECT_NEAR(v[8], 1.7e9, 1e3);  // seconds since the epoch
    ++rows;
  }
  // Every return of every packet is in range: 1736 packets x 384 returns.
  EXPECT_EQ(rows, static_cast<std::size_t>(0.5 * 3472.17) * 384);
  EXPECT_GE(last_scan, 4);
  EXPECT_NE(r.output.find("scans"), std::string::npos);
}

TEST(Cli, DecodeKittiWritesOneFloatFilePerScan) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("kitti");
  const auto pcap = write_capture(dir);
  const CliResult r =
      stac("decode --format kitti --calib " + stac::testing::shared_data(kYaml).string() +
           " --in " + pcap.string() + " --out " + (dir / "scans").string());
  ASSERT_EQ(r.code, 0) << r.output;
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "scans")) {
    EXPECT_EQ(e.path().extension(), ".bin");
    EXPECT_EQ(e.file_size() % 16, 0u);
    EXPECT_GT(e.file_size(), 0u);
    ++files;
  }
  EXPECT_GE(files, 5);
  ASSERT_TRUE(std::filesystem::exists(dir / "scans" / "000001.bin"));
  std::ifstream f(dir / "scans" / "000001.bin", std::ios::binary);
  float p[4];
  f.read(reinterpret_cast<char*>(p), sizeof(p));
  EXPECT_NEAR(std::hypot(p[0], p[1], p[2]), 10.0, 2.5);
  EXPECT_GE(p[3], 0.0f);
  EXPECT_LE(p[3], 1.0f);
}

TEST(Cli, DecodeNamesTheFileAndLaserOfABrokenCalibration) {
  const auto dir = fresh_dir("badcalib");
  const auto pcap = write_capture(dir);
  std::ofstream(dir / "broken.yaml") << "lasers:\n- laser_id: 0\n  rot_correction: 0.1\n";
  const CliResult r = stac("decode --calib " + (dir / "broken.yaml").string() + " --in " +
                           pcap.string() + " --out " + (dir / "x.csv").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("broken.yaml: laser 0: missing 'vert_correction'"), std::string::npos)
      << r.output;
}

TEST(Cli, DecodeRejectsAFileThatIsNotACapture) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("notpcap");
  std::ofstream(dir / "notes.pcap") << "hello, this is not a capture at all, really not";
  const CliResult r =
      stac("decode --calib " + stac::testing::shared_data(kYaml).string() + " --in " +
           (dir / "notes.pcap").string() + " --out " + (dir / "x.csv").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("notes.pcap: cannot read as a pcap capture"), std::string::npos)
      << r.output;
}

TEST(Cli, DecodeSaysWhenNoPacketIsOnThePort) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("port");
  const auto pcap = write_capture(dir);
  const CliResult r =
      stac("decode --port 2369 --calib " + stac::testing::shared_data(kYaml).string() + " --in " +
           pcap.string() + " --out " + (dir / "x.csv").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("no UDP packet to port 2369"), std::string::npos) << r.output;
}

// The capture with every record cut to `keep` captured bytes (a small snap length): caplen
// shrinks, the length on the wire stays.
std::filesystem::path snapped_copy(const std::filesystem::path& pcap, std::uint32_t keep) {
  std::ifstream in(pcap, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string out = bytes.substr(0, 24);
  for (std::size_t at = 24; at + 16 <= bytes.size();) {
    std::uint32_t caplen = 0;
    std::memcpy(&caplen, bytes.data() + at + 8, 4);
    const std::uint32_t kept = std::min(caplen, keep);
    std::string header = bytes.substr(at, 16);
    std::memcpy(header.data() + 8, &kept, 4);
    out += header + bytes.substr(at + 16, kept);
    at += 16 + caplen;
  }
  const auto path = pcap.parent_path() / ("snapped_" + std::to_string(keep) + ".pcap");
  std::ofstream(path, std::ios::binary) << out;
  return path;
}

// A capture that gives nothing says why, in decode, process and segment alike: packets of the
// wrong size, or frames truncated by the capture's snap length; drops are in the summary.
TEST(Cli, ACaptureThatGivesNoScanSaysWhy) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("nothing");
  const auto pcap = write_capture(dir);
  const std::string calib = " --calib " + stac::testing::shared_data(kYaml).string();
  {  // 600 of the 1206 payload bytes: wrong size
    const auto wrong = dir / "wrong.pcap";
    auto w = io::PcapWriter::open(wrong);
    ASSERT_TRUE(w);
    auto reader = io::PcapReader::open(pcap);
    ASSERT_TRUE(reader);
    io::Datagram d;
    std::uint64_t n = 0;
    while (reader->next(d)) {
      d.payload = d.payload.first(600);
      ASSERT_TRUE(w->write_udp(d));
      ++n;
    }
    ASSERT_TRUE(w->close());
    const CliResult r =
        stac("decode" + calib + " --in " + wrong.string() + " --out " + (dir / "x.csv").string());
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.output.find("none of its " + std::to_string(n) +
                            " packets to port 2368 is an HDL-64E data packet: wrong size " +
                            std::to_string(n)),
              std::string::npos)
        << r.output;
    const CliResult p =
        stac("process " + wrong.string() + calib + " --tracks " + (dir / "t.jsonl").string());
    EXPECT_EQ(p.code, 1);
    EXPECT_NE(p.output.find("dropped     wrong size " + std::to_string(n) + ","), std::string::npos)
        << p.output;
    EXPECT_NE(p.output.find("is an HDL-64E data packet"), std::string::npos) << p.output;
  }
  {  // a snap length of 600 bytes
    const auto snapped = snapped_copy(pcap, 600);
    for (const std::string& cmd :
         {"decode" + calib + " --in " + snapped.string() + " --out " + (dir / "y.csv").string(),
          "segment" + calib + " --in " + snapped.string(),
          "process " + snapped.string() + calib + " --tracks " + (dir / "u.jsonl").string()}) {
      const CliResult r = stac(cmd);
      EXPECT_EQ(r.code, 1) << cmd;
      EXPECT_NE(r.output.find("no UDP packet to port 2368 in the capture: "), std::string::npos)
          << r.output;
      EXPECT_NE(
          r.output.find(
              "frames are truncated (captured shorter than their headers say); capture again with "
              "the full snap length"),
          std::string::npos)
          << r.output;
    }
  }
}

TEST(Cli, RecordWritesWhatArrivesOnTheSocket) {
  const auto dir = fresh_dir("record");
  std::uint16_t port = 0;
  {
    io::UdpReceiverConfig any_port;
    any_port.bind_address = "127.0.0.1";
    any_port.port = 0;
    auto probe = io::UdpReceiver::open(any_port);
    ASSERT_TRUE(probe);
    port = probe->port();
  }
  const auto out = dir / "live.pcap";
  CliResult result{};
  std::thread recorder([&] {
    result = stac("record --bind 127.0.0.1 --port " + std::to_string(port) +
                  " --packets 200 --duration 20 --out " + out.string());
  });
  auto sender = io::UdpSender::open("127.0.0.1", port);
  ASSERT_TRUE(sender);
  std::array<std::uint8_t, 1206> packet{};
  // Keep sending until the recorder has what it asked for and exits.
  for (int i = 0; i < 4000 && !std::filesystem::exists(out); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  for (int i = 0; i < 200; ++i) {
    packet[0] = static_cast<std::uint8_t>(i);
    ASSERT_TRUE(sender->send(packet));
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  recorder.join();
  ASSERT_EQ(result.code, 0) << result.output;
  auto r = io::PcapReader::open(out);
  ASSERT_TRUE(r) << r.error().message;
  io::Datagram d;
  int n = 0;
  while (r->next(d)) {
    EXPECT_EQ(d.payload.size(), 1206u);
    EXPECT_EQ(d.payload[0], static_cast<std::uint8_t>(n));
    EXPECT_EQ(d.src_ip, 0x7F000001u);
    ++n;
  }
  EXPECT_EQ(n, 200);
}

// The "points N" figure of a decode summary.
long long decoded_points(const std::string& output) {
  const auto at = output.find("points ");
  return at == std::string::npos ? -1 : std::atoll(output.c_str() + at + 7);
}

TEST(Cli, StatusShowsTheSimulatedUnitAndStreamCalibrationDecodesLikeTheFile) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("status");
  const std::string yaml = stac::testing::shared_data(kYaml).string();
  const auto pcap = (dir / "run.pcap").string();
  CliResult sim = stac("sim --scenario parking-lot --seed 5 --duration 2.8 --calib " + yaml +
                       " --out " + pcap + " --truth " + (dir / "run.jsonl").string());
  ASSERT_EQ(sim.code, 0) << sim.output;

  const auto unit_yaml = (dir / "unit.yaml").string();
  CliResult st = stac("status --in " + pcap + " --calib-out " + unit_yaml);
  ASSERT_EQ(st.code, 0) << st.output;
  for (const char* word : {"1 dumps accepted", "0 out of sequence", "GPS PPS+NMEA", "600 rpm",
                           "return mode strongest", "192.168.3.43", "2026-01-01 12:00:02 UTC"}) {
    EXPECT_NE(st.output.find(word), std::string::npos) << word << " missing from:\n" << st.output;
  }
  auto sent = velodyne::load_calibration(unit_yaml);
  auto file = velodyne::load_calibration(yaml);
  ASSERT_TRUE(sent) << sent.error().message;
  ASSERT_TRUE(file);
  for (int i = 0; i < 64; ++i) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_NEAR(sent->lasers[k].vert_correction_rad, file->lasers[k].vert_correction_rad, 1e-4);
    EXPECT_NEAR(sent->lasers[k].dist_correction_m, file->lasers[k].dist_correction_m, 5e-4 + 1e-9);
  }

  CliResult by_file =
      stac("decode --in " + pcap + " --calib " + yaml + " --out " + (dir / "a.csv").string());
  CliResult by_stream =
      stac("decode --in " + pcap + " --calib stream --out " + (dir / "b.csv").string());
  ASSERT_EQ(by_file.code, 0) << by_file.output;
  ASSERT_EQ(by_stream.code, 0) << by_stream.output;
  EXPECT_GT(decoded_points(by_file.output), 100'000);
  EXPECT_EQ(decoded_points(by_stream.output), decoded_points(by_file.output));
}

TEST(Cli, StreamCalibrationSaysWhatToDoWhenTheCaptureCarriesNone) {
  const auto dir = fresh_dir("no_stream");
  const auto pcap = write_capture(dir);  // trailers without a status cycle
  CliResult r =
      stac("decode --in " + pcap.string() + " --calib stream --out " + (dir / "x.csv").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("no complete calibration"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("pass --calib"), std::string::npos) << r.output;
  CliResult s2 = stac("status --in " + pcap.string() + " --model S2");
  EXPECT_NE(s2.code, 0);
  EXPECT_NE(s2.output.find("sends no status cycle"), std::string::npos) << s2.output;
}

// A short simulated urban drive, written by `stac sim`.
std::filesystem::path simulate(const std::filesystem::path& dir, double seconds) {
  const auto pcap = dir / "sim.pcap";
  const CliResult r = stac("sim --scenario urban --seed 1 --duration " + std::to_string(seconds) +
                           " --calib " + stac::testing::shared_data(kYaml).string() + " --out " +
                           pcap.string() + " --truth " + (dir / "sim.truth.jsonl").string());
  EXPECT_EQ(r.code, 0) << r.output;
  return pcap;
}

std::vector<std::vector<std::uint8_t>> payloads_of(const std::filesystem::path& pcap,
                                                   std::int64_t& span_ns) {
  std::vector<std::vector<std::uint8_t>> out;
  auto r = io::PcapReader::open(pcap);
  EXPECT_TRUE(r);
  io::Datagram d;
  std::int64_t first = 0;
  while (r->next(d)) {
    if (out.empty()) first = d.stamp_ns;
    span_ns = d.stamp_ns - first;
    out.emplace_back(d.payload.begin(), d.payload.end());
  }
  return out;
}

// Runs `stac replay <args> --port P` into a loopback socket and returns what arrived.
std::vector<std::vector<std::uint8_t>> replay_into_socket(const std::string& args,
                                                          std::size_t expected, CliResult& result) {
  io::UdpReceiverConfig c;
  c.bind_address = "127.0.0.1";
  c.port = 0;
  c.receive_buffer_bytes = 8 << 20;
  auto receiver = io::UdpReceiver::open(c);
  EXPECT_TRUE(receiver);
  std::vector<std::vector<std::uint8_t>> got;
  std::thread rx([&] {
    std::array<io::Datagram, 32> batch{};
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (got.size() < expected && std::chrono::steady_clock::now() < deadline) {
      const int n = receiver->receive(batch, 50);
      for (int i = 0; i < n; ++i) {
        const auto& p = batch[static_cast<std::size_t>(i)].payload;
        got.emplace_back(p.begin(), p.end());
      }
    }
  });
  result = stac("replay " + args + " --port " + std::to_string(receiver->port()));
  rx.join();
  return got;
}

double number_after(const std::string& text, const std::string& key, std::size_t from = 0) {
  const std::size_t at = text.find(key, from);
  if (at == std::string::npos) return -1e300;
  return std::stod(text.substr(at + key.size()));
}

TEST(ReplayCli, SimulatedDriveArrivesByteIdenticalAtTheScaledSchedule) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("replay");
  const auto pcap = simulate(dir, 0.3);
  std::int64_t span_ns = 0;
  const auto sent = payloads_of(pcap, span_ns);
  ASSERT_GT(sent.size(), 1000u);
  CliResult r;
  const auto got = replay_into_socket("--in " + pcap.string() + " --rate 2", sent.size(), r);
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_EQ(got.size(), sent.size()) << r.output;
  for (std::size_t i = 0; i < sent.size(); ++i) ASSERT_EQ(got[i], sent[i]) << "packet " << i;
  // The last packet is scheduled at half the recorded span (printed to 1 us).
  EXPECT_NEAR(number_after(r.output, "schedule   "), 0.5e-9 * static_cast<double>(span_ns), 1.5e-6)
      << r.output;
  EXPECT_NE(r.output.find("pacing error"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(std::to_string(sent.size()) + " packets"), std::string::npos) << r.output;
}

TEST(ReplayCli, LoopSendsTheCaptureAgain) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("replay_loop");
  const auto pcap = simulate(dir, 0.2);
  std::int64_t span_ns = 0;
  const auto sent = payloads_of(pcap, span_ns);
  CliResult r;
  const auto got =
      replay_into_socket("--in " + pcap.string() + " --rate 4 --loop 2", 2 * sent.size(), r);
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_EQ(got.size(), 2 * sent.size()) << r.output;
  for (std::size_t i = 0; i < got.size(); ++i)
    ASSERT_EQ(got[i], sent[i % sent.size()]) << "packet " << i;
  EXPECT_NE(r.output.find("2 full passes"), std::string::npos) << r.output;
}

TEST(ReplayCli, MissingFileAndNoMatchingPacketsAreClearErrors) {
  const CliResult missing = stac("replay --in /nonexistent/run.pcap");
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.output.find("/nonexistent/run.pcap"), std::string::npos) << missing.output;
  const auto dir = fresh_dir("replay_empty");
  const auto pcap = write_capture(dir);
  const CliResult none = stac("replay --in " + pcap.string() + " --filter-port 9999");
  EXPECT_EQ(none.code, 1);
  EXPECT_NE(none.output.find("no UDP datagram to replay to port 9999"), std::string::npos)
      << none.output;
  // Cut by a small snap length: every frame counted as truncated, none sent.
  const CliResult snapped =
      stac("replay --in " + snapped_copy(pcap, 600).string() + " --no-tcp --fast");
  EXPECT_EQ(snapped.code, 1);
  EXPECT_NE(snapped.output.find("truncated: captured shorter than their headers say"),
            std::string::npos)
      << snapped.output;
  const CliResult both = stac("replay --in " + pcap.string() + " --fast --rate 2");
  EXPECT_NE(both.code, 0);  // --fast and --rate exclude each other
  // A CAN fault without CAN frames to act on; a CAN log that is not one.
  const CliResult silence = stac("replay --in " + pcap.string() + " --faults can-silence=1+1");
  EXPECT_EQ(silence.code, 1);
  EXPECT_NE(silence.output.find("can-silence acts on the CAN frames of --can LOG"),
            std::string::npos)
      << silence.output;
  const auto not_a_log = dir / "not_a_log.txt";
  std::ofstream(not_a_log) << "hello\n";
  const CliResult garbage = stac("replay --in " + pcap.string() + " --can " + not_a_log.string());
  EXPECT_EQ(garbage.code, 1);
  EXPECT_NE(garbage.output.find(not_a_log.string() + ":1"), std::string::npos) << garbage.output;
}

TEST(SimCompareCli, WritesTheReportWithPlausibleFigures) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  STAC_REQUIRE_SHARED_DATA("kitti/000000.bin");
  const auto dir = fresh_dir("sim_compare");
  const auto pcap = simulate(dir, 0.35);
  const auto report = dir / "report";
  const CliResult r =
      stac("sim-compare --sim " + pcap.string() + " --kitti " +
           stac::testing::shared_data("kitti/000000.bin").string() + " --calib " +
           stac::testing::shared_data(kYaml).string() + " --report " + report.string());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f :
       {"realism.md", "realism.json", "points_per_ring.png", "ring_elevation.png",
        "range_histogram.png", "intensity_histogram.png", "birds_eye_side_by_side.png"}) {
    EXPECT_TRUE(std::filesystem::exists(report / f)) << f;
  }
  std::ifstream in(report / "realism.json");
  const std::string json((std::istreambuf_iterator<char>(in)), {});
  for (const char* key :
       {"\"sim\":", "\"kitti\":", "\"points_per_scan\":", "\"ring_count\":", "\"points_per_ring\":",
        "\"ring_elevation_deg\":", "\"range_m\":", "\"histogram\":", "\"ground_fraction\":",
        "\"intensity\":", "\"rules\":"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing from " << json;
  }
  const std::size_t kitti = json.find("\"kitti\":");
  const std::size_t sim = json.find("\"sim\":");
  ASSERT_NE(kitti, std::string::npos);
  ASSERT_NE(sim, std::string::npos);
  // KITTI 000000: 124668 points in 64 rings, about 58 % of them on the ground.
  EXPECT_EQ(number_after(json, "\"scans\":", kitti), 1.0);
  EXPECT_EQ(number_after(json, "\"mean\":", kitti), 124668.0);
  EXPECT_EQ(number_after(json, "\"ring_count\":", kitti), 64.0);
  EXPECT_NEAR(number_after(json, "\"ground_fraction\":", kitti), 0.595, 0.01);
  // The simulated scans: complete ones, all 64 rings, a plausible point count and ground share.
  EXPECT_GE(number_after(json, "\"scans\":", sim), 2.0);
  EXPECT_EQ(number_after(json, "\"ring_count\":", sim), 64.0);
  const double sim_points = number_after(json, "\"mean\":", sim);
  EXPECT_GT(sim_points, 90'000.0);
  EXPECT_LT(sim_points, 133'400.0);  // at most 64 lasers x 2084 firings
  const double sim_ground = number_after(json, "\"ground_fraction\":", sim);
  EXPECT_GT(sim_ground, 0.3);
  EXPECT_LT(sim_ground, 0.85);
}

// Issue 31: a capture that breaks off (a bad record length 300 records in) lost most of its data
// while decode, status and decode applanix exited 0 with a warning: every command must say it.
TEST(Cli, ACaptureThatBreaksOffIsAnErrorInEveryCommand) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("breaks_off");
  const auto pcap = simulate(dir, 1.0);
  std::string bytes;
  {
    std::ifstream in(pcap, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::size_t at = 24;  // after the file header; each record: 16 bytes of header, then the data
  for (int i = 0; i < 300; ++i) {
    std::uint32_t incl = 0;
    std::memcpy(&incl, bytes.data() + at + 8, 4);
    at += 16 + incl;
  }
  const std::uint32_t bad = 0x7fffffff;
  std::memcpy(bytes.data() + at + 8, &bad, 4);
  const auto broken = dir / "broken.pcap";
  std::ofstream(broken, std::ios::binary) << bytes;
  const std::string b = broken.string(), calib = stac::testing::shared_data(kYaml).string();
  for (const std::string& args :
       {"decode --calib " + calib + " --in " + b + " --out " + (dir / "d.csv").string(),
        "status --in " + b, "decode applanix --in " + b + " --out " + (dir / "a.csv").string(),
        "process " + b + " --calib " + calib + " --tracks " + (dir / "t.jsonl").string(),
        "dataset --in " + b + " --calib " + calib + " --out " + (dir / "data").string()}) {
    const CliResult r = stac(args);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("stopped after 300 records"), std::string::npos) << args << "\n"
                                                                             << r.output;
  }
}

// Issue 31: a NaN or 1e30 point in a KITTI scan crashed sim-compare (a float cast to a
// histogram index); such points are left out and counted.
TEST(SimCompareCli, NonFinitePointsInAKittiScanAreLeftOutAndCounted) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  STAC_REQUIRE_SHARED_DATA("kitti/000000.bin");
  const auto dir = fresh_dir("sim_compare_nan");
  const auto pcap = simulate(dir, 0.35);
  std::string scan;
  {
    std::ifstream in(stac::testing::shared_data("kitti/000000.bin"), std::ios::binary);
    scan.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const float nan = std::nanf(""), huge = 1e30f, inf = std::numeric_limits<float>::infinity();
  std::memcpy(scan.data() + 16 * 10, &nan, 4);             // x of point 10
  std::memcpy(scan.data() + 16 * 20 + 8, &huge, 4);        // z of point 20
  std::memcpy(scan.data() + 16 * 30 + 12, &inf, 4);        // reflectance of point 30
  for (int k = 0; k < 3; ++k) {                            // x, y and z of point 40 (issue 47: the
    std::memcpy(scan.data() + 16 * 40 + 4 * k, &nan, 4);   // bird's-eye picture crashed on it)
    std::memcpy(scan.data() + 16 * 50 + 4 * k, &huge, 4);  // and of point 50
  }
  const auto bin = dir / "damaged.bin";
  std::ofstream(bin, std::ios::binary) << scan;
  const CliResult r =
      stac("sim-compare --sim " + pcap.string() + " --kitti " + bin.string() + " --calib " +
           stac::testing::shared_data(kYaml).string() + " --report " + (dir / "report").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("and 5 KITTI points that are NaN"), std::string::npos) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "report" / "realism.md"));
}

}  // namespace
}  // namespace stac::tools

// stac demo: the main job on a built-in default. A synthetic HDL-64E capture is written to pcap,
// sent at the sensor's pace over loopback UDP into the live receiver (receiver thread -> slot
// exchange -> consumer, as on the vehicle), and decoded offline from the pcap; both must agree.
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "drivers/io/pcap_writer.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "rt/clock.hpp"
#include "tools/commands.hpp"
#include "tools/decode.hpp"
#include "tools/demo_capture.hpp"
#include "tools/settings.hpp"

namespace stac::tools {
namespace {

struct DemoOptions {
  std::string out = "stac-demo";
  std::string config;
  double seconds = 2.0;
};

constexpr std::int64_t kDemoStartNs = 1'767'268'800'000'000'000;  // 2026-01-01 12:00:00 UTC

struct LiveResult {
  std::uint64_t scans = 0, complete = 0, points = 0, packets = 0;
  io::UdpReceiverCounters counters{};
};

// Sends the capture over loopback at its own pace and decodes it as `stac run` will.
rt::Result<LiveResult> run_live(const velodyne::Calibration& calibration,
                                const VelodyneSettings& settings,
                                const std::vector<DemoPacket>& packets) {
  io::UdpReceiverConfig rc;
  rc.bind_address = "127.0.0.1";
  rc.port = 0;  // any free port
  rc.receive_buffer_bytes = settings.receive_buffer_bytes;
  auto receiver = io::UdpReceiver::open(rc);
  if (!receiver) return rt::Unexpected<rt::Error>{receiver.error()};
  auto sender = io::UdpSender::open("127.0.0.1", receiver->port());
  if (!sender) return rt::Unexpected<rt::Error>{sender.error()};

  velodyne::ScanStream stream(calibration, settings.assembler,
                              static_cast<std::size_t>(settings.scan_slots));
  std::atomic<bool> sending_done{false};
  std::atomic<bool> receiving_done{false};
  std::atomic<std::uint64_t> received{0};
  std::thread receive_thread([&] {  // the receiver thread of the architecture
    std::array<io::Datagram, 32> batch{};
    std::int64_t quiet_since = 0;
    while (true) {
      const int n = receiver->receive(batch, 20);
      for (int i = 0; i < n; ++i) {
        const io::Datagram& d = batch[static_cast<std::size_t>(i)];
        (void)stream.add_packet(d.payload, d.stamp_ns);
      }
      received += static_cast<std::uint64_t>(n > 0 ? n : 0);
      if (n > 0) {
        quiet_since = 0;
      } else if (sending_done) {
        if (quiet_since == 0) quiet_since = rt::monotonic_ns();
        if (rt::monotonic_ns() - quiet_since > 200'000'000) break;
      }
    }
    (void)stream.finish();
    receiving_done = true;
  });

  LiveResult result;
  std::thread send_thread([&] {  // paced like the sensor: packet k at its capture time
    const std::int64_t t0 = rt::monotonic_ns();
    for (const DemoPacket& p : packets) {
      const std::int64_t due = t0 + (p.receive_stamp_ns - packets.front().receive_stamp_ns);
      while (rt::monotonic_ns() < due) std::this_thread::sleep_for(std::chrono::microseconds(50));
      (void)sender->send(p.bytes);
    }
    sending_done = true;
  });
  auto consume = [&] {
    while (const velodyne::Scan* s = stream.take()) {
      ++result.scans;
      result.complete += s->header.complete() ? 1 : 0;
      result.points += s->points.size();
      stream.release();
    }
  };
  while (!receiving_done) {  // the perception thread's place
    consume();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  send_thread.join();
  receive_thread.join();
  consume();
  result.packets = received;
  result.counters = receiver->counters();
  return result;
}

int run_demo(const DemoOptions& o) {
  const std::filesystem::path config = config_path(o.config);
  auto settings = load_velodyne_settings(config);
  if (!settings) return fail(settings.error().message);
  if (settings->calibration.empty()) {
    return fail(config.string() + ": the demo needs a calibration file, not 'stream'");
  }
  auto calibration = velodyne::load_calibration(settings->calibration);
  if (!calibration) return fail(calibration.error().message);
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) return fail(o.out + ": cannot create the output folder: " + ec.message());
  const std::filesystem::path dir(o.out);

  // 1. The capture: a synthetic S2.1 at 600 rpm, written as the sensor's packets.
  std::fprintf(stderr, "stac demo: 1/3 synthesising %.1f s of HDL-64E packets with %s\n", o.seconds,
               settings->calibration.filename().c_str());
  const auto packets = make_demo_capture(*calibration, o.seconds, kDemoStartNs);
  const auto pcap = dir / "demo.pcap";
  {
    auto writer = io::PcapWriter::open(pcap);
    if (!writer) return fail(writer.error().message);
    for (const DemoPacket& p : packets) {
      io::Datagram d;
      d.payload = p.bytes;
      d.stamp_ns = p.receive_stamp_ns;
      d.src_ip = 0xC0A8032B;  // 192.168.3.43, the HDL-64E's factory address
      d.dst_ip = 0xFFFFFFFF;
      d.src_port = 2368;
      d.dst_port = 2368;
      if (auto w = writer->write_udp(d); !w) return fail(w.error().message);
    }
    if (auto c = writer->close(); !c) return fail(c.error().message);
  }

  // 2. Live: over loopback UDP into the receiver thread, at the sensor's pace.
  std::fprintf(stderr, "stac demo: 2/3 sending %zu packets over loopback UDP at the sensor's pace\n",
               packets.size());
  auto live = run_live(*calibration, *settings, packets);
  if (!live) return fail(live.error().message);

  // 3. Offline: the pcap through `stac decode`, with a picture.
  std::fprintf(stderr, "stac demo: 3/3 decoding %s\n", pcap.c_str());
  DecodeOptions d;
  d.config = config.string();
  d.calib = settings->calibration.string();
  d.in = pcap.string();
  d.out = (dir / "demo.csv").string();
  d.png = (dir / "demo_birds_eye.png").string();
  if (const int code = run_decode(d); code != 0) return code;

  std::printf(
      "\nSTAC demo\n"
      "  capture      %s (%zu packets, %.1f s)\n"
      "  live UDP     %llu packets received, %llu scans (%llu complete), %llu points;"
      " kernel drops %llu\n"
      "  points       %s\n"
      "  picture      %s\n",
      pcap.c_str(), packets.size(), o.seconds, static_cast<unsigned long long>(live->packets),
      static_cast<unsigned long long>(live->scans), static_cast<unsigned long long>(live->complete),
      static_cast<unsigned long long>(live->points),
      static_cast<unsigned long long>(live->counters.kernel_drops), d.out.c_str(), d.png.c_str());
  if (live->packets != packets.size()) {
    return fail("the live path lost " + std::to_string(packets.size() - live->packets) +
                " packets on loopback (see the kernel drops above)");
  }
  return 0;
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "Run the driver end to end on a built-in synthetic capture (no sensor needed)");
  cmd->description(
      "Run the driver end to end on a built-in synthetic capture (no sensor needed):\n"
      "writes OUT/demo.pcap, sends it over loopback UDP into the live receiver at the sensor's\n"
      "pace, decodes the pcap to OUT/demo.csv and draws OUT/demo_birds_eye.png.");
  cmd->add_option("--out", o->out, "output folder")->capture_default_str();
  cmd->add_option("--seconds", o->seconds, "length of the capture")
      ->check(CLI::Range(0.2, 60.0))
      ->capture_default_str();
  cmd->add_option("--config", o->config, "configuration file (default: $STAC_CONFIG or config/stac.yaml)");
  cmd->callback([o] {
    if (const int code = run_demo(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

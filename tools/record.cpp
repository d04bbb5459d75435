// stac record: live UDP packets from the sensor -> a pcap file (nanosecond kernel stamps).
#include <csignal>
#include <cstdio>
#include <string>

#include "drivers/io/pcap_writer.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "rt/clock.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"

namespace stac::tools {

using namespace stac::settings;
namespace {

struct RecordOptions {
  std::string config;
  std::string out;
  std::string bind;
  int port = -1;
  double duration_s = 0.0;
  long long max_packets = 0;
};

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

int run_record(const RecordOptions& o) {
  const std::filesystem::path config = config_path(o.config);
  auto settings = load_velodyne_settings(config);
  if (!settings) return fail(settings.error().message);
  io::UdpReceiverConfig rc;
  rc.bind_address = o.bind.empty() ? settings->bind_address : o.bind;
  rc.port = o.port >= 0 ? static_cast<std::uint16_t>(o.port) : settings->port;
  rc.receive_buffer_bytes = settings->receive_buffer_bytes;
  rc.sender_address = settings->sender_address;
  auto receiver = io::UdpReceiver::open(rc);
  if (!receiver) return fail(receiver.error().message);
  auto writer = io::PcapWriter::open(o.out);
  if (!writer) return fail(writer.error().message);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::fprintf(stderr, "stac record: listening on %s:%u, writing %s (Ctrl-C to stop)\n",
               rc.bind_address.c_str(), receiver->port(), o.out.c_str());
  const std::int64_t start = rt::monotonic_ns();
  const std::int64_t end =
      o.duration_s > 0 ? start + static_cast<std::int64_t>(o.duration_s * 1e9) : 0;
  std::uint64_t packets = 0, bytes = 0;
  std::int64_t last_report = start;
  std::array<io::Datagram, 64> batch{};
  while (g_stop == 0) {
    const std::int64_t now = rt::monotonic_ns();
    if (end != 0 && now >= end) break;
    if (o.max_packets > 0 && packets >= static_cast<std::uint64_t>(o.max_packets)) break;
    const int n = receiver->receive(batch, 100);
    if (n < 0) return fail("receive failed on port " + std::to_string(receiver->port()));
    for (int i = 0; i < n; ++i) {
      const io::Datagram& d = batch[static_cast<std::size_t>(i)];
      if (auto w = writer->write_udp(d); !w) return fail(w.error().message);
      ++packets;
      bytes += d.payload.size();
      if (o.max_packets > 0 && packets >= static_cast<std::uint64_t>(o.max_packets)) break;
    }
    if (now - last_report > 1'000'000'000) {
      const double s = static_cast<double>(now - start) * 1e-9;
      std::fprintf(stderr, "\r  %.0f s: %llu packets, %.1f MB, %.0f packets/s   ", s,
                   static_cast<unsigned long long>(packets), static_cast<double>(bytes) * 1e-6,
                   static_cast<double>(packets) / s);
      last_report = now;
    }
  }
  if (auto c = writer->close(); !c) return fail(c.error().message);
  const auto& c = receiver->counters();
  std::fprintf(stderr,
               "\nstac record: %llu packets (%.1f MB) written to %s\n"
               "  dropped: by the kernel %llu, other senders %llu, truncated %llu\n",
               static_cast<unsigned long long>(packets), static_cast<double>(bytes) * 1e-6,
               o.out.c_str(), static_cast<unsigned long long>(c.kernel_drops),
               static_cast<unsigned long long>(c.filtered_sender),
               static_cast<unsigned long long>(c.truncated));
  return 0;
}

}  // namespace

void add_record_command(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* cmd =
      app.add_subcommand("record", "Record the sensor's live UDP packets to a pcap file");
  cmd->add_option("--out", o->out, "pcap file to write (nanosecond timestamps)")->required();
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--bind", o->bind, "address to listen on (default: the config's bind_address)");
  cmd->add_option("--port", o->port, "UDP port (default: the config's, 2368)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--duration", o->duration_s, "stop after this many seconds (default: Ctrl-C)")
      ->check(finite_range(0.001, 1e7));
  cmd->add_option("--packets", o->max_packets, "stop after this many packets")
      ->check(CLI::Range(1LL, 1'000'000'000'000LL));
  cmd->callback([o] {
    if (const int code = run_record(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

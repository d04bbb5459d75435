// stac replay: a capture's UDP payloads sent again over a socket at the recorded pace (for
// hardware-in-the-loop runs and tests), with the achieved rate and pacing error reported.
#include <csignal>
#include <cstdio>
#include <memory>

#include "drivers/io/udp_replay.hpp"
#include "tools/commands.hpp"

namespace stac::tools {
namespace {

struct ReplayOptions {
  std::string in;
  std::string to = "127.0.0.1";
  int port = -1;
  int filter_port = -1;
  double rate = 1.0;
  bool fast = false;
  std::uint64_t loops = 1;
  bool forever = false;
};

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free);  // safe to store from a signal handler

extern "C" void on_sigint(int) {
  g_stop.store(true, std::memory_order_relaxed);
}

std::string rate_text(double rate) {
  char b[48];
  std::snprintf(b, sizeof(b), "--rate %g", rate);
  return b;
}

void print_report(const ReplayOptions& o, const io::ReplayPlan& plan, const io::ReplayReport& r) {
  const double elapsed_s = static_cast<double>(r.elapsed_ns) * 1e-9;
  const double span_s = static_cast<double>(plan.span_ns) * 1e-9;
  const double recorded_pps =
      span_s > 0 && plan.packets > 1 ? static_cast<double>(plan.packets - 1) / span_s : 0.0;
  const double recorded_mbps = span_s > 0 ? 8e-6 * static_cast<double>(plan.bytes) / span_s : 0.0;
  const double pps =
      elapsed_s > 0 && r.packets > 1 ? static_cast<double>(r.packets - 1) / elapsed_s : 0.0;
  const double mbps = elapsed_s > 0 ? 8e-6 * static_cast<double>(r.bytes) / elapsed_s : 0.0;
  std::fprintf(
      stderr,
      "stac replay: %s -> %s%s%s\n"
      "  sent       %llu packets, %llu bytes in %.3f s (%llu full passes%s), %llu send failures\n"
      "  rate       %.1f packets/s, %.2f Mbit/s (recorded %.1f packets/s, %.2f Mbit/s; %s)\n",
      o.in.c_str(), o.to.c_str(), o.port > 0 ? (":" + std::to_string(o.port)).c_str() : "",
      o.port > 0 ? "" : " (captured ports)", static_cast<unsigned long long>(r.packets),
      static_cast<unsigned long long>(r.bytes), elapsed_s,
      static_cast<unsigned long long>(r.passes), r.stopped ? ", stopped" : "",
      static_cast<unsigned long long>(r.send_failures), pps, mbps, recorded_pps, recorded_mbps,
      o.fast ? "--fast" : rate_text(o.rate).c_str());
  if (o.fast) {
    std::fprintf(stderr, "  pacing     none (--fast)\n");
  } else {
    std::fprintf(stderr,
                 "  schedule   %.6f s scheduled for the last packet, %.6f s taken\n"
                 "  pacing error |sent - scheduled|: median %.1f us, p99 %.1f us, max %.1f us\n",
                 static_cast<double>(r.scheduled_ns) * 1e-9, elapsed_s,
                 static_cast<double>(r.error_median_ns) * 1e-3,
                 static_cast<double>(r.error_p99_ns) * 1e-3,
                 static_cast<double>(r.error_max_ns) * 1e-3);
  }
  if (r.send_failures > 0) {
    std::fprintf(
        stderr,
        "  note       send failures on loopback usually mean nothing listens on the port\n");
  }
  if (r.stamps_backwards > 0) {
    std::fprintf(stderr,
                 "  note       %llu packets stamped before their predecessor were sent at once\n",
                 static_cast<unsigned long long>(r.stamps_backwards));
  }
}

int run_replay(const ReplayOptions& o) {
  io::ReplayConfig c;
  c.address = o.to;
  if (o.port > 0) c.port = static_cast<std::uint16_t>(o.port);
  if (o.filter_port > 0) c.filter_port = static_cast<std::uint16_t>(o.filter_port);
  c.rate = o.rate;
  c.fast = o.fast;
  c.loops = o.forever ? 0 : o.loops;
  auto replay = io::UdpReplay::open(o.in, c);
  if (!replay) return fail(replay.error().message);
  const io::ReplayPlan& plan = replay->plan();
  std::string ports;
  for (auto p : plan.dst_ports) ports += (ports.empty() ? "" : ",") + std::to_string(p);
  std::fprintf(stderr,
               "stac replay: %llu packets per pass over %.3f s recorded (captured ports %s)\n",
               static_cast<unsigned long long>(plan.packets),
               static_cast<double>(plan.span_ns) * 1e-9, ports.c_str());

  g_stop = false;
  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  struct sigaction old_int {
  }, old_term{};
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);
  auto report = replay->run(g_stop);
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  if (!report) return fail(report.error().message);
  print_report(o, plan, *report);
  if (report->packets == 0 && !report->stopped) return fail("no packet could be sent");
  return 0;
}

}  // namespace

void add_replay_command(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd =
      app.add_subcommand("replay", "Send a capture's UDP packets again at the recorded pace");
  cmd->description(
      "Send the UDP payloads of a pcap capture to an address (default 127.0.0.1), each at its\n"
      "recorded time divided by --rate (or as fast as possible with --fast), optionally looping.\n"
      "Destination port: --port, else each packet's captured destination port. Reports packets,\n"
      "bytes, achieved vs recorded rate and the pacing error |sent - scheduled| (median, p99,\n"
      "max). Ctrl-C stops and reports. TCP streams in the capture are not served (yet).");
  cmd->add_option("--in", o->in, "pcap capture to replay")->required();
  cmd->add_option("--to", o->to, "destination IPv4 address")->capture_default_str();
  cmd->add_option("--port", o->port, "destination UDP port (default: the captured one)")
      ->check(CLI::Range(1, 65535));
  cmd->add_option("--filter-port", o->filter_port, "replay only packets captured to this UDP port")
      ->check(CLI::Range(1, 65535));
  auto* rate = cmd->add_option("--rate", o->rate, "speed factor: 2 sends twice as fast as recorded")
                   ->check(CLI::PositiveNumber)
                   ->capture_default_str();
  cmd->add_flag("--fast", o->fast, "no pacing: as fast as the socket takes them")->excludes(rate);
  auto* loop = cmd->add_option("--loop", o->loops, "passes over the capture")
                   ->check(CLI::Range(1, 1'000'000))
                   ->capture_default_str();
  cmd->add_flag("--forever", o->forever, "loop until Ctrl-C")->excludes(loop);
  cmd->callback([o] {
    if (const int code = run_replay(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools

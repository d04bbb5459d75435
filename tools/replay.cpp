// stac replay: a capture's UDP payloads sent again over a socket and its TCP streams served
// as a TCP server, at the recorded pace on one clock (for hardware-in-the-loop runs and tests),
// with the achieved rate and pacing error reported (replay/replay_session.hpp): the options, the
// stop signals, the reports on stderr.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>

#include "replay/replay_session.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"

namespace stac::tools {
namespace {

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free);  // safe to store from a signal handler

extern "C" void on_stop_signal(int) {
  g_stop.store(true, std::memory_order_relaxed);
}

}  // namespace

void add_replay_command(CLI::App& app) {
  auto o = std::make_shared<replay::SessionOptions>();
  CLI::App* cmd = app.add_subcommand(
      "replay", "Send a capture's UDP packets and serve its TCP streams at the recorded pace");
  cmd->description(
      "Send the UDP payloads of a pcap capture to an address (default 127.0.0.1), each at its\n"
      "recorded time divided by --rate (or as fast as possible with --fast), optionally looping.\n"
      "Destination port: --port, else each packet's captured destination port. Reports packets,\n"
      "bytes, achieved vs recorded rate and the pacing error |sent - scheduled| (median, p99,\n"
      "max). Ctrl-C stops and reports.\n"
      "TCP streams (e.g. the Applanix Real-Time Data port 5602) are served at the same time, on\n"
      "one clock with the UDP packets, by a TCP server on --tcp-listen at the captured server\n"
      "port: one client at a time; the stream runs on whether a client is connected or not (a\n"
      "client that connects gets it from then on); --wait-tcp holds the start until a client\n"
      "is connected to every served port.\n"
      "CAN: --can LOG sends a candump log's frames (stamped in the capture's time, as `stac sim\n"
      "--can` writes them) on the same clock as cannelloni datagrams (CAN over UDP) to\n"
      "--can-port, for `stac run` with can.transport: cannelloni.");
  cmd->add_option("--in", o->in, "pcap capture to replay")->required();
  cmd->add_option("--to", o->to, "destination IPv4 address")->capture_default_str();
  cmd->add_option("--port", o->port, "destination UDP port (default: the captured one)")
      ->check(CLI::Range(1, 65535));
  cmd->add_option("--filter-port", o->filter_port, "replay only packets captured to this UDP port")
      ->check(CLI::Range(1, 65535));
  auto* rate = cmd->add_option("--rate", o->rate, "speed factor: 2 sends twice as fast as recorded")
                   ->check(finite_range(0.001, 1000.0))
                   ->capture_default_str();
  cmd->add_flag("--fast", o->fast, "no pacing: as fast as the socket takes them")->excludes(rate);
  auto* loop = cmd->add_option("--loop", o->loops, "passes over the capture")
                   ->check(CLI::Range(1, 1'000'000))
                   ->capture_default_str();
  cmd->add_flag("--forever", o->forever, "loop until Ctrl-C")->excludes(loop);
  auto* tcp_port = cmd->add_option("--tcp-port", o->tcp_ports,
                                   "captured TCP server port to serve, PORT or PORT:LISTEN_PORT "
                                   "(0: any free one); repeatable (default: every captured one)");
  cmd->add_option("--tcp-listen", o->tcp_listen, "IPv4 address the TCP servers listen on")
      ->capture_default_str();
  cmd->add_flag("--no-tcp", o->no_tcp, "do not serve the capture's TCP streams")
      ->excludes(tcp_port);
  cmd->add_option("--faults", o->faults,
                  "faults injected into the UDP datagrams, seeded (issue 31): comma-separated "
                  "loss=P, burst=P:N, reorder=P, duplicate=P, truncate=P, oversize=P, garbage=P, "
                  "dropout=START+SECONDS, clock-jump=AT:SECONDS (Velodyne timestamps), "
                  "window=START+SECONDS (the random ones only then), seed=N; into the TCP "
                  "streams (the INS): ins-dropout=START+SECONDS, ins-garbage=START+SECONDS, "
                  "ins-checksum=START+SECONDS (Applanix checksums broken), ins-disconnect=AT; "
                  "into the CAN frames of --can: can-silence=START+SECONDS; "
                  "times in capture seconds of each pass, e.g. --faults "
                  "loss=0.01,garbage=0.01,window=2+3,seed=7");
  cmd->add_option("--can", o->can_log,
                  "candump log whose frames are sent as cannelloni datagrams (CAN over UDP) on "
                  "the capture's clock")
      ->check(CLI::ExistingFile);
  cmd->add_option("--can-port", o->can_port, "UDP port of the cannelloni datagrams")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  cmd->add_flag("--wait-tcp", o->wait_tcp,
                "start the replay once a client is connected to every served TCP port");
  cmd->callback([o] {
    // Ctrl-C and SIGTERM stop the replay, which then reports what it sent.
    g_stop = false;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    struct sigaction old_int {
    }, old_term{};
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    const rt::Status done = replay::run_session(
        *o, g_stop, [](const std::string& text) { std::fputs(text.c_str(), stderr); });
    sigaction(SIGINT, &old_int, nullptr);
    sigaction(SIGTERM, &old_term, nullptr);
    if (!done) throw CLI::RuntimeError(fail(done.error().message));
  });
}

}  // namespace stac::tools

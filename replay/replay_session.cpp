// A replay session (replay_session.hpp): the capture's UDP datagrams, TCP streams and a candump
// log opened, faults planned, everything run on one clock in threads of its own, the reports.
#include "replay/replay_session.hpp"

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "replay/can_replay.hpp"
#include "replay/faults.hpp"
#include "replay/tcp_replay.hpp"
#include "replay/udp_replay.hpp"
#include "rt/clock.hpp"
#include "rt/formatted.hpp"

namespace stac::replay {
namespace {

struct TcpServe {
  std::uint16_t port = 0;                    // captured server port
  std::optional<std::uint16_t> listen_port;  // default: the captured one
  bool asked = false;                        // named by --tcp-port: failures are fatal
};

std::string rate_text(double rate) {
  char b[48];
  std::snprintf(b, sizeof(b), "--rate %g", rate);
  return b;
}

// The schedule and pacing error of a stream's report, its last UNIT (packet, segment) named.
std::string pacing_lines(const char* unit, std::int64_t scheduled_ns, double elapsed_s,
                         std::int64_t median_ns, std::int64_t p99_ns, std::int64_t max_ns) {
  return rt::formatted(
      "  schedule   %.6f s scheduled for the last %s, %.6f s taken\n"
      "  pacing error |sent - scheduled|: median %.1f us, p99 %.1f us, max %.1f us\n",
      static_cast<double>(scheduled_ns) * 1e-9, unit, elapsed_s,
      static_cast<double>(median_ns) * 1e-3, static_cast<double>(p99_ns) * 1e-3,
      static_cast<double>(max_ns) * 1e-3);
}

// first_due_ns: when the first datagram was due on the shared clock; the schedule is printed
// from there (as for a UDP replay alone).
void print_report(const Say& say, const SessionOptions& o, const ReplayPlan& plan, ReplayReport r,
                  std::int64_t first_due_ns) {
  r.elapsed_ns -= first_due_ns;
  if (!o.fast) r.scheduled_ns -= first_due_ns;
  const double elapsed_s = static_cast<double>(r.elapsed_ns) * 1e-9;
  const double span_s = static_cast<double>(plan.span_ns) * 1e-9;
  const double recorded_pps =
      span_s > 0 && plan.packets > 1 ? static_cast<double>(plan.packets - 1) / span_s : 0.0;
  const double recorded_mbps = span_s > 0 ? 8e-6 * static_cast<double>(plan.bytes) / span_s : 0.0;
  const double pps =
      elapsed_s > 0 && r.packets > 1 ? static_cast<double>(r.packets - 1) / elapsed_s : 0.0;
  const double mbps = elapsed_s > 0 ? 8e-6 * static_cast<double>(r.bytes) / elapsed_s : 0.0;
  // (the port as its own formatted text: a `":" + std::to_string()` here makes GCC 12's -Wrestrict
  // misfire)
  const std::string port = o.port > 0 ? rt::formatted(":%d", o.port) : std::string();
  say(rt::formatted(
      "stac replay: %s -> %s%s%s\n"
      "  sent       %llu packets, %llu bytes in %.3f s (%llu full passes%s), %llu send failures\n"
      "  rate       %.1f packets/s, %.2f Mbit/s (recorded %.1f packets/s, %.2f Mbit/s; %s)\n",
      o.in.c_str(), o.to.c_str(), port.c_str(), o.port > 0 ? "" : " (captured ports)",
      static_cast<unsigned long long>(r.packets), static_cast<unsigned long long>(r.bytes),
      elapsed_s, static_cast<unsigned long long>(r.passes), r.stopped ? ", stopped" : "",
      static_cast<unsigned long long>(r.send_failures), pps, mbps, recorded_pps, recorded_mbps,
      o.fast ? "--fast" : rate_text(o.rate).c_str()));
  if (o.fast) {
    say("  pacing     none (--fast)\n");
  } else {
    say(pacing_lines("packet", r.scheduled_ns, elapsed_s, r.error_median_ns, r.error_p99_ns,
                     r.error_max_ns));
  }
  if (r.faults) say(rt::formatted("  %s\n", summary(*r.faults).c_str()));
  if (r.send_failures > 0) {
    say("  note       send failures on loopback usually mean nothing listens on the port\n");
  }
  if (r.stamps_backwards > 0) {
    say(rt::formatted(
        "  note       %llu packets stamped before their predecessor were sent at once\n",
        static_cast<unsigned long long>(r.stamps_backwards)));
  }
}

void print_tcp_report(const Say& say, const SessionOptions& o, const TcpReplay& t,
                      TcpReplayReport r, std::uint16_t port, std::int64_t first_due_ns) {
  const TcpReplayPlan& plan = t.plan();
  r.elapsed_ns = std::max<std::int64_t>(0, r.elapsed_ns - first_due_ns);  // 0: nothing written
  if (!o.fast) r.scheduled_ns -= first_due_ns;
  const double elapsed_s = static_cast<double>(r.elapsed_ns) * 1e-9;
  const double span_s = static_cast<double>(plan.span_ns) * 1e-9;
  const double recorded_mbps = span_s > 0 ? 8e-6 * static_cast<double>(plan.bytes) / span_s : 0.0;
  const double mbps = elapsed_s > 0 ? 8e-6 * static_cast<double>(r.bytes) / elapsed_s : 0.0;
  const double sps =
      elapsed_s > 0 && r.segments > 1 ? static_cast<double>(r.segments - 1) / elapsed_s : 0.0;
  say(rt::formatted(
      "stac replay: TCP stream of port %u served on %s:%u\n"
      "  sent       %llu bytes in %llu segments in %.3f s (%llu full passes%s), %llu bytes "
      "unserved (no client)\n"
      "  clients    %llu connected, %llu gone (%llu stalled)\n"
      "  rate       %.1f segments/s, %.4f Mbit/s (recorded %.4f Mbit/s; %s)\n",
      port, o.tcp_listen.c_str(), t.listen_port(), static_cast<unsigned long long>(r.bytes),
      static_cast<unsigned long long>(r.segments), elapsed_s,
      static_cast<unsigned long long>(r.passes), r.stopped ? ", stopped" : "",
      static_cast<unsigned long long>(r.unserved_bytes), static_cast<unsigned long long>(r.clients),
      static_cast<unsigned long long>(r.disconnects), static_cast<unsigned long long>(r.stalls),
      sps, mbps, recorded_mbps, o.fast ? "--fast" : rate_text(o.rate).c_str()));
  if (o.fast) {
    say("  pacing     none (--fast)\n");
  } else if (r.error_max_ns >= 0) {
    say(pacing_lines("segment", r.scheduled_ns, elapsed_s, r.error_median_ns, r.error_p99_ns,
                     r.error_max_ns));
  }
  if (r.faults) say(rt::formatted("  %s\n", summary(*r.faults).c_str()));
}

// --tcp-port values: "P" or "P:L" (serve captured port P on listen port L, 0: any free one).
rt::Result<std::vector<TcpServe>> parse_tcp_ports(const std::vector<std::string>& values) {
  std::vector<TcpServe> out;
  auto number = [](const std::string& t, long lo) -> std::optional<std::uint16_t> {
    if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos || t.size() > 5) {
      return std::nullopt;
    }
    const long v = std::stol(t);
    if (v < lo || v > 65535) return std::nullopt;
    return static_cast<std::uint16_t>(v);
  };
  for (const std::string& v : values) {
    const std::size_t colon = v.find(':');
    TcpServe s;
    s.asked = true;
    const auto port = number(v.substr(0, colon), 1);
    if (!port) return rt::make_error("--tcp-port " + v + ": expected PORT or PORT:LISTEN_PORT");
    s.port = *port;
    if (colon != std::string::npos) {
      s.listen_port = number(v.substr(colon + 1), 0);
      if (!s.listen_port) return rt::make_error("--tcp-port " + v + ": bad LISTEN_PORT");
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace

rt::Status run_session(const SessionOptions& o, std::atomic<bool>& stop, const Say& say) {
  // The TCP streams to serve.
  std::vector<TcpServe> serve;
  if (!o.no_tcp) {
    if (!o.tcp_ports.empty()) {
      auto asked = parse_tcp_ports(o.tcp_ports);
      if (!asked) return rt::make_error(asked.error().message);
      serve = *asked;
    } else {
      auto found = TcpReplay::server_ports(o.in);
      if (!found) return rt::make_error(found.error().message);
      for (std::uint16_t p : *found) serve.push_back(TcpServe{p, std::nullopt, false});
    }
  }
  std::vector<TcpReplay> tcp;
  std::vector<std::uint16_t> tcp_port_of;
  for (const TcpServe& s : serve) {
    TcpReplayConfig tc;
    tc.server_port = s.port;
    tc.listen_address = o.tcp_listen;
    tc.listen_port = s.listen_port;
    tc.rate = o.rate;
    tc.fast = o.fast;
    tc.loops = o.forever ? 0 : o.loops;
    auto t = TcpReplay::open(o.in, tc);
    if (!t && s.asked) return rt::make_error(t.error().message);
    if (!t) {
      say(
          rt::formatted("stac replay: warning: TCP stream of port %u not served: %s (choose with "
                        "--tcp-port %u:LISTEN_PORT, or --no-tcp)\n",
                        s.port, t.error().message.c_str(), s.port));
      continue;
    }
    tcp.push_back(std::move(*t));
    tcp_port_of.push_back(s.port);
  }

  ReplayConfig c;
  c.address = o.to;
  if (o.port > 0) c.port = static_cast<std::uint16_t>(o.port);
  if (o.filter_port > 0) c.filter_port = static_cast<std::uint16_t>(o.filter_port);
  c.rate = o.rate;
  c.fast = o.fast;
  c.loops = o.forever ? 0 : o.loops;
  c.allow_empty = !tcp.empty() && o.filter_port <= 0;  // a TCP-only capture
  std::optional<StreamFaultPlan> stream_faults;
  TimeSpan can_silence;
  if (!o.faults.empty()) {
    auto plan = parse_fault_plan(o.faults);
    if (!plan) return rt::make_error(plan.error().message);
    if (plan->any()) c.faults = *plan;
    if (plan->ins.any()) {
      if (tcp.empty()) {
        return rt::make_error(
            "--faults " + o.faults +
            ": ins-... faults act on the replayed TCP streams, and none is served "
            "(--no-tcp, or no TCP stream in the capture)");
      }
      stream_faults = plan->ins;
    }
    if (plan->can_silence && o.can_log.empty()) {
      return rt::make_error("--faults " + o.faults +
                            ": can-silence acts on the CAN frames of --can LOG, and none is given");
    }
    can_silence = plan->can_silence;
  }
  auto replay = UdpReplay::open(o.in, c);
  if (!replay) return rt::make_error(replay.error().message);
  const ReplayPlan& plan = replay->plan();
  if (stream_faults) {  // in the same capture time as the datagrams' faults
    for (auto& t : tcp)
      t.inject(*stream_faults, plan.packets > 0 ? plan.first_stamp_ns : t.plan().first_stamp_ns);
  }
  std::optional<CanReplay> can;
  if (!o.can_log.empty()) {
    CanReplayConfig cc;
    cc.address = o.to;
    cc.port = static_cast<std::uint16_t>(o.can_port);
    cc.fast = o.fast;
    cc.loops = o.forever ? 0 : o.loops;
    cc.silence = can_silence;
    cc.origin_ns = plan.packets > 0 ? plan.first_stamp_ns : 0;
    auto opened = CanReplay::open(o.can_log, cc);
    if (!opened) return rt::make_error(opened.error().message);
    can.emplace(std::move(*opened));
    if (plan.packets == 0) {
      return rt::make_error("--can " + o.can_log +
                            ": CAN frames are sent beside the capture's UDP "
                            "datagrams, and it has none");
    }
    say(
        rt::formatted("stac replay: CAN: %llu frames of %s over %.3f s, as cannelloni datagrams to "
                      "%s:%d\n",
                      static_cast<unsigned long long>(can->plan().frames), o.can_log.c_str(),
                      static_cast<double>(can->plan().span_ns) * 1e-9, o.to.c_str(), o.can_port));
  }
  if (plan.packets == 0)
    say(rt::formatted("stac replay: warning: %s; the TCP streams only\n", plan.why_empty.c_str()));
  if (plan.packets > 0) {
    std::string ports;
    for (auto p : plan.dst_ports) ports += (ports.empty() ? "" : ",") + std::to_string(p);
    say(rt::formatted(
        "stac replay: %llu packets per pass over %.3f s recorded (captured ports %s)\n",
        static_cast<unsigned long long>(plan.packets), static_cast<double>(plan.span_ns) * 1e-9,
        ports.c_str()));
  }
  for (std::size_t i = 0; i < tcp.size(); ++i) {
    const TcpReplayPlan& tp = tcp[i].plan();
    say(rt::formatted(
        "stac replay: TCP stream of port %u: %llu bytes in %llu segments over %.3f s "
        "recorded (%llu retransmitted, %llu gaps); listening on %s:%u\n",
        tcp_port_of[i], static_cast<unsigned long long>(tp.bytes),
        static_cast<unsigned long long>(tp.segments), static_cast<double>(tp.span_ns) * 1e-9,
        static_cast<unsigned long long>(tp.retransmitted), static_cast<unsigned long long>(tp.gaps),
        o.tcp_listen.c_str(), tcp[i].listen_port()));
  }

  if (o.wait_tcp) {
    for (std::size_t i = 0; i < tcp.size(); ++i) {
      say(rt::formatted("stac replay: waiting for a client on %s:%u\n", o.tcp_listen.c_str(),
                        tcp[i].listen_port()));
      (void)tcp[i].wait_for_client(stop);
    }
  }
  // One clock for all: the capture's earliest stream byte or datagram is due 2 ms from now.
  ReplayClock clock;
  clock.rate = o.fast ? 1.0 : o.rate;
  std::vector<std::pair<std::int64_t, std::int64_t>> firsts;  // (first stamp, pass period)
  if (plan.packets > 0) firsts.emplace_back(plan.first_stamp_ns, plan.pass_period_ns);
  for (const auto& t : tcp) firsts.emplace_back(t.plan().first_stamp_ns, t.plan().pass_period_ns);
  if (can) firsts.emplace_back(can->plan().first_stamp_ns, can->plan().span_ns + 1'000'000);
  clock.first_stamp_ns = std::min_element(firsts.begin(), firsts.end())->first;
  for (const auto& [first, period] : firsts) {
    clock.pass_period_ns = std::max(clock.pass_period_ns, first - clock.first_stamp_ns + period);
  }
  clock.start_ns = rt::monotonic_ns() + 2'000'000;
  // The same moment on the wall clock, which receivers stamp packets with (SO_TIMESTAMPNS): a
  // fault at capture second S reaches them at this time + S / rate.
  say(rt::formatted(
      "stac replay: the capture's first datagram is due at %.6f s (CLOCK_REALTIME)\n",
      static_cast<double>(
          rt::realtime_ns() + clock.start_ns - rt::monotonic_ns() +
          clock.offset_ns(0, plan.packets > 0 ? plan.first_stamp_ns : clock.first_stamp_ns)) *
          1e-9));

  std::vector<rt::Result<TcpReplayReport>> tcp_reports(tcp.size(), rt::make_error("not run"));
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < tcp.size(); ++i) {
    threads.emplace_back([&, i] { tcp_reports[i] = tcp[i].run(stop, &clock); });
  }
  CanReplayReport can_report;
  if (can) threads.emplace_back([&] { can_report = can->run(stop, clock); });
  rt::Result<ReplayReport> report = ReplayReport{};
  if (plan.packets > 0) report = replay->run(stop, &clock);
  for (auto& t : threads) t.join();
  if (!report) return rt::make_error(report.error().message);
  for (auto& r : tcp_reports) {
    if (!r) return rt::make_error(r.error().message);
  }
  const std::int64_t udp_first_due = clock.offset_ns(0, plan.first_stamp_ns);
  if (plan.packets > 0) print_report(say, o, plan, *report, o.fast ? 0 : udp_first_due);
  for (std::size_t i = 0; i < tcp.size(); ++i) {
    print_tcp_report(say, o, tcp[i], *tcp_reports[i], tcp_port_of[i],
                     o.fast ? 0 : clock.offset_ns(0, tcp[i].plan().first_stamp_ns));
  }
  if (can) {
    say(rt::formatted(
        "stac replay: CAN to %s:%d: %llu frames sent (%llu full passes%s), %llu "
        "silenced (can-silence), %llu send failures\n",
        o.to.c_str(), o.can_port, static_cast<unsigned long long>(can_report.frames),
        static_cast<unsigned long long>(can_report.passes), can_report.stopped ? ", stopped" : "",
        static_cast<unsigned long long>(can_report.silenced),
        static_cast<unsigned long long>(can_report.send_failures)));
  }
  if (plan.packets > 0 && report->packets == 0 && !report->stopped) {
    return rt::make_error("no packet could be sent");
  }
  return {};
}

}  // namespace stac::replay

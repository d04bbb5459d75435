#include "drivers/io/udp_replay.hpp"

#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

#include "rt/clock.hpp"

namespace stac::io {
namespace {

constexpr std::int64_t kSpinNs = 50'000;       // busy-wait the last 50 us before a send
constexpr std::size_t kHistogramUs = 100'000;  // 1 us bins up to 100 ms, then one overflow bin
constexpr std::size_t kMaxPorts = 64;

PcapFilter filter_of(const ReplayConfig& c) {
  PcapFilter f;
  f.udp_dst_port = c.filter_port;
  return f;
}

// Sleeps until CLOCK_MONOTONIC reaches due_ns (or stop is set): an absolute sleep to shortly
// before, then a spin.
void wait_until(std::int64_t due_ns, const std::atomic<bool>& stop) noexcept {
  if (due_ns - rt::monotonic_ns() > kSpinNs) {
    const std::int64_t wake = due_ns - kSpinNs;
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(wake / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(wake % 1'000'000'000);
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
      if (stop.load(std::memory_order_relaxed)) return;
    }
  }
  while (rt::monotonic_ns() < due_ns) {
    if (stop.load(std::memory_order_relaxed)) return;
  }
}

std::int64_t percentile_ns(const std::vector<std::uint64_t>& histogram, std::uint64_t total,
                           double q) {
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(total)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < histogram.size(); ++i) {
    seen += histogram[i];
    if (seen >= std::max<std::uint64_t>(rank, 1)) return static_cast<std::int64_t>(i) * 1000;
  }
  return static_cast<std::int64_t>(histogram.size() - 1) * 1000;
}

}  // namespace

rt::Result<UdpReplay> UdpReplay::open(const std::filesystem::path& capture,
                                      const ReplayConfig& config) {
  if (!(config.rate > 0.0) || !std::isfinite(config.rate)) {
    return rt::make_error("replay rate must be a number > 0 (1 = recorded pace)");
  }
  auto reader = PcapReader::open(capture, filter_of(config));
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  UdpReplay r;
  r.capture_ = capture;
  r.config_ = config;
  Datagram d;
  std::int64_t last = 0;
  while (reader->next(d)) {
    if (r.plan_.packets == 0) r.first_stamp_ns_ = d.stamp_ns;
    last = std::max(last, d.stamp_ns);
    ++r.plan_.packets;
    r.plan_.bytes += d.payload.size();
    auto& ports = r.plan_.dst_ports;
    if (std::find(ports.begin(), ports.end(), d.dst_port) == ports.end()) {
      if (ports.size() == kMaxPorts && !config.port) {
        return rt::make_error(capture.string() +
                              ": datagrams to more than 64 ports; pass --port "
                              "(or --filter-port) to choose one");
      }
      if (ports.size() < kMaxPorts) ports.push_back(d.dst_port);
    }
  }
  if (!reader->error().empty()) return rt::make_error(reader->error());
  if (r.plan_.packets == 0) {
    const PcapCounters& c = reader->counters();
    std::string why = capture.string() + ": no UDP datagram to replay";
    if (config.filter_port) why += " to port " + std::to_string(*config.filter_port);
    why += " (" + std::to_string(c.frames) + " frames: " + std::to_string(c.non_udp) +
           " IPv4 not UDP, " + std::to_string(c.non_ipv4) + " not IPv4, " +
           std::to_string(c.filtered_out) + " UDP to other ports, " + std::to_string(c.fragments) +
           " fragments)";
    return rt::make_error(why);
  }
  r.plan_.span_ns = std::max<std::int64_t>(0, last - r.first_stamp_ns_);
  const std::int64_t mean_gap =
      r.plan_.packets > 1 ? r.plan_.span_ns / static_cast<std::int64_t>(r.plan_.packets - 1) : 0;
  r.plan_.pass_period_ns = r.plan_.span_ns + mean_gap;

  if (config.port) {
    auto s = UdpSender::open(config.address, *config.port);
    if (!s) return rt::Unexpected<rt::Error>{s.error()};
    r.senders_.emplace_back(*config.port, std::move(*s));
  } else {
    for (std::uint16_t p : r.plan_.dst_ports) {
      if (p == 0) return rt::make_error(capture.string() + ": a datagram to port 0; pass --port");
      auto s = UdpSender::open(config.address, p);
      if (!s) return rt::Unexpected<rt::Error>{s.error()};
      r.senders_.emplace_back(p, std::move(*s));
    }
  }
  return r;
}

std::int64_t UdpReplay::scheduled_ns(std::uint64_t pass, std::int64_t stamp_ns) const noexcept {
  const double recorded = static_cast<double>(pass) * static_cast<double>(plan_.pass_period_ns) +
                          static_cast<double>(stamp_ns - first_stamp_ns_);
  return std::llround(recorded / config_.rate);
}

UdpSender* UdpReplay::sender_for(std::uint16_t port) noexcept {
  if (config_.port) return &senders_.front().second;
  for (auto& [p, s] : senders_) {
    if (p == port) return &s;
  }
  return nullptr;
}

rt::Result<ReplayReport> UdpReplay::run(const std::atomic<bool>& stop) {
  ReplayReport report;
  // The default timer slack (50 us) would let every sleep overshoot into the spin margin.
  (void)::prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL);
  std::vector<std::uint64_t> histogram(kHistogramUs + 1, 0);
  std::int64_t start = 0, last_send = 0, last_scheduled = 0;
  for (std::uint64_t pass = 0; config_.loops == 0 || pass < config_.loops; ++pass) {
    auto reader = PcapReader::open(capture_, filter_of(config_));
    if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
    Datagram d;
    std::int64_t prev_stamp = first_stamp_ns_;
    bool interrupted = false;
    while (reader->next(d)) {
      if (stop.load(std::memory_order_relaxed)) {
        interrupted = true;
        break;
      }
      UdpSender* sender = sender_for(d.dst_port);
      if (sender == nullptr) continue;  // a port beyond the 64 planned: cannot happen with --port
      if (d.stamp_ns < prev_stamp) ++report.stamps_backwards;
      prev_stamp = std::max(prev_stamp, d.stamp_ns);
      std::int64_t now = rt::monotonic_ns();
      if (report.packets + report.send_failures == 0) start = now;
      if (!config_.fast) {
        // Never earlier than the datagram before: stamps that go backwards are sent at once.
        last_scheduled = std::max(last_scheduled, scheduled_ns(pass, d.stamp_ns));
        wait_until(start + last_scheduled, stop);
        if (stop.load(std::memory_order_relaxed)) {
          interrupted = true;
          break;
        }
        now = rt::monotonic_ns();
        const std::int64_t error = std::abs(now - (start + last_scheduled));
        ++histogram[std::min<std::size_t>(static_cast<std::size_t>(error / 1000), kHistogramUs)];
        report.error_max_ns = std::max(report.error_max_ns, error);
      }
      if (sender->send(d.payload)) {
        ++report.packets;
        report.bytes += d.payload.size();
      } else {
        ++report.send_failures;
      }
      last_send = now;
    }
    if (!reader->error().empty()) return rt::make_error(reader->error());
    if (!interrupted) ++report.passes;  // every datagram of the pass was sent
    if (stop.load(std::memory_order_relaxed)) {
      report.stopped = true;
      break;
    }
  }
  report.scheduled_ns = config_.fast ? 0 : last_scheduled;
  report.elapsed_ns = last_send - start;
  const std::uint64_t sent = report.packets + report.send_failures;
  if (!config_.fast && sent > 0) {
    report.error_median_ns = percentile_ns(histogram, sent, 0.5);
    report.error_p99_ns = percentile_ns(histogram, sent, 0.99);
  }
  return report;
}

}  // namespace stac::io

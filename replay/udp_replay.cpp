#include "replay/udp_replay.hpp"

#include <algorithm>
#include <cmath>

#include "rt/clock.hpp"

namespace stac::replay {
namespace {

constexpr std::size_t kMaxPorts = 64;

io::PcapFilter filter_of(const ReplayConfig& c) {
  io::PcapFilter f;
  f.udp_dst_port = c.filter_port;
  return f;
}

}  // namespace

rt::Result<UdpReplay> UdpReplay::open(const std::filesystem::path& capture,
                                      const ReplayConfig& config) {
  if (!(config.rate > 0.0) || !std::isfinite(config.rate)) {
    return rt::make_error("replay rate must be a number > 0 (1 = recorded pace)");
  }
  auto reader = io::PcapReader::open(capture, filter_of(config));
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  UdpReplay r;
  r.capture_ = capture;
  r.config_ = config;
  io::Datagram d;
  std::int64_t last = 0;
  while (reader->next(d)) {
    if (r.plan_.packets == 0) r.plan_.first_stamp_ns = d.stamp_ns;
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
    const io::PcapCounters& c = reader->counters();
    std::string why = capture.string() + ": no UDP datagram to replay";
    if (config.filter_port) why += " to port " + std::to_string(*config.filter_port);
    why += " (" + std::to_string(c.frames) + " frames: " + std::to_string(c.non_udp) +
           " IPv4 not UDP, " + std::to_string(c.non_ipv4) + " not IPv4, " +
           std::to_string(c.filtered_out) + " UDP to other ports, " + std::to_string(c.fragments) +
           " fragments, " + std::to_string(c.truncated_frame) +
           " truncated: captured shorter than their headers say, a snap length below the packet "
           "size?, " +
           std::to_string(c.bad_header) + " with impossible headers)";
    r.plan_.why_empty = why;
    if (config.allow_empty) return r;
    return rt::make_error(why);
  }
  r.plan_.span_ns = std::max<std::int64_t>(0, last - r.plan_.first_stamp_ns);
  const std::int64_t mean_gap =
      r.plan_.packets > 1 ? r.plan_.span_ns / static_cast<std::int64_t>(r.plan_.packets - 1) : 0;
  r.plan_.pass_period_ns = r.plan_.span_ns + mean_gap;

  if (config.port) {
    auto s = io::UdpSender::open(config.address, *config.port);
    if (!s) return rt::Unexpected<rt::Error>{s.error()};
    r.senders_.emplace_back(*config.port, std::move(*s));
  } else {
    for (std::uint16_t p : r.plan_.dst_ports) {
      if (p == 0) return rt::make_error(capture.string() + ": a datagram to port 0; pass --port");
      auto s = io::UdpSender::open(config.address, p);
      if (!s) return rt::Unexpected<rt::Error>{s.error()};
      r.senders_.emplace_back(p, std::move(*s));
    }
  }
  if (config.faults) r.faults_.emplace(*config.faults);
  return r;
}

std::int64_t UdpReplay::scheduled_ns(std::uint64_t pass, std::int64_t stamp_ns) const noexcept {
  return ReplayClock{0, plan_.first_stamp_ns, plan_.pass_period_ns, config_.rate}.offset_ns(
      pass, stamp_ns);
}

io::UdpSender* UdpReplay::sender_for(std::uint16_t port) noexcept {
  if (config_.port) return &senders_.front().second;
  for (auto& [p, s] : senders_) {
    if (p == port) return &s;
  }
  return nullptr;
}

rt::Result<ReplayReport> UdpReplay::run(const std::atomic<bool>& stop, const ReplayClock* shared) {
  ReplayReport report;
  if (plan_.packets == 0) return report;
  PacingStats pacing;
  ReplayClock clock =
      shared ? *shared : ReplayClock{0, plan_.first_stamp_ns, plan_.pass_period_ns, config_.rate};
  std::int64_t last_send = clock.start_ns, last_scheduled = 0;
  for (std::uint64_t pass = 0; config_.loops == 0 || pass < config_.loops; ++pass) {
    auto reader = io::PcapReader::open(capture_, filter_of(config_));
    if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
    io::Datagram d;
    std::int64_t prev_stamp = plan_.first_stamp_ns;
    bool interrupted = false;
    while (reader->next(d)) {
      if (stop.load(std::memory_order_relaxed)) {
        interrupted = true;
        break;
      }
      io::UdpSender* sender = sender_for(d.dst_port);
      if (sender == nullptr) continue;  // a port beyond the 64 planned: cannot happen with --port
      if (d.stamp_ns < prev_stamp) ++report.stamps_backwards;
      prev_stamp = std::max(prev_stamp, d.stamp_ns);
      std::int64_t now = rt::monotonic_ns();
      if (!shared && report.packets + report.send_failures == 0) clock.start_ns = now;
      if (!config_.fast) {
        // Never earlier than the datagram before: stamps that go backwards are sent at once.
        last_scheduled = std::max(last_scheduled, clock.offset_ns(pass, d.stamp_ns));
        wait_until(clock.start_ns + last_scheduled, stop);
        if (stop.load(std::memory_order_relaxed)) {
          interrupted = true;
          break;
        }
        now = rt::monotonic_ns();
        pacing.add(std::abs(now - (clock.start_ns + last_scheduled)));
      }
      if (faults_) {
        ++report.packets;
        report.bytes += d.payload.size();
        report.send_failures += faults_->offer(
            d.payload, static_cast<double>(d.stamp_ns - plan_.first_stamp_ns) * 1e-9, *sender);
      } else if (sender->send(d.payload)) {
        ++report.packets;
        report.bytes += d.payload.size();
      } else {
        ++report.send_failures;
      }
      last_send = now;
    }
    if (!reader->error().empty()) return rt::make_error(reader->error());
    if (faults_) report.send_failures += faults_->flush();
    if (!interrupted) ++report.passes;  // every datagram of the pass was sent
    if (stop.load(std::memory_order_relaxed)) {
      report.stopped = true;
      break;
    }
  }
  report.scheduled_ns = config_.fast ? 0 : last_scheduled;
  report.elapsed_ns = last_send - clock.start_ns;
  report.error_median_ns = pacing.median_ns();
  report.error_p99_ns = pacing.p99_ns();
  report.error_max_ns = pacing.max_ns();
  if (faults_) {
    report.faults = faults_->counts();
  }
  return report;
}

}  // namespace stac::replay

#include "replay/tcp_replay.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <utility>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/tcp_stream.hpp"
#include "rt/clock.hpp"

namespace stac::replay {
namespace {

constexpr int kPollSliceMs = 50;  // longest blocking poll: the stop flag's latency

io::TcpFilter from_port(std::uint16_t port) {
  io::TcpFilter f;
  f.src_port = port;
  return f;
}

// Reads one pass of the stream from `port`, calling on_chunk(bytes, stamp_ns) for each
// in-order chunk; false on a read error (reader's message in `error`).
template <typename OnChunk>
bool read_stream(const std::filesystem::path& capture, std::uint16_t port, OnChunk&& on_chunk,
                 std::string& error, io::TcpReassemblerCounters* counters = nullptr,
                 std::uint64_t* payload_segments = nullptr) {
  auto reader = io::PcapReader::open(capture, {}, from_port(port));
  if (!reader) {
    error = reader.error().message;
    return false;
  }
  io::TcpReassembler reassembler;
  io::TcpSegment s;
  std::span<const std::uint8_t> chunk;
  std::int64_t stamp = 0;
  while (reader->next_tcp(s)) {
    if (payload_segments && !s.payload.empty()) ++*payload_segments;
    stamp = s.stamp_ns;
    (void)reassembler.add(s);
    while (reassembler.next(chunk)) {
      if (!on_chunk(chunk, stamp)) return true;
    }
  }
  if (!reader->error().empty()) {
    error = reader->error();
    return false;
  }
  reassembler.finish();
  while (reassembler.next(chunk)) {
    if (!on_chunk(chunk, stamp)) return true;
  }
  if (counters) *counters = reassembler.counters();
  return true;
}

std::string ports_text(const std::vector<std::uint16_t>& ports) {
  std::string t;
  for (auto p : ports) t += (t.empty() ? "" : ", ") + std::to_string(p);
  return t.empty() ? "none" : t;
}

}  // namespace

rt::Result<std::vector<std::uint16_t>> TcpReplay::server_ports(
    const std::filesystem::path& capture) {
  auto reader = io::PcapReader::open(capture);
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  std::vector<std::uint16_t> syn_ack, lower;
  auto add = [](std::vector<std::uint16_t>& v, std::uint16_t p) {
    if (std::find(v.begin(), v.end(), p) == v.end() && v.size() < 64) v.push_back(p);
  };
  io::TcpSegment s;
  while (reader->next_tcp(s)) {
    if ((s.flags & (io::kTcpSyn | io::kTcpAck)) == (io::kTcpSyn | io::kTcpAck))
      add(syn_ack, s.src_port);
    if (!s.payload.empty() && s.src_port < s.dst_port) add(lower, s.src_port);
  }
  if (!reader->error().empty()) return rt::make_error(reader->error());
  auto& ports = syn_ack.empty() ? lower : syn_ack;
  std::sort(ports.begin(), ports.end());
  return ports;
}

rt::Result<TcpReplay> TcpReplay::open(const std::filesystem::path& capture,
                                      const TcpReplayConfig& config) {
  if (!(config.rate > 0.0) || !std::isfinite(config.rate)) {
    return rt::make_error("replay rate must be a number > 0 (1 = recorded pace)");
  }
  TcpReplay r;
  r.capture_ = capture;
  r.config_ = config;
  std::int64_t last = 0;
  std::string error;
  io::TcpReassemblerCounters counters;
  const bool ok = read_stream(
      capture, config.server_port,
      [&](std::span<const std::uint8_t> chunk, std::int64_t stamp) {
        if (r.plan_.bytes == 0) r.plan_.first_stamp_ns = stamp;
        r.plan_.bytes += chunk.size();
        last = std::max(last, stamp);
        return true;
      },
      error, &counters, &r.plan_.segments);
  if (!ok) return rt::make_error(error);
  if (r.plan_.bytes == 0) {
    auto ports = server_ports(capture);
    return rt::make_error(capture.string() + ": no TCP stream from port " +
                          std::to_string(config.server_port) +
                          " to serve (captured TCP server ports: " +
                          (ports ? ports_text(*ports) : ports.error().message) + ")");
  }
  r.plan_.span_ns = std::max<std::int64_t>(0, last - r.plan_.first_stamp_ns);
  r.plan_.pass_period_ns =
      r.plan_.span_ns + (r.plan_.segments > 1
                             ? r.plan_.span_ns / static_cast<std::int64_t>(r.plan_.segments - 1)
                             : 0);
  r.plan_.streams = counters.streams;
  r.plan_.retransmitted = counters.retransmitted;
  r.plan_.gaps = counters.gaps;
  r.plan_.gap_bytes = counters.gap_bytes;

  const std::uint16_t port = config.listen_port.value_or(config.server_port);
  const std::string where = "listening on " + config.listen_address + ":" + std::to_string(port);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (::inet_pton(AF_INET, config.listen_address.c_str(), &addr.sin_addr) != 1) {
    return rt::make_error(where + ": not an IPv4 address");
  }
  r.listen_fd_.reset(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!r.listen_fd_) return rt::make_error(where + ": socket: " + std::strerror(errno));
  const int on = 1;
  (void)::setsockopt(r.listen_fd_.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof(on));
  if (::bind(r.listen_fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0 ||
      ::listen(r.listen_fd_.get(), 4) != 0) {
    return rt::make_error(where + ": " + std::strerror(errno));
  }
  socklen_t len = sizeof(addr);
  (void)::getsockname(r.listen_fd_.get(), reinterpret_cast<sockaddr*>(&addr), &len);
  r.listen_port_ = ntohs(addr.sin_port);
  return r;
}

void TcpReplay::inject(const StreamFaultPlan& plan, std::int64_t zero_stamp_ns) {
  faults_.emplace(plan);
  faults_zero_ns_ = zero_stamp_ns;
}

void TcpReplay::accept_pending() noexcept {
  if (client_fd_) return;
  rt::UniqueFd fd(::accept4(listen_fd_.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC));
  if (!fd) return;  // none waiting (EAGAIN) or it went away already
  const int on = 1;
  (void)::setsockopt(fd.get(), IPPROTO_TCP, TCP_NODELAY, &on, sizeof(on));
  client_fd_ = std::move(fd);
  ++accepted_;
}

bool TcpReplay::wait_for_client(const std::atomic<bool>& stop) noexcept {
  while (!client_fd_) {
    if (stop.load(std::memory_order_relaxed)) return false;
    pollfd p{listen_fd_.get(), POLLIN, 0};
    (void)::poll(&p, 1, kPollSliceMs);
    accept_pending();
  }
  return true;
}

void TcpReplay::drop_client(TcpReplayReport& report) noexcept {
  client_fd_.reset();
  ++report.disconnects;
}

// Notices a client that closed or reset; bytes it sent are read and ignored.
void TcpReplay::check_client(TcpReplayReport& report) noexcept {
  if (!client_fd_) return;
  pollfd p{client_fd_.get(), POLLIN | POLLRDHUP, 0};
  if (::poll(&p, 1, 0) <= 0) return;
  if (p.revents & (POLLERR | POLLHUP | POLLRDHUP)) {
    drop_client(report);
    return;
  }
  std::array<std::uint8_t, 512> sink{};
  const ssize_t n = ::recv(client_fd_.get(), sink.data(), sink.size(), MSG_DONTWAIT);
  if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) drop_client(report);
}

bool TcpReplay::write_all(std::span<const std::uint8_t> chunk, const std::atomic<bool>& stop,
                          TcpReplayReport& report) noexcept {
  std::size_t done = 0;
  std::int64_t waited_since = rt::monotonic_ns();
  while (done < chunk.size()) {
    const ssize_t n = ::send(client_fd_.get(), chunk.data() + done, chunk.size() - done,
                             MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      report.bytes += static_cast<std::uint64_t>(n);
      waited_since = rt::monotonic_ns();
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      drop_client(report);
      return false;
    }
    if (stop.load(std::memory_order_relaxed)) return false;
    if (rt::monotonic_ns() - waited_since > std::int64_t{config_.stall_timeout_ms} * 1'000'000) {
      ++report.stalls;
      drop_client(report);
      return false;
    }
    pollfd p{client_fd_.get(), POLLOUT, 0};
    (void)::poll(&p, 1, kPollSliceMs);
  }
  return true;
}

rt::Result<TcpReplayReport> TcpReplay::run(const std::atomic<bool>& stop,
                                           const ReplayClock* shared) {
  TcpReplayReport report;
  PacingStats pacing;
  // A client accepted by wait_for_client() just before counts for this run.
  const std::uint64_t accepted_before = accepted_ - (client_fd_ ? 1 : 0);
  const ReplayClock clock = shared ? *shared
                                   : ReplayClock{rt::monotonic_ns(), plan_.first_stamp_ns,
                                                 plan_.pass_period_ns, config_.rate};
  std::int64_t last_write = clock.start_ns, last_scheduled = 0;
  for (std::uint64_t pass = 0; config_.loops == 0 || pass < config_.loops; ++pass) {
    bool interrupted = false;
    std::string error;
    auto serve = [&](std::span<const std::uint8_t> chunk, std::int64_t stamp) {
      if (stop.load(std::memory_order_relaxed)) {
        interrupted = true;
        return false;
      }
      std::int64_t error_ns = -1;
      if (!config_.fast) {
        // Never earlier than the chunk before (stamps that go backwards are sent at once).
        last_scheduled = std::max(last_scheduled, clock.offset_ns(pass, stamp));
        wait_until(clock.start_ns + last_scheduled, stop);
        if (stop.load(std::memory_order_relaxed)) {
          interrupted = true;
          return false;
        }
        error_ns = std::abs(rt::monotonic_ns() - (clock.start_ns + last_scheduled));
      }
      check_client(report);
      accept_pending();
      if (!client_fd_) {
        report.unserved_bytes += chunk.size();
        return true;
      }
      if (error_ns >= 0) pacing.add(error_ns);
      last_write = rt::monotonic_ns();
      if (!faults_) {
        if (write_all(chunk, stop, report)) ++report.segments;
        return true;
      }
      const double capture_s = static_cast<double>(stamp - faults_zero_ns_) * 1e-9;
      bool sent = false;
      for (std::size_t at = 0; at < chunk.size() && client_fd_;
           at += StreamFaultInjector::kMaxChunk) {
        bool disconnect = false;
        const auto piece = faults_->apply(
            chunk.subspan(at, std::min(StreamFaultInjector::kMaxChunk, chunk.size() - at)),
            capture_s, disconnect);
        if (disconnect) {  // the rest is due with no client connected
          drop_client(report);
          report.unserved_bytes += chunk.size() - at;
          break;
        }
        if (!piece.empty()) sent = write_all(piece, stop, report) || sent;
      }
      report.segments += sent ? 1 : 0;
      return true;
    };
    if (faults_) faults_->new_pass();
    if (!read_stream(capture_, config_.server_port, serve, error)) return rt::make_error(error);
    if (!interrupted) ++report.passes;
    if (stop.load(std::memory_order_relaxed)) {
      report.stopped = true;
      break;
    }
  }
  if (client_fd_) {  // end of stream for the client
    (void)::shutdown(client_fd_.get(), SHUT_WR);
    client_fd_.reset();
  }
  report.clients = accepted_ - accepted_before;
  report.scheduled_ns = config_.fast ? 0 : last_scheduled;
  report.elapsed_ns = last_write - clock.start_ns;
  report.error_median_ns = pacing.median_ns();
  report.error_p99_ns = pacing.p99_ns();
  report.error_max_ns = pacing.max_ns();
  if (faults_) report.faults = faults_->counts();
  return report;
}

}  // namespace stac::replay

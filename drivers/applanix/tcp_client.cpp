#include "drivers/applanix/tcp_client.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <utility>

#include "drivers/io/datagram.hpp"
#include "rt/clock.hpp"

namespace stac::applanix {
namespace {

constexpr std::int64_t kMs = 1'000'000;

int ms_until(std::int64_t deadline_ns, std::int64_t now_ns) noexcept {
  if (deadline_ns <= now_ns) return 0;
  return static_cast<int>(std::min<std::int64_t>((deadline_ns - now_ns + kMs - 1) / kMs, 1 << 30));
}

}  // namespace

rt::Result<TcpClient> TcpClient::open(const TcpClientConfig& config) {
  const std::string where = "Applanix TCP " + config.address + ":" + std::to_string(config.port);
  TcpClient c;
  if (!io::parse_ipv4(config.address.c_str(), c.address_)) {
    return rt::make_error(where + ": address '" + config.address +
                          "' is not an IPv4 address; set the POS computer's address (a.b.c.d)");
  }
  if (config.port == 0) return rt::make_error(where + ": port must be 1..65535");
  if (config.message_timeout_ms < 0)
    return rt::make_error("applanix tcp: message_timeout_ms must be >= 0 (0: never)");
  if (config.connect_timeout_ms < 1 || config.stall_timeout_ms < 1 ||
      config.initial_backoff_ms < 1 || config.max_backoff_ms < config.initial_backoff_ms) {
    return rt::make_error(where +
                          ": connect_timeout_ms, stall_timeout_ms and initial_backoff_ms "
                          "must be >= 1 and max_backoff_ms >= initial_backoff_ms");
  }
  c.config_ = config;
  c.wake_fd_.reset(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC));
  if (!c.wake_fd_) return rt::make_error(where + ": eventfd failed");
  return c;
}

void TcpClient::stop() noexcept {
  const std::uint64_t one = 1;
  (void)!::write(wake_fd_.get(), &one, sizeof(one));
}

bool TcpClient::wait_wake(int timeout_ms) noexcept {
  pollfd p{wake_fd_.get(), POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) > 0;
}

void TcpClient::disconnect(std::int64_t now_ns) noexcept {
  fd_.reset();
  backoff_ms_ = config_.initial_backoff_ms;
  next_attempt_ns_ = now_ns + backoff_ms_ * kMs;
}

bool TcpClient::try_connect(std::int64_t now_ns) noexcept {
  rt::UniqueFd fd(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  bool ok = fd.valid();
  if (ok) {
    const int on = 1;
    (void)::setsockopt(fd.get(), IPPROTO_TCP, TCP_NODELAY, &on, sizeof(on));
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(config_.port);
    addr.sin_addr.s_addr = htonl(address_);
    if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
      ok = errno == EINPROGRESS;
      if (ok) {
        pollfd p[2] = {{fd.get(), POLLOUT, 0}, {wake_fd_.get(), POLLIN, 0}};
        ok = ::poll(p, 2, config_.connect_timeout_ms) > 0 && (p[0].revents & POLLOUT) != 0;
        int error = 0;
        socklen_t len = sizeof(error);
        ok = ok && ::getsockopt(fd.get(), SOL_SOCKET, SO_ERROR, &error, &len) == 0 && error == 0;
      }
    }
  }
  if (ok) {
    fd_ = std::move(fd);
    ++counters_.connects;
    backoff_ms_ = 0;
    last_data_ns_ = rt::monotonic_ns();
    last_message_ns_ = last_data_ns_;
    return true;
  }
  ++counters_.connect_failures;
  backoff_ms_ = backoff_ms_ == 0 ? config_.initial_backoff_ms
                                 : std::min(backoff_ms_ * 2, config_.max_backoff_ms);
  next_attempt_ns_ = now_ns + backoff_ms_ * kMs;
  return false;
}

void TcpClient::note_message() noexcept {
  last_message_ns_ = rt::monotonic_ns();
}

int TcpClient::receive(std::span<std::uint8_t> out, int timeout_ms) noexcept {
  const std::int64_t deadline = rt::monotonic_ns() + std::max(timeout_ms, 0) * kMs;
  if (out.empty()) return 0;
  out = out.first(std::min<std::size_t>(out.size(), 1 << 30));
  while (true) {
    std::int64_t now = rt::monotonic_ns();
    if (!fd_) {
      if (now < next_attempt_ns_) {
        if (now >= deadline) return 0;
        if (wait_wake(ms_until(std::min(next_attempt_ns_, deadline), now))) return kStopped;
        continue;
      }
      if (wait_wake(0)) return kStopped;
      if (!try_connect(now)) {
        if (wait_wake(0)) return kStopped;
        continue;
      }
      now = rt::monotonic_ns();
    }
    if (config_.message_timeout_ms > 0 &&
        now - last_message_ns_ > std::int64_t{config_.message_timeout_ms} * kMs) {
      ++counters_.no_message;
      disconnect(now);
      continue;
    }
    const std::int64_t stall_at = last_data_ns_ + config_.stall_timeout_ms * kMs;
    pollfd p[2] = {{fd_.get(), POLLIN, 0}, {wake_fd_.get(), POLLIN, 0}};
    const int rc = ::poll(p, 2, ms_until(std::min(stall_at, deadline), now));
    if (rc < 0 && errno != EINTR) return 0;
    if (p[1].revents != 0) return kStopped;
    now = rt::monotonic_ns();
    if (rc > 0 && p[0].revents != 0) {
      const ssize_t n = ::recv(fd_.get(), out.data(), out.size(), 0);
      if (n > 0) {
        last_data_ns_ = now;
        counters_.bytes += static_cast<std::uint64_t>(n);
        return static_cast<int>(n);
      }
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      ++counters_.disconnects;  // orderly close (0) or a socket error
      disconnect(now);
      continue;
    }
    if (now >= stall_at) {
      ++counters_.stalls;
      disconnect(now);
      continue;
    }
    if (now >= deadline) return 0;
  }
}

}  // namespace stac::applanix

#include "drivers/io/udp_receiver.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "rt/clock.hpp"

namespace stac::io {
namespace {

constexpr std::size_t kControlSpace =
    CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t));

std::string where(const UdpReceiverConfig& c) {
  return "UDP " + c.bind_address + ":" + std::to_string(c.port);
}

}  // namespace

rt::Result<UdpReceiver> UdpReceiver::open(const UdpReceiverConfig& config) {
  UdpReceiver r;
  if (config.batch < 1 || config.max_payload < 1 || config.max_payload > 65535) {
    return rt::make_error(where(config) + ": batch must be >= 1 and max_payload 1..65535");
  }
  std::uint32_t bind_ip = 0;
  if (!parse_ipv4(config.bind_address.c_str(), bind_ip)) {
    return rt::make_error(where(config) + ": '" + config.bind_address + "' is not an IPv4 address");
  }
  if (!config.sender_address.empty()) {
    if (!parse_ipv4(config.sender_address.c_str(), r.sender_)) {
      return rt::make_error(where(config) + ": sender filter '" + config.sender_address +
                            "' is not an IPv4 address");
    }
    r.filter_sender_ = true;
  }
  r.fd_.reset(::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!r.fd_) return rt::make_error(where(config) + ": socket: " + std::strerror(errno));
  int size = config.receive_buffer_bytes;
  (void)::setsockopt(r.fd_.get(), SOL_SOCKET, SO_RCVBUF, &size, sizeof(size));
  socklen_t len = sizeof(r.granted_rcvbuf_);
  (void)::getsockopt(r.fd_.get(), SOL_SOCKET, SO_RCVBUF, &r.granted_rcvbuf_, &len);
  const int on = 1;
  (void)::setsockopt(r.fd_.get(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on));
  (void)::setsockopt(r.fd_.get(), SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(config.port);
  addr.sin_addr.s_addr = htonl(bind_ip);
  if (::bind(r.fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int e = errno;
    return rt::make_error(where(config) + ": cannot bind: " + std::strerror(e) +
                          (e == EADDRINUSE      ? " (another program, e.g. a second stac or a ROS "
                                                  "driver, listens there; stop it or change the port)"
                           : e == EADDRNOTAVAIL ? " (no interface has that address)"
                                                : ""));
  }
  sockaddr_in bound{};
  len = sizeof(bound);
  (void)::getsockname(r.fd_.get(), reinterpret_cast<sockaddr*>(&bound), &len);
  r.port_ = ntohs(bound.sin_port);
  r.wake_fd_.reset(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC));
  if (!r.wake_fd_) return rt::make_error(where(config) + ": eventfd: " + std::strerror(errno));

  r.batch_ = config.batch;
  r.max_payload_ = static_cast<std::size_t>(config.max_payload);
  const auto n = static_cast<std::size_t>(config.batch);
  r.buffers_.assign(n * (r.max_payload_ + 1), 0);  // +1 byte tells an oversize datagram
  r.control_.assign(n * kControlSpace, 0);
  r.messages_.assign(n, mmsghdr{});
  r.iovecs_.assign(n * sizeof(iovec), std::byte{0});
  r.addresses_.assign(n * sizeof(sockaddr_in), std::byte{0});
  return r;
}

UdpReceiver::UdpReceiver(UdpReceiver&&) noexcept = default;
UdpReceiver& UdpReceiver::operator=(UdpReceiver&&) noexcept = default;
UdpReceiver::~UdpReceiver() = default;

void UdpReceiver::stop() noexcept {
  const std::uint64_t one = 1;
  if (wake_fd_) (void)!::write(wake_fd_.get(), &one, sizeof(one));
}

int UdpReceiver::receive(std::span<Datagram> out, int timeout_ms) noexcept {
  if (out.empty()) return 0;
  pollfd fds[2] = {{fd_.get(), POLLIN, 0}, {wake_fd_.get(), POLLIN, 0}};
  const int ready = ::poll(fds, 2, timeout_ms);
  if (ready < 0) return errno == EINTR ? 0 : kError;
  if ((fds[1].revents & POLLIN) != 0) return kStopped;  // the eventfd stays readable: sticky
  if (ready == 0 || (fds[0].revents & POLLIN) == 0) return 0;

  const auto n =
      static_cast<unsigned>(std::min<std::size_t>(out.size(), static_cast<std::size_t>(batch_)));
  auto* iov = reinterpret_cast<iovec*>(iovecs_.data());
  auto* addr = reinterpret_cast<sockaddr_in*>(addresses_.data());
  for (unsigned i = 0; i < n; ++i) {
    iov[i].iov_base = buffers_.data() + i * (max_payload_ + 1);
    iov[i].iov_len = max_payload_ + 1;
    msghdr& h = messages_[i].msg_hdr;
    h = msghdr{};
    h.msg_name = &addr[i];
    h.msg_namelen = sizeof(sockaddr_in);
    h.msg_iov = &iov[i];
    h.msg_iovlen = 1;
    h.msg_control = control_.data() + i * kControlSpace;
    h.msg_controllen = kControlSpace;
  }
  const int got = ::recvmmsg(fd_.get(), messages_.data(), n, MSG_DONTWAIT, nullptr);
  if (got < 0) return (errno == EAGAIN || errno == EINTR) ? 0 : kError;
  int kept = 0;
  for (int i = 0; i < got; ++i) {
    const msghdr& h = messages_[static_cast<std::size_t>(i)].msg_hdr;
    const std::size_t size = messages_[static_cast<std::size_t>(i)].msg_len;
    std::int64_t stamp = 0;
    for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr;
         c = CMSG_NXTHDR(const_cast<msghdr*>(&h), c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
        stamp = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
      } else if (c->cmsg_type == SO_RXQ_OVFL) {
        std::uint32_t drops = 0;
        std::memcpy(&drops, CMSG_DATA(c), sizeof(drops));
        counters_.kernel_drops = drops;  // cumulative for the socket
      }
    }
    const sockaddr_in& from = addr[i];
    if (filter_sender_ && ntohl(from.sin_addr.s_addr) != sender_) {
      ++counters_.filtered_sender;
      continue;
    }
    if (size > max_payload_ || (h.msg_flags & MSG_TRUNC) != 0) {
      ++counters_.truncated;
      continue;
    }
    if (stamp == 0) {
      stamp = rt::realtime_ns();
      ++counters_.no_kernel_stamp;
    }
    Datagram& d = out[static_cast<std::size_t>(kept++)];
    d.payload = {buffers_.data() + static_cast<std::size_t>(i) * (max_payload_ + 1), size};
    d.stamp_ns = stamp;
    d.src_ip = ntohl(from.sin_addr.s_addr);
    d.src_port = ntohs(from.sin_port);
    d.dst_ip = 0;
    d.dst_port = port_;
  }
  counters_.received += static_cast<std::uint64_t>(kept);
  return kept;
}

rt::Result<UdpSender> UdpSender::open(const std::string& address, std::uint16_t port) {
  std::uint32_t ip = 0;
  if (!parse_ipv4(address.c_str(), ip))
    return rt::make_error("'" + address + "' is not an IPv4 address");
  UdpSender s;
  s.fd_.reset(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  if (!s.fd_) return rt::make_error(std::string("socket: ") + std::strerror(errno));
  const int on = 1;
  (void)::setsockopt(s.fd_.get(), SOL_SOCKET, SO_BROADCAST, &on, sizeof(on));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(ip);
  if (::connect(s.fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    return rt::make_error("UDP " + address + ":" + std::to_string(port) + ": " +
                          std::strerror(errno));
  }
  return s;
}

bool UdpSender::send(std::span<const std::uint8_t> payload) noexcept {
  return ::send(fd_.get(), payload.data(), payload.size(), 0) ==
         static_cast<ssize_t>(payload.size());
}

}  // namespace stac::io

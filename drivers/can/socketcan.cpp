#include "drivers/can/socketcan.hpp"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "rt/clock.hpp"

namespace stac::can {
namespace {

static_assert(sizeof(can_frame) == 16 && CAN_MTU == 16, "classic SocketCAN frame is 16 bytes");
static_assert(CANFD_MTU == 72, "CAN FD SocketCAN frame is 72 bytes");

std::string errno_text(int e) {
  return std::string(std::strerror(e)) + ", errno " + std::to_string(e);
}

}  // namespace

rt::Result<unsigned> interface_index(const std::string& name) {
  if (name.empty() || name.size() >= IFNAMSIZ) {
    return rt::make_error("SocketCAN: interface name '" + name + "' must have 1.." +
                          std::to_string(IFNAMSIZ - 1) + " characters");
  }
  const unsigned index = if_nametoindex(name.c_str());
  if (index == 0) {
    return rt::make_error("SocketCAN: no network interface '" + name +
                          "' (list them with `ip link show`; a virtual bus for tests: "
                          "`ip link add dev vcan0 type vcan && ip link set vcan0 up`)");
  }
  return index;
}

rt::Result<SocketCanReader> SocketCanReader::open(const SocketCanConfig& config) {
  const std::string& name = config.interface;
  auto found = interface_index(name);
  if (!found) return rt::Unexpected<rt::Error>{found.error()};
  const unsigned index = *found;
  rt::UniqueFd fd(::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW));
  if (!fd) {
    const int e = errno;
    if (e == EAFNOSUPPORT) {
      return rt::make_error("SocketCAN: this kernel has no AF_CAN (" + errno_text(e) +
                            "): load the can and can_raw modules, or use a gs_usb/candleLight "
                            "adapter through libusb (can.transport: gs_usb)");
    }
    return rt::make_error("SocketCAN: socket(AF_CAN) failed: " + errno_text(e));
  }
  std::vector<can_filter> filters;
  for (const CanIdFilter& f : config.filters) {
    can_filter k{};
    if (f.extended) {
      k.can_id = (f.id & CAN_EFF_MASK) | CAN_EFF_FLAG;
      k.can_mask = CAN_EFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
    } else {
      k.can_id = f.id & CAN_SFF_MASK;
      k.can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
    }
    filters.push_back(k);
  }
  if (!filters.empty() &&
      setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                 static_cast<socklen_t>(filters.size() * sizeof(can_filter))) != 0) {
    const int e = errno;
    return rt::make_error("SocketCAN: " + name + ": CAN_RAW_FILTER refused: " + errno_text(e));
  }
  const int one = 1;
  setsockopt(fd.get(), SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof(one));  // best effort: a counter only
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int e = errno;
    return rt::make_error("SocketCAN: cannot bind to '" + name +
                          "' (is it a CAN interface and up? " + "`ip link set " + name +
                          " up`): " + errno_text(e));
  }
  return adopt(fd.release());
}

rt::Result<SocketCanReader> SocketCanReader::adopt(int fd) {
  if (fd < 0) return rt::make_error("SocketCAN: adopt() needs an open descriptor");
  SocketCanReader r;
  r.fd_.reset(fd);
  const int one = 1;
  setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof(one));  // absent: counted per frame
  r.wake_fd_.reset(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  if (!r.wake_fd_) return rt::make_error("SocketCAN: eventfd failed: " + errno_text(errno));
  return r;
}

void SocketCanReader::stop() noexcept {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(wake_fd_.get(), &one, sizeof(one));
}

int SocketCanReader::read(std::span<Frame> out, int timeout_ms) noexcept {
  pollfd fds[2] = {{wake_fd_.get(), POLLIN, 0}, {fd_.get(), POLLIN, 0}};
  int ready = 0;
  do {
    ready = ::poll(fds, 2, timeout_ms);
  } while (ready < 0 && errno == EINTR);
  if (ready < 0) return kError;
  if ((fds[0].revents & POLLIN) != 0) return kStopped;
  if (ready == 0) return 0;
  if ((fds[1].revents & (POLLERR | POLLNVAL)) != 0 && (fds[1].revents & POLLIN) == 0) return kError;

  int count = 0;
  while (static_cast<std::size_t>(count) < out.size()) {
    alignas(can_frame) std::uint8_t record[CANFD_MTU + 8];
    alignas(cmsghdr)
        std::uint8_t control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
    iovec iov{record, sizeof(record)};
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof(control);
    const ssize_t n = ::recvmsg(fd_.get(), &msg, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      if (errno == EINTR) continue;
      if (count > 0) break;
      return errno == ENETDOWN || errno == ENODEV ? kClosed : kError;
    }
    if (n == 0) {  // orderly shutdown of a stream/seqpacket peer
      if (count > 0) break;
      return kClosed;
    }
    if (n == CANFD_MTU && (msg.msg_flags & MSG_TRUNC) == 0) {
      ++counters_.can_fd;
      continue;
    }
    if (n != CAN_MTU || (msg.msg_flags & MSG_TRUNC) != 0) {
      ++counters_.bad_size;
      continue;
    }
    can_frame cf{};
    std::memcpy(&cf, record, sizeof(cf));
    Frame& f = out[static_cast<std::size_t>(count)];
    f = Frame{};
    from_socketcan_id(cf.can_id, f);
    f.dlc = cf.len > kMaxDataBytes ? kMaxDataBytes : cf.len;
    std::memcpy(f.data.data(), cf.data, kMaxDataBytes);
    bool stamped = false;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SO_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
        f.stamp_ns = ts.tv_sec * 1'000'000'000LL + ts.tv_nsec;
        stamped = true;
      } else if (c->cmsg_type == SO_RXQ_OVFL) {
        std::uint32_t dropped = 0;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof(dropped));
        counters_.kernel_drops = dropped;  // the kernel reports a running total
      }
    }
    if (!stamped) {
      f.stamp_ns = rt::realtime_ns();
      ++counters_.no_kernel_stamp;
    }
    ++counters_.frames;
    ++count;
  }
  return count;
}

bool SocketCanReader::write(const Frame& frame) noexcept {
  can_frame cf{};
  cf.can_id = to_socketcan_id(frame);
  cf.len = frame.dlc > kMaxDataBytes ? kMaxDataBytes : frame.dlc;
  std::memcpy(cf.data, frame.data.data(), kMaxDataBytes);
  ssize_t n = 0;
  do {
    n = ::send(fd_.get(), &cf, sizeof(cf), MSG_NOSIGNAL);
  } while (n < 0 && errno == EINTR);
  return n == static_cast<ssize_t>(sizeof(cf));
}

}  // namespace stac::can

// A SOCK_SEQPACKET socketpair keeps each 16-byte struct can_frame a record, as a raw CAN socket
// does (this kernel has no AF_CAN): a SocketCanReader gets one end, the test writes hand-made
// records into the other.
#pragma once

#include <gtest/gtest.h>
#include <linux/can.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <utility>

#include "drivers/can/socketcan.hpp"

namespace stac::testing {

struct SocketCanPair {
  can::SocketCanReader reader;
  int peer;
};

inline SocketCanPair make_socketcan_pair() {
  int fds[2];
  EXPECT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0) << std::strerror(errno);
  auto r = can::SocketCanReader::adopt(fds[0]);
  EXPECT_TRUE(r);
  return {std::move(r).value(), fds[1]};
}

inline void send_record(int fd, const void* bytes, std::size_t size) {
  ASSERT_EQ(::send(fd, bytes, size, 0), static_cast<ssize_t>(size)) << std::strerror(errno);
}

// One classic frame: `can_id` with SocketCAN's flag bits (CAN_EFF_FLAG for a 29-bit id).
inline void send_frame(int fd, std::uint32_t can_id, std::initializer_list<std::uint8_t> data) {
  can_frame f{};
  f.can_id = can_id;
  for (const std::uint8_t b : data) f.data[f.len++] = b;
  send_record(fd, &f, sizeof(f));
}

}  // namespace stac::testing

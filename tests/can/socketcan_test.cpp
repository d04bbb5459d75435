#include "drivers/can/socketcan.hpp"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <thread>
#include <type_traits>

#include "can/socketcan_pair.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::can {
namespace {

using stac::testing::send_record;

// Move-only; a move never throws (the descriptors go with the object).
static_assert(std::is_nothrow_move_constructible_v<SocketCanReader> &&
              std::is_nothrow_move_assignable_v<SocketCanReader> &&
              !std::is_copy_constructible_v<SocketCanReader>);

TEST(SocketCanReader, ReadsHandMadeCanFrameRecordsWithStamps) {
  auto p = stac::testing::make_socketcan_pair();
  can_frame a{};
  a.can_id = 0x1A0;
  a.len = 2;
  a.data[0] = 0x0E;
  a.data[1] = 0x10;
  can_frame b{};
  b.can_id = 0x18FEF1FE | CAN_EFF_FLAG;
  b.len = 8;
  for (int i = 0; i < 8; ++i) b.data[i] = static_cast<std::uint8_t>(0xA0 + i);
  can_frame c{};
  c.can_id = 0x7FF | CAN_RTR_FLAG;
  send_record(p.peer, &a, sizeof(a));
  send_record(p.peer, &b, sizeof(b));
  send_record(p.peer, &c, sizeof(c));
  std::array<Frame, 8> out;
  const int n = p.reader.read(out, 1000);
  ASSERT_EQ(n, 3);
  EXPECT_EQ(out[0].id, 0x1A0u);
  EXPECT_FALSE(out[0].extended);
  EXPECT_EQ(out[0].dlc, 2);
  EXPECT_EQ(out[0].data[1], 0x10);
  EXPECT_EQ(out[1].id, 0x18FEF1FEu);
  EXPECT_TRUE(out[1].extended);
  EXPECT_EQ(out[1].data[7], 0xA7);
  EXPECT_TRUE(out[2].remote);
  EXPECT_EQ(out[2].id, 0x7FFu);
  for (int i = 0; i < 3; ++i)
    EXPECT_GT(out[static_cast<std::size_t>(i)].stamp_ns, 1'600'000'000'000'000'000);
  // the kernel stamps AF_UNIX datagrams too when SO_TIMESTAMPNS is on
  EXPECT_EQ(p.reader.counters().no_kernel_stamp, 0u);
  EXPECT_LE(out[0].stamp_ns, out[2].stamp_ns);
  EXPECT_EQ(p.reader.counters().frames, 3u);
  ::close(p.peer);
}

TEST(SocketCanReader, CanFdAndOddSizedRecordsAreCountedAndSkipped) {
  auto p = stac::testing::make_socketcan_pair();
  canfd_frame fd{};
  fd.can_id = 0x100;
  fd.len = 12;
  const std::uint8_t odd[10] = {};
  can_frame ok{};
  ok.can_id = 0x200;
  ok.len = 1;
  ok.data[0] = 0x42;
  send_record(p.peer, &fd, sizeof(fd));
  send_record(p.peer, odd, sizeof(odd));
  send_record(p.peer, &ok, sizeof(ok));
  std::array<Frame, 4> out;
  int got = 0;
  for (int tries = 0; tries < 3 && got == 0; ++tries) got = p.reader.read(out, 1000);
  ASSERT_EQ(got, 1);
  EXPECT_EQ(out[0].id, 0x200u);
  EXPECT_EQ(out[0].data[0], 0x42);
  EXPECT_EQ(p.reader.counters().can_fd, 1u);
  EXPECT_EQ(p.reader.counters().bad_size, 1u);
  ::close(p.peer);
}

TEST(SocketCanReader, TimeoutStopAndPeerClose) {
  auto p = stac::testing::make_socketcan_pair();
  std::array<Frame, 4> out;
  EXPECT_EQ(p.reader.read(out, 10), 0);  // nothing there: timeout
  std::thread stopper([&p] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    p.reader.stop();
  });
  EXPECT_EQ(p.reader.read(out, -1), SocketCanReader::kStopped);  // would block forever otherwise
  stopper.join();
  EXPECT_EQ(p.reader.read(out, 0), SocketCanReader::kStopped);  // and stays stopped
  auto q = stac::testing::make_socketcan_pair();
  ::close(q.peer);
  EXPECT_EQ(q.reader.read(out, 1000), SocketCanReader::kClosed);
}

TEST(SocketCanReader, WriteSendsOneRecordAndReadAllocatesNothing) {
  static_assert(noexcept(std::declval<SocketCanReader&>().read(std::span<Frame>{}, 0)));
  auto p = stac::testing::make_socketcan_pair();
  Frame f;
  f.id = 0x123;
  f.dlc = 3;
  f.data = {1, 2, 3};
  ASSERT_TRUE(p.reader.write(f));
  can_frame got{};
  ASSERT_EQ(::recv(p.peer, &got, sizeof(got), 0), 16);
  EXPECT_EQ(got.can_id, 0x123u);
  EXPECT_EQ(got.len, 3);
  EXPECT_EQ(got.data[2], 3);
  for (int i = 0; i < 50; ++i) send_record(p.peer, &got, sizeof(got));
  std::array<Frame, 64> out;
  rt::testing::AllocationCounter counter;
  int total = 0;
  while (total < 50) {
    const int n = p.reader.read(out, 1000);
    if (n <= 0) break;
    total += n;
  }
  counter.stop();
  EXPECT_EQ(total, 50);
  EXPECT_EQ(counter.allocations(), 0u);
  ::close(p.peer);
}

TEST(SocketCanReader, OpeningAMissingInterfaceNamesIt) {
  const auto r = SocketCanReader::open({"stacnocan0", {}});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no network interface 'stacnocan0'"), std::string::npos)
      << r.error().message;
  const auto long_name = SocketCanReader::open({"a_name_longer_than_ifnamsiz", {}});
  ASSERT_FALSE(long_name);
  EXPECT_NE(long_name.error().message.find("must have 1..15 characters"), std::string::npos);
}

// The one test that needs the kernel's CAN stack: a real raw socket on vcan0 with a kernel filter.
TEST(SocketCanReader, RealVcanSocketFiltersAndStamps) {
  const int probe = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (probe < 0 && errno == EAFNOSUPPORT) {
    GTEST_SKIP()
        << "SKIPPED: AF_CAN is unavailable on this kernel (socket(AF_CAN) fails with errno 97, "
           "EAFNOSUPPORT); the read path is tested through a SOCK_SEQPACKET socketpair instead";
  }
  ASSERT_GE(probe, 0) << std::strerror(errno);
  ::close(probe);
  if (if_nametoindex("vcan0") == 0) {
    GTEST_SKIP() << "SKIPPED: AF_CAN exists but vcan0 does not: "
                    "`ip link add dev vcan0 type vcan && ip link set vcan0 up` to run this test";
  }
  auto reader = SocketCanReader::open({"vcan0", {{0x1A0, false}}});
  ASSERT_TRUE(reader) << reader.error().message;
  auto sender = SocketCanReader::open({"vcan0", {}});
  ASSERT_TRUE(sender) << sender.error().message;
  Frame other;
  other.id = 0x1A1;
  other.dlc = 1;
  Frame wanted;
  wanted.id = 0x1A0;
  wanted.dlc = 2;
  wanted.data = {0x0E, 0x10};
  ASSERT_TRUE(sender->write(other));
  ASSERT_TRUE(sender->write(wanted));
  std::array<Frame, 4> out;
  const int n = reader->read(out, 1000);
  ASSERT_EQ(n, 1);  // 0x1A1 filtered out by the kernel
  EXPECT_EQ(out[0].id, 0x1A0u);
  EXPECT_EQ(out[0].data[1], 0x10);
  EXPECT_EQ(reader->counters().no_kernel_stamp, 0u);
}

}  // namespace
}  // namespace stac::can

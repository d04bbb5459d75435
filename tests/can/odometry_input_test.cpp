#include "drivers/can/odometry_input.hpp"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "can/shipped_decoder.hpp"
#include "can/socketcan_pair.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::can {
namespace {

// A reader over a socketpair has no kernel filter: like a gs_usb adapter it hands over the whole
// bus, so the user-space filter of the signal map is what keeps the other ids out.
TEST(OdometryInput, MappedFramesBecomeUpdatesAndTheOtherIdsAreDroppedAndCounted) {
  auto p = testing::make_socketcan_pair();
  OdometryInput<SocketCanReader> in(std::move(p.reader), testing::shipped_decoder());
  testing::send_frame(p.peer, testing::kSpeedId, testing::kTenMetresPerSecond);
  testing::send_frame(p.peer, 0x123, {1, 2, 3});                         // not in the DBC
  testing::send_frame(p.peer, 0x18FEF1FE | CAN_EFF_FLAG, {0, 0, 0, 0});  // in the DBC, not mapped
  testing::send_frame(p.peer, testing::kSpeedId | CAN_EFF_FLAG,
                      testing::kTenMetresPerSecond);               // 29-bit: another message
  testing::send_frame(p.peer, testing::kYawRateId, {0xFF, 0xFE});  // -2.57 deg/s
  std::vector<OdometryUpdate> got;
  for (int tries = 0; tries < 5 && in.counters().frames < 5; ++tries) {
    ASSERT_EQ(in.read(1000, [&](const OdometryUpdate& u) { got.push_back(u); }), InputEvent::kRead);
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_TRUE(got[0].has_speed);
  EXPECT_NEAR(got[0].speed_mps, 10.0, 1e-12);
  EXPECT_TRUE(got[1].has_yaw_rate);
  EXPECT_NEAR(got[1].yaw_rate_dps, -2.57, 1e-12);
  EXPECT_GT(got[0].stamp_ns, 0);  // the transport's receive stamp
  const CanInputCounters c = in.counters();
  EXPECT_EQ(c.frames, 5u);
  EXPECT_EQ(c.updates, 2u);
  EXPECT_EQ(c.not_mapped, 3u);
  EXPECT_EQ(c.read_errors, 0u);
  ::close(p.peer);
}

TEST(OdometryInput, TimeoutStopAndPeerCloseAreTheirOwnEvents) {
  auto p = testing::make_socketcan_pair();
  OdometryInput<SocketCanReader> in(std::move(p.reader), testing::shipped_decoder());
  int updates = 0;
  const auto count = [&](const OdometryUpdate&) { ++updates; };
  EXPECT_EQ(in.read(10, count), InputEvent::kRead);  // nothing there: a timeout is a read
  std::thread stopper([&in] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    in.stop();
  });
  EXPECT_EQ(in.read(-1, count), InputEvent::kStopped);  // would block forever otherwise
  stopper.join();
  auto q = testing::make_socketcan_pair();
  OdometryInput<SocketCanReader> closed(std::move(q.reader), testing::shipped_decoder());
  ::close(q.peer);  // what the kernel reports as ENETDOWN/ENODEV when the interface goes away
  EXPECT_EQ(closed.read(1000, count), InputEvent::kGone);
  EXPECT_EQ(updates, 0);
  ::close(p.peer);
}

TEST(OdometryInput, ReadingAndDecodingAllocateNothing) {
  auto p = testing::make_socketcan_pair();
  OdometryInput<SocketCanReader> in(std::move(p.reader), testing::shipped_decoder(), 16);
  for (int i = 0; i < 50; ++i)
    testing::send_frame(p.peer, i % 2 == 0 ? testing::kSpeedId : 0x321,
                        testing::kTenMetresPerSecond);
  double sum = 0;
  rt::testing::AllocationCounter counter;
  while (in.counters().frames < 50) {
    if (in.read(1000, [&](const OdometryUpdate& u) { sum += u.speed_mps; }) != InputEvent::kRead)
      break;
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_NEAR(sum, 250.0, 1e-9);  // 25 speed frames of 10 m/s
  EXPECT_EQ(in.counters().not_mapped, 25u);
  static_assert(noexcept(in.read(0, [](const OdometryUpdate&) noexcept {})));
  ::close(p.peer);
}

// The transport traits: which read result ends the input, and where each driver counter goes.
TEST(TransportTraits, EachDriversEndAndDropCountersMapToTheCommonCauses) {
  static_assert(TransportTraits<GsUsbDevice>::kGone == GsUsbDevice::kError);  // device unplugged
  static_assert(TransportTraits<SocketCanReader>::kGone == SocketCanReader::kClosed);
  static_assert(TransportTraits<SocketCanReader>::kGone != SocketCanReader::kError);  // retried
  CanInputCounters g;
  TransportTraits<GsUsbDevice>::count(
      {.frames = 10, .echoes = 1, .truncated = 2, .can_fd = 3, .other_channel = 4, .overflows = 5},
      g);
  EXPECT_EQ(g, (CanInputCounters{
                   .frames = 10, .overflows = 5, .can_fd = 3, .malformed = 2, .other_channel = 4}));
  CanInputCounters s;
  TransportTraits<SocketCanReader>::count(
      {.frames = 20, .can_fd = 6, .bad_size = 7, .kernel_drops = 8, .no_kernel_stamp = 9}, s);
  EXPECT_EQ(s, (CanInputCounters{.frames = 20, .kernel_drops = 8, .can_fd = 6, .malformed = 7}));
}

}  // namespace
}  // namespace stac::can

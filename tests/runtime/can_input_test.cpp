// stac run's CAN thread loop and read step, driven through a socketpair-backed SocketCAN reader:
// the same template code the gs_usb thread runs over a GsUsbDevice.
#include "runtime/can_input.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <thread>

#include "can/shipped_decoder.hpp"
#include "can/socketcan_pair.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::runtime {
namespace {

using Input = can::OdometryInput<can::SocketCanReader>;

constexpr std::size_t kCan = 2;                      // the watchdog index, as in stac run
constexpr std::int64_t kTimeoutNs = 60'000'000'000;  // never stale within a test

struct Fixture {
  testing::SocketCanPair pair = testing::make_socketcan_pair();
  Input input{std::move(pair.reader), testing::shipped_decoder()};
  rt::Watchdog watchdog;
  CanCounterCells cells;
  CanReport report{watchdog, kCan, cells};
  Fixture() { watchdog.start({0, 0, kTimeoutNs, 0}, rt::monotonic_ns()); }
  ~Fixture() {
    if (pair.peer >= 0) ::close(pair.peer);
  }
  rt::InputState can_state() const { return watchdog.status(kCan, rt::monotonic_ns()).state; }
};

TEST(CanThread, UpdatesReachTheRingTheWatchdogAndTheCellsAndAGoneBusIsMarkedLost) {
  Fixture f;
  rt::SpscRing<can::OdometryUpdate> ring(8);
  auto loop =
      std::async(std::launch::async, [&] { return read_can_until_end(f.input, ring, f.report); });
  testing::send_frame(f.pair.peer, testing::kSpeedId, testing::kTenMetresPerSecond);
  testing::send_frame(f.pair.peer, 0x123, {1});  // not mapped: dropped, counted
  testing::send_frame(f.pair.peer, testing::kYawRateId, {0xFF, 0xFE});
  std::vector<can::OdometryUpdate> got;
  for (int i = 0; i < 500 && got.size() < 2; ++i) {
    for (can::OdometryUpdate u; ring.try_pop(u);) got.push_back(u);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_NEAR(got[0].speed_mps, 10.0, 1e-12);
  EXPECT_NEAR(got[1].yaw_rate_dps, -2.57, 1e-12);
  const rt::InputStatus beat = f.watchdog.status(kCan, rt::monotonic_ns());
  EXPECT_TRUE(beat.seen);
  EXPECT_EQ(beat.state, rt::InputState::kOk);
  ::close(f.pair.peer);  // the bus goes away
  f.pair.peer = -1;
  ASSERT_EQ(loop.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  EXPECT_EQ(loop.get(), can::InputEvent::kGone);
  EXPECT_EQ(f.can_state(), rt::InputState::kLost);
  const can::CanInputCounters c = f.cells.load();  // what the publisher reads
  EXPECT_EQ(c.frames, 3u);
  EXPECT_EQ(c.updates, 2u);
  EXPECT_EQ(c.not_mapped, 1u);
  EXPECT_EQ(f.cells.ring_full.load(), 0u);
}

TEST(CanThread, AFullRingDropsTheNewestUpdatesAndCountsThem) {
  Fixture f;
  rt::SpscRing<can::OdometryUpdate> ring(1);
  testing::send_frame(f.pair.peer, testing::kSpeedId, testing::kTenMetresPerSecond);
  testing::send_frame(f.pair.peer, testing::kSpeedId, {0, 0});  // 0 m/s
  testing::send_frame(f.pair.peer, testing::kYawRateId, {0xFF, 0xFE});
  ::close(f.pair.peer);  // the loop reads the three, then ends
  f.pair.peer = -1;
  EXPECT_EQ(read_can_until_end(f.input, ring, f.report), can::InputEvent::kGone);
  EXPECT_EQ(f.cells.ring_full.load(), 2u);
  can::OdometryUpdate first;
  ASSERT_TRUE(ring.try_pop(first));
  EXPECT_NEAR(first.speed_mps, 10.0, 1e-12);  // the oldest is kept
  EXPECT_FALSE(ring.try_pop(first));
}

TEST(CanThread, StopEndsTheLoopWithoutMarkingTheInputLost) {
  Fixture f;
  rt::SpscRing<can::OdometryUpdate> ring(8);
  auto loop =
      std::async(std::launch::async, [&] { return read_can_until_end(f.input, ring, f.report); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  f.input.stop();
  ASSERT_EQ(loop.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  EXPECT_EQ(loop.get(), can::InputEvent::kStopped);
  EXPECT_EQ(f.can_state(), rt::InputState::kOk);  // never heard, still within its timeout
}

TEST(CanThread, TheLoopAllocatesNothingUpToTheBusGoingAway) {
  Fixture f;
  rt::SpscRing<can::OdometryUpdate> ring(64);
  for (int i = 0; i < 50; ++i)
    testing::send_frame(f.pair.peer, i % 2 == 0 ? testing::kSpeedId : testing::kYawRateId, {1, 2});
  ::close(f.pair.peer);
  f.pair.peer = -1;
  rt::testing::AllocationCounter counter;
  const can::InputEvent e = read_can_until_end(f.input, ring, f.report);  // warns on stderr
  counter.stop();
  EXPECT_EQ(e, can::InputEvent::kGone);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(ring.size(), 50u);
  EXPECT_EQ(f.cells.load().updates, 50u);
  static_assert(noexcept(read_can_until_end(f.input, ring, f.report)));
}

TEST(CanCounterCells, EveryFieldRoundTrips) {
  CanCounterCells cells;
  const can::CanInputCounters c{.frames = 1,
                                .updates = 2,
                                .not_mapped = 3,
                                .kernel_drops = 4,
                                .overflows = 5,
                                .can_fd = 6,
                                .malformed = 7,
                                .lost = 10,
                                .other_channel = 8,
                                .read_errors = 9};
  cells.store(c);
  EXPECT_EQ(cells.load(), c);
}

}  // namespace
}  // namespace stac::runtime

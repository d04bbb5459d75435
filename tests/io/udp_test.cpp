#include <gtest/gtest.h>

#include <array>
#include <thread>
#include <type_traits>
#include <vector>

#include "drivers/io/udp_receiver.hpp"
#include "rt/clock.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::io {
namespace {

// Move-only; a move never throws (the descriptors go with the object).
static_assert(std::is_nothrow_move_constructible_v<UdpReceiver> &&
              std::is_nothrow_move_assignable_v<UdpReceiver> &&
              !std::is_copy_constructible_v<UdpReceiver>);
static_assert(std::is_nothrow_move_constructible_v<UdpSender> &&
              !std::is_copy_constructible_v<UdpSender>);

UdpReceiverConfig loopback(int max_payload = 2048) {
  UdpReceiverConfig c;
  c.bind_address = "127.0.0.1";
  c.port = 0;
  c.receive_buffer_bytes = 4 << 20;
  c.max_payload = max_payload;
  return c;
}

// Receives until `expected` datagrams arrived or 2 s passed.
std::vector<std::vector<std::uint8_t>> drain(UdpReceiver& r, std::size_t expected) {
  std::vector<std::vector<std::uint8_t>> got;
  std::array<Datagram, 16> batch{};
  const std::int64_t deadline = rt::monotonic_ns() + 2'000'000'000;
  while (got.size() < expected && rt::monotonic_ns() < deadline) {
    const int n = r.receive(batch, 50);
    for (int i = 0; i < n; ++i) {
      const auto& p = batch[static_cast<std::size_t>(i)].payload;
      got.emplace_back(p.begin(), p.end());
    }
  }
  return got;
}

TEST(UdpReceiver, ReceivesEveryDatagramOverLoopback) {
  auto r = UdpReceiver::open(loopback());
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_NE(r->port(), 0);
  auto s = UdpSender::open("127.0.0.1", r->port());
  ASSERT_TRUE(s) << s.error().message;
  const std::int64_t before = rt::realtime_ns();
  std::array<std::uint8_t, 1206> packet{};
  for (int i = 0; i < 500; ++i) {
    packet[0] = static_cast<std::uint8_t>(i);
    packet[1] = static_cast<std::uint8_t>(i >> 8);
    ASSERT_TRUE(s->send(packet));
  }
  const auto got = drain(*r, 500);
  ASSERT_EQ(got.size(), 500u);
  for (int i = 0; i < 500; ++i) {
    ASSERT_EQ(got[static_cast<std::size_t>(i)].size(), 1206u);
    EXPECT_EQ(got[static_cast<std::size_t>(i)][0] | (got[static_cast<std::size_t>(i)][1] << 8), i);
  }
  EXPECT_EQ(r->counters().received, 500u);
  EXPECT_EQ(r->counters().kernel_drops, 0u);
  EXPECT_EQ(r->counters().no_kernel_stamp, 0u);  // kernel stamps were delivered

  // Stamps are kernel receive times: after the sending started, not in the future.
  s->send(packet);
  std::array<Datagram, 1> one{};
  ASSERT_EQ(r->receive(one, 1000), 1);
  EXPECT_GE(one[0].stamp_ns, before);
  EXPECT_LE(one[0].stamp_ns, rt::realtime_ns());
  EXPECT_EQ(one[0].src_ip, 0x7F000001u);
}

TEST(UdpReceiver, FiltersOtherSenders) {
  UdpReceiverConfig c = loopback();
  c.sender_address = "127.0.0.2";  // the sender below uses 127.0.0.1
  auto r = UdpReceiver::open(c);
  ASSERT_TRUE(r);
  auto s = UdpSender::open("127.0.0.1", r->port());
  ASSERT_TRUE(s);
  std::array<std::uint8_t, 10> p{};
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(s->send(p));
  EXPECT_TRUE(drain(*r, 1).empty());
  EXPECT_EQ(r->counters().filtered_sender, 20u);
}

TEST(UdpReceiver, CountsOversizeDatagramsAsTruncated) {
  auto r = UdpReceiver::open(loopback(1206));
  ASSERT_TRUE(r);
  auto s = UdpSender::open("127.0.0.1", r->port());
  ASSERT_TRUE(s);
  std::vector<std::uint8_t> big(1500, 1), ok(1206, 2);
  ASSERT_TRUE(s->send(big));
  ASSERT_TRUE(s->send(ok));
  const auto got = drain(*r, 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].size(), 1206u);
  EXPECT_EQ(r->counters().truncated, 1u);
}

TEST(UdpReceiver, StopWakesABlockedReceive) {
  auto r = UdpReceiver::open(loopback());
  ASSERT_TRUE(r);
  std::array<Datagram, 4> batch{};
  int result = 0;
  const std::int64_t start = rt::monotonic_ns();
  std::thread t([&] { result = r->receive(batch, 30'000); });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  r->stop();
  t.join();
  EXPECT_EQ(result, UdpReceiver::kStopped);
  EXPECT_LT(rt::monotonic_ns() - start, 10'000'000'000);      // long before the 30 s timeout
  EXPECT_EQ(r->receive(batch, 1000), UdpReceiver::kStopped);  // and stays stopped
}

TEST(UdpReceiver, APortInUseGivesAClearError) {
  auto first = UdpReceiver::open(loopback());
  ASSERT_TRUE(first);
  UdpReceiverConfig c = loopback();
  c.port = first->port();
  auto second = UdpReceiver::open(c);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find(std::to_string(first->port())), std::string::npos);
  EXPECT_NE(second.error().message.find("in use"), std::string::npos) << second.error().message;
  UdpReceiverConfig bad = loopback();
  bad.bind_address = "not-an-address";
  auto third = UdpReceiver::open(bad);
  ASSERT_FALSE(third);
  EXPECT_NE(third.error().message.find("not-an-address"), std::string::npos);
}

TEST(UdpReceiver, ReceiveAllocatesNothing) {
  auto r = UdpReceiver::open(loopback());
  ASSERT_TRUE(r);
  auto s = UdpSender::open("127.0.0.1", r->port());
  ASSERT_TRUE(s);
  std::array<std::uint8_t, 1206> p{};
  std::array<Datagram, 32> batch{};
  for (int i = 0; i < 64; ++i) ASSERT_TRUE(s->send(p));
  rt::testing::AllocationCounter counter;
  int got = 0;
  const std::int64_t deadline = rt::monotonic_ns() + 2'000'000'000;
  while (got < 64 && rt::monotonic_ns() < deadline) {
    const int n = r->receive(batch, 50);
    if (n > 0) got += n;
  }
  counter.stop();
  EXPECT_EQ(got, 64);
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::io

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <thread>
#include <vector>

#include "drivers/can/candump.hpp"
#include "drivers/can/cannelloni.hpp"
#include "drivers/io/pcap_writer.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "replay/can_replay.hpp"
#include "replay/faults.hpp"
#include "replay/udp_replay.hpp"
#include "rt/clock.hpp"

namespace stac::replay {
namespace {

using namespace io;  // the captures, receivers and senders the replays are tested with

using Bytes = std::vector<std::uint8_t>;

std::filesystem::path temp(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("stac_replay_test_" + name);
}

// `n` datagrams of different sizes and contents, `gap_ns` apart, captured to port 2368.
std::vector<Bytes> write_capture(const std::filesystem::path& path, int n, std::int64_t gap_ns,
                                 std::uint16_t dst_port = 2368) {
  auto w = PcapWriter::open(path);
  EXPECT_TRUE(w);
  std::vector<Bytes> payloads;
  for (int i = 0; i < n; ++i) {
    Bytes b(static_cast<std::size_t>(100 + (i * 37) % 1107));
    for (std::size_t j = 0; j < b.size(); ++j)
      b[j] = static_cast<std::uint8_t>(i * 7 + static_cast<int>(j));
    Datagram d;
    d.payload = b;
    d.stamp_ns = 1'700'000'000'000'000'000 + i * gap_ns;
    d.src_ip = 0xC0A8032B;
    d.dst_ip = 0xFFFFFFFF;
    d.src_port = 2368;
    d.dst_port = dst_port;
    EXPECT_TRUE(w->write_udp(d));
    payloads.push_back(std::move(b));
  }
  EXPECT_TRUE(w->close());
  return payloads;
}

UdpReceiver loopback_receiver() {
  UdpReceiverConfig c;
  c.bind_address = "127.0.0.1";
  c.port = 0;
  c.receive_buffer_bytes = 8 << 20;
  auto r = UdpReceiver::open(c);
  EXPECT_TRUE(r) << r.error().message;
  return std::move(*r);
}

// Receives until `expected` datagrams arrived or the socket stayed quiet for a second.
std::vector<Bytes> drain(UdpReceiver& r, std::size_t expected) {
  std::vector<Bytes> got;
  std::array<Datagram, 32> batch{};
  std::int64_t quiet_since = rt::monotonic_ns();
  while (got.size() < expected && rt::monotonic_ns() - quiet_since < 1'000'000'000) {
    const int n = r.receive(batch, 50);
    if (n > 0) quiet_since = rt::monotonic_ns();
    for (int i = 0; i < n; ++i) {
      const auto& p = batch[static_cast<std::size_t>(i)].payload;
      got.emplace_back(p.begin(), p.end());
    }
  }
  return got;
}

struct Outcome {
  ReplayPlan plan;
  ReplayReport report;
  std::vector<Bytes> received;
};

Outcome replay_into_socket(const std::filesystem::path& capture, ReplayConfig config,
                           std::size_t expected) {
  UdpReceiver receiver = loopback_receiver();
  config.address = "127.0.0.1";
  config.port = receiver.port();
  auto replay = UdpReplay::open(capture, config);
  EXPECT_TRUE(replay) << replay.error().message;
  Outcome o;
  o.plan = replay->plan();
  std::thread rx([&] { o.received = drain(receiver, expected); });
  const std::atomic<bool> never{false};
  auto report = replay->run(never);
  rx.join();
  EXPECT_TRUE(report) << report.error().message;
  o.report = *report;
  return o;
}

TEST(UdpReplay, EveryDatagramArrivesByteIdenticalAndInOrder) {
  const auto path = temp("order.pcap");
  const auto sent = write_capture(path, 300, 1'000'000);
  const Outcome o = replay_into_socket(path, ReplayConfig{}, sent.size());
  EXPECT_EQ(o.plan.packets, 300u);
  EXPECT_EQ(o.plan.span_ns, 299 * 1'000'000);
  ASSERT_EQ(o.received.size(), sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i)
    EXPECT_EQ(o.received[i], sent[i]) << "datagram " << i;
  EXPECT_EQ(o.report.packets, 300u);
  EXPECT_EQ(o.report.passes, 1u);
  EXPECT_EQ(o.report.send_failures, 0u);
  EXPECT_EQ(o.report.scheduled_ns, 299 * 1'000'000);
  // The pacing statistics are ordered and measured.
  EXPECT_GE(o.report.error_median_ns, 0);
  EXPECT_LE(o.report.error_median_ns, o.report.error_p99_ns);
  EXPECT_LE(o.report.error_p99_ns, o.report.error_max_ns);
  // Nothing is sent before its time: the last one went out no earlier than scheduled.
  EXPECT_GE(o.report.elapsed_ns, o.report.scheduled_ns);
}

TEST(UdpReplay, RateDividesTheSchedule) {
  const auto path = temp("rate.pcap");
  const auto sent = write_capture(path, 120, 2'000'000);
  ReplayConfig c;
  c.rate = 4.0;
  const Outcome o = replay_into_socket(path, c, sent.size());
  EXPECT_EQ(o.received.size(), sent.size());
  EXPECT_EQ(o.report.scheduled_ns, 119 * 2'000'000 / 4);
  EXPECT_GE(o.report.elapsed_ns, o.report.scheduled_ns);
}

TEST(UdpReplay, LoopingSendsTheCaptureNTimes) {
  const auto path = temp("loop.pcap");
  const auto sent = write_capture(path, 50, 500'000);
  ReplayConfig c;
  c.loops = 3;
  c.rate = 2.0;
  const Outcome o = replay_into_socket(path, c, 3 * sent.size());
  ASSERT_EQ(o.received.size(), 3 * sent.size());
  for (std::size_t i = 0; i < o.received.size(); ++i)
    EXPECT_EQ(o.received[i], sent[i % sent.size()]);
  EXPECT_EQ(o.report.passes, 3u);
  EXPECT_EQ(o.report.packets, 150u);
  // A pass lasts the span plus one mean gap: the third pass starts 2 x 50 x 0.5 ms in.
  EXPECT_EQ(o.plan.pass_period_ns, 50 * 500'000);
  EXPECT_EQ(o.report.scheduled_ns, (2 * 50 * 500'000 + 49 * 500'000) / 2);
}

TEST(UdpReplay, FastSendsEverythingWithoutASchedule) {
  const auto path = temp("fast.pcap");
  const auto sent = write_capture(path, 200, 100'000'000);  // 20 s recorded
  ReplayConfig c;
  c.fast = true;
  const Outcome o = replay_into_socket(path, c, sent.size());
  EXPECT_EQ(o.received, sent);
  EXPECT_EQ(o.report.scheduled_ns, 0);
  EXPECT_EQ(o.report.error_median_ns, -1);
  EXPECT_LT(o.report.elapsed_ns, 19'900'000'000);  // far from the recorded 19.9 s
}

TEST(UdpReplay, StopFlagEndsAnEndlessReplay) {
  const auto path = temp("forever.pcap");
  write_capture(path, 20, 1'000'000);
  UdpReceiver receiver = loopback_receiver();
  ReplayConfig c;
  c.port = receiver.port();
  c.loops = 0;
  auto replay = UdpReplay::open(path, c);
  ASSERT_TRUE(replay) << replay.error().message;
  std::atomic<bool> stop{false};
  std::thread stopper([&] {
    std::array<Datagram, 32> batch{};
    std::size_t got = 0;
    const std::int64_t deadline = rt::monotonic_ns() + 10'000'000'000;
    while (got < 100 && rt::monotonic_ns() < deadline)
      got += static_cast<std::size_t>(std::max(0, receiver.receive(batch, 100)));
    stop = true;
  });
  auto report = replay->run(stop);
  stopper.join();
  ASSERT_TRUE(report);
  EXPECT_TRUE(report->stopped);
  // Stopped after the 100th datagram arrived: five whole passes went out, maybe part of a sixth.
  EXPECT_GE(report->passes, 5u);
  EXPECT_GE(report->packets, 100u);
  EXPECT_LT(report->packets, 20 * (report->passes + 1));
}

TEST(UdpReplay, MissingCaptureIsNamed) {
  auto r = UdpReplay::open(temp("does_not_exist.pcap"), ReplayConfig{});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("does_not_exist.pcap"), std::string::npos) << r.error().message;
}

TEST(UdpReplay, CaptureWithoutUdpIsAClearError) {
  // A pcap with one ARP frame: no UDP at all.
  const auto path = temp("arp.pcap");
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    const std::uint32_t header[6] = {0xA1B2C3D4, 0x00040002, 0, 0, 65535, 1};  // v2.4, Ethernet
    std::fwrite(header, sizeof(header), 1, f);
    std::array<std::uint8_t, 42> frame{};
    frame.fill(0xFF);
    frame[12] = 0x08;  // EtherType 0x0806: ARP
    frame[13] = 0x06;
    const std::uint32_t record[4] = {1'700'000'000, 0, 42, 42};
    std::fwrite(record, sizeof(record), 1, f);
    std::fwrite(frame.data(), frame.size(), 1, f);
    std::fclose(f);
  }
  auto r = UdpReplay::open(path, ReplayConfig{});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no UDP datagram"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("1 not IPv4"), std::string::npos) << r.error().message;
}

TEST(UdpReplay, FilterPortWithoutMatchesIsAClearError) {
  const auto path = temp("filter.pcap");
  write_capture(path, 5, 1'000'000, 2368);
  ReplayConfig c;
  c.filter_port = 8308;
  auto r = UdpReplay::open(path, c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("to port 8308"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("5 UDP to other ports"), std::string::npos) << r.error().message;
}

TEST(UdpReplay, RateMustBePositive) {
  const auto path = temp("zero_rate.pcap");
  write_capture(path, 2, 1'000'000);
  ReplayConfig c;
  c.rate = 0.0;
  EXPECT_FALSE(UdpReplay::open(path, c));
}

// --faults (issue 31): the plan's grammar, refused with the item and what is wrong.
TEST(ReplayFaults, PlansParseAndBadItemsAreNamed) {
  auto p =
      parse_fault_plan("loss=0.1,burst=0.01:20,dropout=2+1.5,clock-jump=3:-5,window=1+2,seed=9");
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_DOUBLE_EQ(p->loss, 0.1);
  EXPECT_EQ(p->burst_length, 20u);
  EXPECT_DOUBLE_EQ(p->dropout->second, 1.5);
  EXPECT_DOUBLE_EQ(p->clock_jump->second, -5.0);
  EXPECT_EQ(p->seed, 9u);
  auto can = parse_fault_plan("can-silence=2+0.5");
  ASSERT_TRUE(can) << can.error().message;
  EXPECT_FALSE(can->any()) << "not a fault of the datagrams";
  ASSERT_TRUE(can->can_silence);
  EXPECT_DOUBLE_EQ(can->can_silence->first, 2.0);
  EXPECT_DOUBLE_EQ(can->can_silence->second, 0.5);
  for (const auto& [spec, what] : std::vector<std::pair<std::string, std::string>>{
           {"loss=2", "loss=2: not a probability"},
           {"burst=0.1", "burst=0.1: not PROBABILITY:DATAGRAMS"},
           {"dropout=3", "dropout=3: not START+SECONDS"},
           {"clock-jump=1:4000", "less than an hour"},
           {"jitter=0.1", "jitter=0.1: unknown fault"},
           {"loss", "loss: not NAME=VALUE"},
           {"seed=-1", "not a whole number"},
           {"window=1+1,seed=2", "names no fault"},
           {"can-silence=1", "can-silence=1: not START+SECONDS"}}) {
    auto bad = parse_fault_plan(spec);
    ASSERT_FALSE(bad) << spec;
    EXPECT_NE(bad.error().message.find(what), std::string::npos) << bad.error().message;
  }
}

// 2000 Velodyne-sized datagrams, numbered, 1 ms of capture time apart, through the injector into
// a real loopback socket: the same seed sends the same bytes; every datagram sent is one of the
// capture's (whole, cut, grown, or twice) or garbage, in the numbers the counts say.
std::vector<Bytes> faulted(const std::string& spec, FaultCounts* counts = nullptr) {
  UdpReceiver rx = loopback_receiver();
  auto tx = UdpSender::open("127.0.0.1", rx.port());
  EXPECT_TRUE(tx);
  auto plan = parse_fault_plan(spec);
  EXPECT_TRUE(plan) << plan.error().message;
  FaultInjector faults(*plan);
  std::uint64_t refused = 0;
  for (std::uint32_t i = 0; i < 2000; ++i) {
    Bytes d(1206, static_cast<std::uint8_t>(i));
    std::memcpy(d.data(), &i, 4);
    const std::uint32_t stamp = 1'000'000 + i * 1000;  // us past the hour
    std::memcpy(d.data() + 1200, &stamp, 4);
    refused += faults.offer(d, (i + 0.5) * 1e-3, *tx);  // mid-millisecond: no edge rounding
  }
  refused += faults.flush();
  EXPECT_EQ(refused, 0u);
  const FaultCounts& c = faults.counts();
  if (counts != nullptr) *counts = c;
  const std::size_t expected =
      2000 - c.lost - c.burst_lost - c.dropout_lost + c.duplicated + c.garbage;
  std::vector<Bytes> got = drain(rx, expected);
  EXPECT_EQ(got.size(), expected) << summary(faults.counts());
  return got;
}

TEST(ReplayFaults, SeededFaultsAreRepeatableAndCountedAsSent) {
  const std::string spec =
      "loss=0.05,burst=0.005:10,reorder=0.05,duplicate=0.05,truncate=0.05,oversize=0.05,"
      "garbage=0.05,seed=";
  FaultCounts c{};
  const std::vector<Bytes> a = faulted(spec + "5", &c);
  EXPECT_EQ(faulted(spec + "5"), a);
  EXPECT_NE(faulted(spec + "6"), a);
  for (const std::uint64_t n :
       {c.lost, c.burst_lost, c.reordered, c.duplicated, c.truncated, c.oversized, c.garbage})
    EXPECT_GT(n, 40u);  // about 100 of each in 2000
  std::size_t cut = 0, grown = 0, whole = 0;
  for (const Bytes& d : a) {
    cut += d.size() < 1206 ? 1 : 0;
    grown += d.size() > 1206 ? 1 : 0;
    whole += d.size() == 1206 ? 1 : 0;
  }
  EXPECT_GE(cut, c.truncated);  // and garbage shorter than a packet
  EXPECT_GE(grown, c.oversized);
  EXPECT_GE(whole, 2000 - c.lost - c.burst_lost - c.truncated - c.oversized);
}

TEST(ReplayFaults, DropoutWindowAndClockJumpActAtTheirCaptureTimes) {
  // Nothing from 0.2 s to 0.3 s; every datagram lost from 0.5 s to 0.6 s (the window); from
  // 1.5 s on, the Velodyne timestamps 2 s earlier.
  const std::vector<Bytes> got = faulted("dropout=0.2+0.1,loss=1,window=0.5+0.1,clock-jump=1.5:-2");
  ASSERT_EQ(got.size(), 1800u);
  std::uint32_t expect = 0;
  for (const Bytes& d : got) {
    if (expect == 200) expect = 300;
    if (expect == 500) expect = 600;
    std::uint32_t i = 0, stamp = 0;
    std::memcpy(&i, d.data(), 4);
    std::memcpy(&stamp, d.data() + 1200, 4);
    ASSERT_EQ(i, expect);
    const std::uint32_t recorded = 1'000'000 + i * 1000;
    EXPECT_EQ(stamp, i >= 1500 ? recorded - 2'000'000 : recorded) << i;
    ++expect;
  }
}

// A candump log of 100 frames, 10 ms apart from capture time 0, replayed as cannelloni datagrams
// into a real CannelloniReader at 10x: every frame arrives with its id and bytes, one datagram
// each in sequence; a can-silence of 0.3 s sends none of the 30 frames in it, without a gap in
// the sequence numbers.
TEST(CanReplay, ALogIsSentAsCannelloniDatagramsOnTheClockAndASilenceSendsNothing) {
  const auto log = temp("can.log");
  constexpr std::int64_t kStart = 1'767'268'800'000'000'000;
  {
    auto w = can::CandumpWriter::open(log, "can0");
    ASSERT_TRUE(w);
    for (std::uint8_t i = 0; i < 100; ++i) {
      can::Frame f;
      f.stamp_ns = kStart + i * 10'000'000;
      f.id = 0x1A0;
      f.dlc = 2;
      f.data = {i, static_cast<std::uint8_t>(i ^ 0xFF)};
      ASSERT_TRUE(w->write(f));
    }
    ASSERT_TRUE(w->close());
  }
  auto reader = can::CannelloniReader::open({"127.0.0.1", 0});
  ASSERT_TRUE(reader) << reader.error().message;
  CanReplayConfig c;
  c.port = reader->port();
  c.silence = std::pair{0.2, 0.3};  // frames 20..49
  c.origin_ns = kStart;
  auto replay = CanReplay::open(log, c);
  ASSERT_TRUE(replay) << replay.error().message;
  EXPECT_EQ(replay->plan().frames, 100u);
  EXPECT_EQ(replay->plan().span_ns, 990'000'000);
  ReplayClock clock{rt::monotonic_ns(), kStart, 1'000'000'000, 10.0};
  std::vector<can::Frame> got;
  std::thread rx([&] {
    std::vector<can::Frame> out(8);
    for (int quiet = 0; quiet < 10 && got.size() < 70;) {
      const int n = reader->read(out, 100);
      quiet = n > 0 ? 0 : quiet + 1;
      for (int i = 0; i < n; ++i) got.push_back(out[static_cast<std::size_t>(i)]);
    }
  });
  const std::atomic<bool> never{false};
  const std::int64_t start = rt::monotonic_ns();
  const CanReplayReport r = replay->run(never, clock);
  const std::int64_t took = rt::monotonic_ns() - start;
  rx.join();
  EXPECT_EQ(r.frames, 70u);
  EXPECT_EQ(r.silenced, 30u);
  EXPECT_EQ(r.send_failures, 0u);
  EXPECT_EQ(r.passes, 1u);
  EXPECT_GE(took, 90'000'000) << "paced: 0.99 s of log at 10x";
  ASSERT_EQ(got.size(), 70u);
  for (std::size_t k = 0; k < got.size(); ++k) {
    const std::uint8_t i = static_cast<std::uint8_t>(k < 20 ? k : k + 30);
    EXPECT_EQ(got[k].id, 0x1A0u);
    EXPECT_EQ(got[k].dlc, 2);
    EXPECT_EQ(got[k].data[0], i) << k;
    EXPECT_EQ(got[k].data[1], static_cast<std::uint8_t>(i ^ 0xFF)) << k;
  }
  const can::CannelloniCounters counts = reader->counters();
  EXPECT_EQ(counts.datagrams, 70u);
  EXPECT_EQ(counts.lost, 0u);
  EXPECT_EQ(counts.malformed, 0u);
}

TEST(CanReplay, AMalformedLogIsRefusedNamingItsLine) {
  const auto log = temp("bad_can.log");
  std::ofstream(log) << "(1.000000) can0 1A0#0102\n(1.010000) can0 1A0#XYZ\n";
  auto replay = CanReplay::open(log, {});
  ASSERT_FALSE(replay);
  EXPECT_NE(replay.error().message.find(log.string() + ":2"), std::string::npos)
      << replay.error().message;
}

}  // namespace
}  // namespace stac::replay

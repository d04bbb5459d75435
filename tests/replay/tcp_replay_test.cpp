#include "replay/tcp_replay.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <thread>
#include <type_traits>
#include <vector>

#include "drivers/io/pcap_writer.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "replay/udp_replay.hpp"
#include "rt/clock.hpp"

namespace stac::replay {
namespace {

using namespace io;  // the captures, receivers and senders the replays are tested with

// Move-only; a move never throws (the descriptors go with the object).
static_assert(std::is_nothrow_move_constructible_v<TcpReplay> &&
              std::is_nothrow_move_assignable_v<TcpReplay> &&
              !std::is_copy_constructible_v<TcpReplay>);

using Bytes = std::vector<std::uint8_t>;
constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;
constexpr std::uint32_t kPos = 0xC0A83564, kHost = 0xC0A83501;  // 192.168.53.100, .1
constexpr std::uint16_t kServer = 5602, kClient = 40000;

std::filesystem::path temp(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("stac_tcp_replay_test_" + name);
}

TcpSegment segment(std::int64_t stamp, bool from_server, std::uint32_t seq, std::uint8_t flags,
                   std::span<const std::uint8_t> payload = {}) {
  TcpSegment s;
  s.stamp_ns = stamp;
  s.src_ip = from_server ? kPos : kHost;
  s.dst_ip = from_server ? kHost : kPos;
  s.src_port = from_server ? kServer : kClient;
  s.dst_port = from_server ? kClient : kServer;
  s.seq = seq;
  s.flags = flags;
  s.payload = payload;
  return s;
}

struct Capture {
  Bytes stream;                      // what the server sent, in order
  std::vector<std::size_t> offsets;  // where each segment's bytes start in it
};

// A handshake then `n` server segments `gap_ns` apart; with `disorder`, segment 3 is
// retransmitted and segments 5 and 6 are captured swapped. Optionally UDP datagrams to 2368
// interleaved at the same times shifted by udp_shift_ns.
Capture write_capture(const std::filesystem::path& path, int n, std::int64_t gap_ns,
                      bool disorder = false, std::int64_t udp_shift_ns = -1) {
  auto w = PcapWriter::open(path);
  EXPECT_TRUE(w);
  constexpr std::uint32_t kIsn = 1000;
  EXPECT_TRUE(w->write_tcp(segment(kT0 - 2000, false, 7, kTcpSyn)));
  EXPECT_TRUE(w->write_tcp(segment(kT0 - 1000, true, kIsn, kTcpSyn | kTcpAck)));
  Capture c;
  std::vector<Bytes> payloads;
  std::vector<std::uint32_t> seqs;
  std::uint32_t seq = kIsn + 1;
  for (int i = 0; i < n; ++i) {
    Bytes b(static_cast<std::size_t>(40 + (i * 29) % 300));
    for (std::size_t j = 0; j < b.size(); ++j) b[j] = static_cast<std::uint8_t>(i * 13 + int(j));
    c.offsets.push_back(c.stream.size());
    c.stream.insert(c.stream.end(), b.begin(), b.end());
    seqs.push_back(seq);
    seq += static_cast<std::uint32_t>(b.size());
    payloads.push_back(std::move(b));
  }
  for (int k = 0; k < n; ++k) {
    int i = k;
    if (disorder && k == 5) i = 6;
    if (disorder && k == 6) i = 5;
    const auto ui = static_cast<std::size_t>(i);
    const std::int64_t t = kT0 + k * gap_ns;
    EXPECT_TRUE(w->write_tcp(segment(t, true, seqs[ui], kTcpAck, payloads[ui])));
    if (disorder && k == 3) {
      EXPECT_TRUE(w->write_tcp(segment(t + 10, true, seqs[ui], kTcpAck, payloads[ui])));
    }
    if (udp_shift_ns >= 0) {
      const Bytes u(100, static_cast<std::uint8_t>(k));
      Datagram d;
      d.payload = u;
      d.stamp_ns = t + udp_shift_ns;
      d.src_ip = 0xC0A8032B;
      d.dst_ip = 0x7F000001;
      d.src_port = 2368;
      d.dst_port = 2368;
      EXPECT_TRUE(w->write_udp(d));
    }
  }
  EXPECT_TRUE(w->close());
  return c;
}

int connect_to(std::uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof(a)), 0);
  timeval tv{10, 0};  // a broken replay fails the test instead of hanging it
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  return fd;
}

// Reads until end of stream (or `limit` bytes), then closes.
Bytes read_all(int fd, std::size_t limit = SIZE_MAX) {
  Bytes got;
  std::uint8_t buf[4096];
  while (got.size() < limit) {
    const ssize_t n = ::recv(fd, buf, std::min(sizeof(buf), limit - got.size()), 0);
    if (n <= 0) break;
    got.insert(got.end(), buf, buf + n);
  }
  ::close(fd);
  return got;
}

TcpReplay open_replay(const std::filesystem::path& path, TcpReplayConfig c = {}) {
  c.listen_port = 0;
  auto r = TcpReplay::open(path, c);
  EXPECT_TRUE(r) << r.error().message;
  return std::move(*r);
}

TEST(TcpReplay, ClientReceivesTheExactReassembledStream) {
  const auto path = temp("exact.pcap");
  const Capture cap = write_capture(path, 40, 1'000'000, /*disorder=*/true);
  TcpReplay replay = open_replay(path);
  EXPECT_EQ(replay.plan().bytes, cap.stream.size());
  EXPECT_EQ(replay.plan().retransmitted, 1u);
  EXPECT_EQ(replay.plan().gaps, 0u);
  EXPECT_EQ(replay.plan().span_ns, 40 * 1'000'000 - 1'000'000);
  Bytes got;
  std::thread client([&] { got = read_all(connect_to(replay.listen_port())); });
  const std::atomic<bool> never{false};
  ASSERT_TRUE(replay.wait_for_client(never));
  auto report = replay.run(never);
  client.join();
  ASSERT_TRUE(report) << report.error().message;
  EXPECT_EQ(got, cap.stream);
  EXPECT_EQ(report->bytes, cap.stream.size());
  EXPECT_EQ(report->unserved_bytes, 0u);
  EXPECT_EQ(report->clients, 1u);
  EXPECT_EQ(report->passes, 1u);
  EXPECT_EQ(report->scheduled_ns, replay.plan().span_ns);
  EXPECT_GE(report->elapsed_ns, report->scheduled_ns);  // nothing before its time
  EXPECT_GE(report->error_median_ns, 0);
  EXPECT_LE(report->error_median_ns, report->error_p99_ns);
  EXPECT_LE(report->error_p99_ns, report->error_max_ns);
}

// Issue 31: the INS stream's faults, chunk by chunk.
TEST(StreamFaults, EachActsInItsWindowAndCountsWhatItDid) {
  auto plan = parse_fault_plan(
      "ins-checksum=1+1,ins-garbage=2+1,ins-dropout=3+1,ins-disconnect=3.5,seed=4");
  ASSERT_TRUE(plan) << plan.error().message;
  EXPECT_FALSE(plan->any());  // nothing for the datagrams
  ASSERT_TRUE(plan->ins.any());
  StreamFaultInjector f(plan->ins);
  Bytes chunk(200);
  for (std::size_t i = 0; i < chunk.size(); ++i) chunk[i] = static_cast<std::uint8_t>(i);
  for (const std::size_t at : {0, 100}) std::memcpy(chunk.data() + at, "$GRP", 4);
  bool disconnect = true;
  auto out = f.apply(chunk, 0.5, disconnect);  // before every window: the bytes as they are
  EXPECT_FALSE(disconnect);
  EXPECT_EQ(Bytes(out.begin(), out.end()), chunk);
  out = f.apply(chunk, 1.5, disconnect);  // one body byte of each message
  ASSERT_EQ(out.size(), chunk.size());
  std::vector<std::size_t> changed;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (out[i] != chunk[i]) changed.push_back(i);
  EXPECT_EQ(changed, (std::vector<std::size_t>{12, 112}));
  EXPECT_EQ(f.counts().checksums_broken, 2u);
  out = f.apply(chunk, 2.5, disconnect);  // random bytes, as many
  ASSERT_EQ(out.size(), chunk.size());
  EXPECT_NE(Bytes(out.begin(), out.end()), chunk);
  EXPECT_EQ(f.counts().garbage_bytes, 200u);
  EXPECT_TRUE(f.apply(chunk, 3.2, disconnect).empty());  // the dropout
  EXPECT_FALSE(disconnect);
  EXPECT_TRUE(f.apply(chunk, 3.6, disconnect).empty());
  EXPECT_TRUE(disconnect);  // once per pass
  (void)f.apply(chunk, 3.7, disconnect);
  EXPECT_FALSE(disconnect);
  EXPECT_EQ(f.counts().dropout_bytes, 600u);
  f.new_pass();
  (void)f.apply(chunk, 3.6, disconnect);
  EXPECT_TRUE(disconnect);
  EXPECT_EQ(f.counts().disconnects, 2u);
  EXPECT_EQ(summary(f.counts()),
            "ins faults: 800 bytes held back in the dropout, 200 bytes of garbage instead of the "
            "stream, 2 messages with a broken checksum, 2 disconnects");

  for (const auto& [spec, what] : std::vector<std::pair<std::string, std::string>>{
           {"ins-dropout=3", "ins-dropout=3: not START+SECONDS"},
           {"ins-checksum=1+0", "not START+SECONDS"},
           {"ins-disconnect=-1", "ins-disconnect=-1: not AT"},
           {"ins-jam=1", "unknown fault"}}) {
    auto bad = parse_fault_plan(spec);
    ASSERT_FALSE(bad) << spec;
    EXPECT_NE(bad.error().message.find(what), std::string::npos) << bad.error().message;
  }
}

// Over a real loopback connection: the dropout's segments never arrive, and the disconnect ends
// the client's stream at its capture time.
TEST(TcpReplay, InjectedDropoutAndDisconnectActAtTheirCaptureTimes) {
  const auto path = temp("faults.pcap");
  const Capture cap = write_capture(path, 40, 1'000'000);
  TcpReplay replay = open_replay(path);
  auto plan = parse_fault_plan("ins-dropout=0.0095+0.010,ins-disconnect=0.0295");
  ASSERT_TRUE(plan) << plan.error().message;
  replay.inject(plan->ins, replay.plan().first_stamp_ns);
  Bytes got;
  std::thread client([&] { got = read_all(connect_to(replay.listen_port())); });
  const std::atomic<bool> never{false};
  ASSERT_TRUE(replay.wait_for_client(never));
  auto report = replay.run(never);
  client.join();
  ASSERT_TRUE(report) << report.error().message;
  // Segments 0-9, then 20-29: 10-19 held back, the connection closed before 30.
  Bytes expected(cap.stream.begin(), cap.stream.begin() + static_cast<long>(cap.offsets[10]));
  expected.insert(expected.end(), cap.stream.begin() + static_cast<long>(cap.offsets[20]),
                  cap.stream.begin() + static_cast<long>(cap.offsets[30]));
  EXPECT_EQ(got, expected);
  ASSERT_TRUE(report->faults.has_value());
  EXPECT_EQ(report->faults->dropout_bytes, cap.offsets[20] - cap.offsets[10]);
  EXPECT_EQ(report->faults->disconnects, 1u);
  EXPECT_EQ(report->disconnects, 1u);
  EXPECT_EQ(report->unserved_bytes, cap.stream.size() - cap.offsets[30]);
}

TEST(TcpReplay, RateDividesTheScheduleAndLoopsRepeatTheStream) {
  const auto path = temp("rate.pcap");
  const Capture cap = write_capture(path, 30, 4'000'000);
  TcpReplayConfig c;
  c.rate = 4.0;
  c.loops = 2;
  TcpReplay replay = open_replay(path, c);
  Bytes got;
  std::thread client([&] { got = read_all(connect_to(replay.listen_port())); });
  const std::atomic<bool> never{false};
  ASSERT_TRUE(replay.wait_for_client(never));
  auto report = replay.run(never);
  client.join();
  ASSERT_TRUE(report);
  Bytes twice = cap.stream;
  twice.insert(twice.end(), cap.stream.begin(), cap.stream.end());
  EXPECT_EQ(got, twice);
  EXPECT_EQ(report->passes, 2u);
  // Pass period = span + one mean gap = 30 x 4 ms; the last chunk: (120 ms + 116 ms) / 4.
  EXPECT_EQ(replay.plan().pass_period_ns, 120'000'000);
  EXPECT_EQ(report->scheduled_ns, 59'000'000);
  EXPECT_GE(report->elapsed_ns, report->scheduled_ns);
}

TEST(TcpReplay, FastServesEverythingWithoutSchedule) {
  const auto path = temp("fast.pcap");
  const Capture cap = write_capture(path, 50, 1'000'000'000);  // 49 s recorded
  TcpReplayConfig c;
  c.fast = true;
  TcpReplay replay = open_replay(path, c);
  Bytes got;
  std::thread client([&] { got = read_all(connect_to(replay.listen_port())); });
  const std::atomic<bool> never{false};
  ASSERT_TRUE(replay.wait_for_client(never));
  auto report = replay.run(never);
  client.join();
  ASSERT_TRUE(report);
  EXPECT_EQ(got, cap.stream);
  EXPECT_EQ(report->scheduled_ns, 0);
  EXPECT_EQ(report->error_median_ns, -1);
}

TEST(TcpReplay, ReconnectingClientGetsTheStreamFromThenOn) {
  const auto path = temp("reconnect.pcap");
  const Capture cap = write_capture(path, 60, 10'000'000);  // 0.6 s
  TcpReplay replay = open_replay(path);
  Bytes first, second;
  std::thread client([&] {
    first = read_all(connect_to(replay.listen_port()), cap.offsets[3]);  // 3 segments, then gone
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    second = read_all(connect_to(replay.listen_port()));
  });
  const std::atomic<bool> never{false};
  ASSERT_TRUE(replay.wait_for_client(never));
  auto report = replay.run(never);
  client.join();
  ASSERT_TRUE(report);
  EXPECT_EQ(first, Bytes(cap.stream.begin(), cap.stream.begin() + long(cap.offsets[3])));
  EXPECT_EQ(report->clients, 2u);
  EXPECT_GE(report->disconnects, 1u);
  // The second client gets the rest of the stream from a segment boundary on, to the end.
  ASSERT_FALSE(second.empty());
  ASSERT_LT(second.size(), cap.stream.size());
  const std::size_t from = cap.stream.size() - second.size();
  EXPECT_NE(std::find(cap.offsets.begin(), cap.offsets.end(), from), cap.offsets.end());
  EXPECT_EQ(second, Bytes(cap.stream.begin() + long(from), cap.stream.end()));
  // Every byte was either written to a client or due while none was connected.
  EXPECT_EQ(report->bytes + report->unserved_bytes, cap.stream.size());
  EXPECT_GT(report->unserved_bytes, 0u);
}

TEST(TcpReplay, StopEndsALongWaitPromptly) {
  const auto path = temp("stop.pcap");
  write_capture(path, 3, 60'000'000'000);  // a minute between segments
  TcpReplay replay = open_replay(path);
  std::atomic<bool> stop{false};
  Bytes got;
  std::thread client([&] { got = read_all(connect_to(replay.listen_port())); });
  ASSERT_TRUE(replay.wait_for_client(stop));
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    stop = true;
  });
  const std::int64_t t0 = rt::monotonic_ns();
  auto report = replay.run(stop);
  const std::int64_t took = rt::monotonic_ns() - t0;
  stopper.join();
  client.join();
  ASSERT_TRUE(report);
  EXPECT_TRUE(report->stopped);
  EXPECT_EQ(report->passes, 0u);
  EXPECT_EQ(report->segments, 1u);  // only the first was due
  EXPECT_LT(took, 10'000'000'000);  // far below the minute the next segment waits for
}

TEST(TcpReplay, NoStreamOnThePortIsAClearError) {
  const auto path = temp("noport.pcap");
  write_capture(path, 3, 1'000'000);
  TcpReplayConfig c;
  c.server_port = 5603;
  auto r = TcpReplay::open(path, c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no TCP stream from port 5603"), std::string::npos)
      << r.error().message;
  EXPECT_NE(r.error().message.find("5602"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find(path.string()), std::string::npos);
  auto ports = TcpReplay::server_ports(path);
  ASSERT_TRUE(ports);
  EXPECT_EQ(*ports, std::vector<std::uint16_t>{kServer});
  EXPECT_FALSE(TcpReplay::open("/nonexistent/x.pcap", {}));
}

TEST(TcpReplay, SharesOneClockWithTheUdpReplay) {
  const auto path = temp("shared.pcap");
  // TCP at kT0 + k x 5 ms, UDP 2 ms after each; the capture starts with the TCP stream.
  const Capture cap = write_capture(path, 40, 5'000'000, false, 2'000'000);
  TcpReplay tcp = open_replay(path);
  UdpReceiverConfig rc;
  rc.bind_address = "127.0.0.1";
  rc.port = 0;
  auto receiver = UdpReceiver::open(rc);
  ASSERT_TRUE(receiver);
  ReplayConfig uc;
  uc.port = receiver->port();
  auto udp = UdpReplay::open(path, uc);
  ASSERT_TRUE(udp) << udp.error().message;
  ASSERT_EQ(udp->plan().first_stamp_ns, kT0 + 2'000'000);
  Bytes got;
  std::thread client([&] { got = read_all(connect_to(tcp.listen_port())); });
  const std::atomic<bool> never{false};
  ASSERT_TRUE(tcp.wait_for_client(never));
  const ReplayClock clock{rt::monotonic_ns() + 5'000'000, kT0, 200'000'000, 2.0};
  rt::Result<ReplayReport> ur = rt::make_error("not run");
  std::thread udp_thread([&] { ur = udp->run(never, &clock); });
  auto tr = tcp.run(never, &clock);
  udp_thread.join();
  client.join();
  ASSERT_TRUE(tr);
  ASSERT_TRUE(ur);
  EXPECT_EQ(got, cap.stream);
  EXPECT_EQ(ur->packets, 40u);
  // Both on the capture's time line from kT0, halved: last TCP at 195 ms, last UDP at 197 ms.
  EXPECT_EQ(tr->scheduled_ns, 97'500'000);
  EXPECT_EQ(ur->scheduled_ns, 98'500'000);
  EXPECT_GE(ur->elapsed_ns, ur->scheduled_ns);
  EXPECT_GE(tr->elapsed_ns, tr->scheduled_ns);
}

}  // namespace
}  // namespace stac::replay

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <thread>
#include <type_traits>
#include <vector>

#include "applanix/applanix_stream.hpp"
#include "drivers/applanix/capture_reader.hpp"
#include "drivers/applanix/tcp_client.hpp"
#include "drivers/applanix/udp_listener.hpp"
#include "drivers/io/pcap_writer.hpp"

namespace stac::applanix {
namespace {

using Bytes = std::vector<std::uint8_t>;

// Move-only; a move never throws (the descriptors go with the object).
static_assert(std::is_nothrow_move_constructible_v<TcpClient> &&
              std::is_nothrow_move_assignable_v<TcpClient> &&
              !std::is_copy_constructible_v<TcpClient>);

std::vector<Bytes> random_messages(std::uint32_t seed, int count) {
  std::mt19937 rng(seed);
  std::vector<Bytes> out;
  for (int i = 0; i < count; ++i) out.push_back(testing::random_message(rng).bytes);
  return out;
}

Bytes concat(const std::vector<Bytes>& messages) {
  Bytes out;
  for (const auto& m : messages) out.insert(out.end(), m.begin(), m.end());
  return out;
}

// A listening TCP socket on 127.0.0.1 (any free port) for the client to connect to.
class LocalServer {
 public:
  LocalServer() {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    EXPECT_EQ(::listen(fd_, 4), 0);
    socklen_t len = sizeof(a);
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
  }
  ~LocalServer() { ::close(fd_); }
  std::uint16_t port() const { return port_; }
  // The next connection, or -1 after 10 s without one.
  int accept() {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 10'000) != 1) return -1;
    return ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
  }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
};

void send_all(int fd, const Bytes& b) {
  std::size_t at = 0;
  while (at < b.size()) {
    const ssize_t n = ::send(fd, b.data() + at, b.size() - at, MSG_NOSIGNAL);
    if (n <= 0) return;
    at += static_cast<std::size_t>(n);
  }
}

// Blocks until the peer closes (the client's destructor) or 10 s pass.
void wait_for_close(int fd) {
  pollfd p{fd, POLLIN, 0};
  char c;
  while (::poll(&p, 1, 10'000) == 1 && ::recv(fd, &c, 1, 0) > 0) {
  }
}

TcpClientConfig local_config(std::uint16_t port) {
  TcpClientConfig c;
  c.address = "127.0.0.1";
  c.port = port;
  c.connect_timeout_ms = 1000;
  c.stall_timeout_ms = 5000;
  c.initial_backoff_ms = 20;
  c.max_backoff_ms = 200;
  return c;
}

// Reads from the client into the parser until `want` messages came (or 20 s of nothing).
std::vector<Bytes> read_messages(TcpClient& client, StreamParser& parser, std::size_t want) {
  std::vector<Bytes> got;
  std::vector<std::uint8_t> buf(777);  // an odd size, so messages straddle reads
  std::uint64_t session = 0;
  int idle = 0;
  while (got.size() < want && idle < 200) {
    const int n = client.receive(buf, 100);
    if (n <= 0) {
      ++idle;
      continue;
    }
    if (client.session() != session) {  // a new connection starts a new stream
      parser.end_of_stream();
      session = client.session();
    }
    parser.feed({buf.data(), static_cast<std::size_t>(n)});
    Parsed p;
    while (parser.next(p)) {
      client.note_message();
      got.emplace_back(p.bytes.begin(), p.bytes.end());
    }
  }
  return got;
}

TEST(ApplanixTcpClient, ReconnectsAfterTheServerDropsAndResumes) {
  const auto first = random_messages(1, 30), second = random_messages(2, 30);
  LocalServer server;
  std::thread pos([&] {
    const int c1 = server.accept();
    Bytes b = concat(first);
    b.insert(b.end(), second[0].begin(), second[0].begin() + 30);  // cut off by the drop
    send_all(c1, b);
    ::close(c1);
    const int c2 = server.accept();
    send_all(c2, concat(second));
    wait_for_close(c2);
    ::close(c2);
  });
  {
    auto client = TcpClient::open(local_config(server.port()));
    ASSERT_TRUE(client) << client.error().message;
    StreamParser parser;
    auto got = read_messages(*client, parser, first.size() + second.size());
    auto expected = first;
    expected.insert(expected.end(), second.begin(), second.end());
    EXPECT_EQ(got, expected);
    EXPECT_EQ(client->counters().connects, 2u);
    EXPECT_EQ(client->counters().disconnects, 1u);
    EXPECT_EQ(client->counters().stalls, 0u);
    EXPECT_EQ(parser.counters().truncated, 1u);  // the message cut by the drop
  }
  pos.join();
}

TEST(ApplanixTcpClient, StalledStreamTimesOutAndReconnects) {
  const auto first = random_messages(3, 10), second = random_messages(4, 10);
  LocalServer server;
  std::thread pos([&] {
    const int c1 = server.accept();
    send_all(c1, concat(first));  // then silent, connection left open
    const int c2 = server.accept();
    send_all(c2, concat(second));
    wait_for_close(c2);
    ::close(c2);
    ::close(c1);
  });
  {
    auto config = local_config(server.port());
    config.stall_timeout_ms = 300;
    auto client = TcpClient::open(config);
    ASSERT_TRUE(client);
    StreamParser parser;
    auto got = read_messages(*client, parser, first.size() + second.size());
    auto expected = first;
    expected.insert(expected.end(), second.begin(), second.end());
    EXPECT_EQ(got, expected);
    EXPECT_EQ(client->counters().stalls, 1u);
    EXPECT_EQ(client->counters().connects, 2u);
    EXPECT_EQ(client->counters().disconnects, 0u);
  }
  pos.join();
}

// Issue 31: a server that trickles a byte every 50 ms (never a stall) or floods garbage kept its
// connection forever while the INS was reported stale.
TEST(ApplanixTcpClient, BytesWithoutAValidMessageForAWhileReconnect) {
  LocalServer server;
  std::atomic<bool> done{false};
  std::thread pos([&] {
    const int c1 = server.accept();
    while (!done.load()) {  // one garbage byte every 50 ms, until the client gives up on it
      const std::uint8_t junk = 0x5a;
      if (::send(c1, &junk, 1, MSG_NOSIGNAL) != 1) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ::close(c1);
  });
  auto config = local_config(server.port());
  config.stall_timeout_ms = 300;  // longer than the trickle's gaps: never a stall
  config.message_timeout_ms = 400;
  auto client = TcpClient::open(config);
  ASSERT_TRUE(client);
  std::vector<std::uint8_t> buf(64);
  for (int i = 0; i < 300 && client->counters().no_message == 0; ++i)
    (void)client->receive(buf, 10);
  EXPECT_EQ(client->counters().no_message, 1u);
  EXPECT_EQ(client->counters().stalls, 0u);
  done.store(true);
  pos.join();
  TcpClientConfig bad = local_config(1);
  bad.message_timeout_ms = -1;
  EXPECT_FALSE(TcpClient::open(bad));
}

TEST(ApplanixTcpClient, StopReturnsPromptlyWhileConnectedOrBackingOff) {
  LocalServer server;
  std::thread pos([&] {
    const int c = server.accept();
    wait_for_close(c);
    ::close(c);
  });
  for (const bool with_server : {true, false}) {
    auto config = local_config(with_server ? server.port() : std::uint16_t{1});
    config.stall_timeout_ms = 60'000;
    config.initial_backoff_ms = 60'000;
    config.max_backoff_ms = 60'000;
    auto client = TcpClient::open(config);
    ASSERT_TRUE(client);
    std::thread stopper([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      client->stop();
    });
    std::vector<std::uint8_t> buf(64);
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(client->receive(buf, 60'000), TcpClient::kStopped);
    // Returned on stop(), far before its 60 s timeout, stall or backoff.
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(30));
    EXPECT_EQ(client->connected(), with_server);
    EXPECT_EQ(client->receive(buf, 60'000), TcpClient::kStopped);  // stays stopped
    stopper.join();
  }
  pos.join();
}

TEST(ApplanixTcpClient, BackoffDoublesUpToItsLimitWhileTheServerIsAway) {
  std::uint16_t port = 0;
  {
    LocalServer gone;  // a port that nothing listens on once this closes
    port = gone.port();
  }
  auto config = local_config(port);
  config.initial_backoff_ms = 1;
  config.max_backoff_ms = 8;
  auto client = TcpClient::open(config);
  ASSERT_TRUE(client);
  std::vector<std::uint8_t> buf(64);
  for (int i = 0; i < 500 && client->counters().connect_failures < 7; ++i) {
    EXPECT_EQ(client->receive(buf, 5), 0);
    const auto failures = client->counters().connect_failures;
    if (failures > 0) {
      EXPECT_EQ(client->backoff_ms(), std::min(1 << (failures - 1), 8)) << failures << " failures";
    }
  }
  EXPECT_GE(client->counters().connect_failures, 7u);
  EXPECT_EQ(client->backoff_ms(), 8);
  EXPECT_EQ(client->counters().connects, 0u);
}

TEST(ApplanixTcpClient, OpenRejectsABadConfiguration) {
  auto c = local_config(5602);
  c.address = "pos.local";
  auto r = TcpClient::open(c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("pos.local"), std::string::npos);
  c = local_config(5602);
  c.max_backoff_ms = 1;
  EXPECT_FALSE(TcpClient::open(c));
}

TEST(ApplanixUdpListener, ParsesEachDatagramAsItsOwnStream) {
  io::UdpReceiverConfig config;
  config.bind_address = "127.0.0.1";
  config.port = 0;
  config.max_payload = 9000;
  auto listener = UdpListener::open(config);
  ASSERT_TRUE(listener) << listener.error().message;
  auto sender = io::UdpSender::open("127.0.0.1", listener->port());
  ASSERT_TRUE(sender) << sender.error().message;
  std::vector<Bytes> expected;
  for (std::uint32_t i = 0; i < 20; ++i) {
    const auto messages = random_messages(100 + i, 3);
    Bytes datagram = concat(messages);
    if (i == 7) datagram.resize(datagram.size() - 5);  // the last message is cut short
    expected.insert(expected.end(), messages.begin(), messages.end() - (i == 7 ? 1 : 0));
    ASSERT_TRUE(sender->send(datagram));
  }
  std::vector<Bytes> got;
  Parsed p;
  for (int tries = 0; tries < 100 && got.size() < expected.size(); ++tries) {
    if (listener->receive(100) <= 0) continue;
    while (listener->next(p)) {
      got.emplace_back(p.bytes.begin(), p.bytes.end());
      EXPECT_GT(listener->stamp_ns(), 0);
    }
  }
  EXPECT_EQ(got, expected);
  EXPECT_EQ(listener->parser().counters().truncated, 1u);
}

TEST(ApplanixCaptureReader, FollowsATcpStreamWithRetransmissionAndReorderInAPcap) {
  const auto path = std::filesystem::temp_directory_path() / "stac_applanix_tcp.pcap";
  const auto messages = random_messages(9, 60);
  const Bytes stream = concat(messages);
  const std::uint32_t isn = 0xFFFFF000u;  // sequence numbers wrap inside the capture
  std::mt19937 rng(17);
  std::vector<io::TcpSegment> segments;
  io::TcpSegment s;
  s.src_ip = 0xC0A80203;  // POS 192.168.2.3:5602 -> client 192.168.2.1:40000
  s.dst_ip = 0xC0A80201;
  s.src_port = kPortRealTime;
  s.dst_port = 40000;
  s.seq = isn;
  s.flags = io::kTcpSyn | io::kTcpAck;
  segments.push_back(s);
  for (std::size_t at = 0; at < stream.size();) {
    const std::size_t n = std::min<std::size_t>(1 + rng() % 400, stream.size() - at);
    s.payload = {stream.data() + at, n};
    s.seq = isn + 1 + static_cast<std::uint32_t>(at);
    s.flags = io::kTcpAck;
    segments.push_back(s);
    at += n;
  }
  std::swap(segments[10], segments[11]);                 // out of order
  segments.insert(segments.begin() + 20, segments[15]);  // retransmitted
  Group1 g1;
  g1.latitude_deg = 44.0;
  Bytes display(kGroup1Bytes);
  ASSERT_EQ(encode_group1(g1, TimeDistance{}, display), kGroup1Bytes);
  {
    auto w = io::PcapWriter::open(path);
    ASSERT_TRUE(w);
    for (std::size_t i = 0; i < segments.size(); ++i) {
      ASSERT_TRUE(w->write_tcp(segments[i]));
      io::TcpSegment ack;  // the client's direction: must be ignored
      ack.src_ip = s.dst_ip;
      ack.dst_ip = s.src_ip;
      ack.src_port = 40000;
      ack.dst_port = kPortRealTime;
      ack.flags = io::kTcpAck;
      ack.payload = display;  // even with a payload
      ASSERT_TRUE(w->write_tcp(ack));
      if (i == 5) {
        io::Datagram d;
        d.payload = display;
        d.dst_port = kPortDisplay;
        ASSERT_TRUE(w->write_udp(d));
      }
    }
    ASSERT_TRUE(w->close());
  }
  auto reader = CaptureReader::open(path);
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_TRUE(reader->is_pcap());
  std::vector<Bytes> got;
  Parsed p;
  while (reader->next(p)) got.emplace_back(p.bytes.begin(), p.bytes.end());
  auto expected = messages;
  expected.insert(expected.begin(), display);  // UDP messages come first
  EXPECT_EQ(got, expected);
  EXPECT_TRUE(reader->error().empty()) << reader->error();
  EXPECT_EQ(reader->tcp_counters().retransmitted, 1u);
  EXPECT_EQ(reader->tcp_counters().out_of_order, 1u);
  EXPECT_EQ(reader->tcp_counters().gaps, 0u);
  EXPECT_EQ(reader->tcp_counters().streams, 1u);
  EXPECT_EQ(reader->parser().counters().garbage_bytes, 0u);
  EXPECT_EQ(reader->counters().datagrams, 1u);

  // Restricted to the real-time port: the display datagram is left out.
  auto only = CaptureReader::open(path, kPortRealTime);
  ASSERT_TRUE(only);
  std::size_t count = 0;
  while (only->next(p)) ++count;
  EXPECT_EQ(count, messages.size());
  std::filesystem::remove(path);
}

TEST(ApplanixCaptureReader, ReadsARawStreamFileWithATruncatedEnd) {
  const auto path = std::filesystem::temp_directory_path() / "stac_applanix_raw.bin";
  const auto messages = random_messages(12, 2000);  // several read blocks
  Bytes stream = concat(messages);
  stream.resize(stream.size() - 3);
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(stream.data(), 1, stream.size(), f);
    std::fclose(f);
  }
  auto reader = CaptureReader::open(path);
  ASSERT_TRUE(reader) << reader.error().message;
  EXPECT_FALSE(reader->is_pcap());
  std::vector<Bytes> got;
  Parsed p;
  while (reader->next(p)) got.emplace_back(p.bytes.begin(), p.bytes.end());
  EXPECT_EQ(got, std::vector<Bytes>(messages.begin(), messages.end() - 1));
  EXPECT_EQ(reader->parser().counters().truncated, 1u);
  EXPECT_EQ(reader->counters().raw_bytes, stream.size());
  std::filesystem::remove(path);
  EXPECT_FALSE(CaptureReader::open(path));  // gone: the error names the file
}

}  // namespace
}  // namespace stac::applanix

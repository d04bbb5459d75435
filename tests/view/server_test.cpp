// The Foxglove server of stac view against raw WebSocket clients on loopback (real sockets, the
// handshake and frames written by hand): its limits hold when clients arrive together and when
// one client asks for more than a viewer needs.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "view/foxglove_server.hpp"

namespace stac::view {
namespace {

// A TCP connection to 127.0.0.1:port, closed with the object.
class Socket {
 public:
  explicit Socket(std::uint16_t port) : fd_(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = fd_ >= 0 && ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~Socket() {
    if (fd_ >= 0) ::close(fd_);
  }
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  [[nodiscard]] bool connected() const { return connected_; }

  bool write(const std::string& bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }
  // Exactly n bytes, or nothing when they do not come within the timeout (or the peer closes).
  std::optional<std::string> read(std::size_t n, std::chrono::milliseconds timeout) {
    std::string out;
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (out.size() < n) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      pollfd p{fd_, POLLIN, 0};
      if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) <= 0)
        return std::nullopt;
      char buffer[4096];
      const ssize_t got = ::recv(fd_, buffer, std::min(sizeof buffer, n - out.size()), 0);
      if (got <= 0) return std::nullopt;
      out.append(buffer, static_cast<std::size_t>(got));
    }
    return out;
  }

 private:
  int fd_;
  bool connected_ = false;
};

std::string handshake(std::uint16_t port) {
  return "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
         "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
         "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n";
}

// The HTTP status of the handshake's answer (0: none within the timeout).
int handshake_status(Socket& s) {
  std::string head;
  while (head.size() < 8192 && head.find("\r\n\r\n") == std::string::npos) {
    const auto byte = s.read(1, std::chrono::seconds(10));
    if (!byte) return 0;
    head += *byte;
  }
  return head.rfind("HTTP/1.1 ", 0) == 0 ? std::stoi(head.substr(9, 3)) : 0;
}

// A masked text frame, as a client must send it (RFC 6455 5.2).
std::string text_frame(const std::string& payload) {
  std::string f;
  f.push_back(static_cast<char>(0x81));
  if (payload.size() < 126) {
    f.push_back(static_cast<char>(0x80 | payload.size()));
  } else {
    f.push_back(static_cast<char>(0x80 | 126));
    f.push_back(static_cast<char>(payload.size() >> 8));
    f.push_back(static_cast<char>(payload.size() & 0xFF));
  }
  const char mask[4] = {0x12, 0x34, 0x56, 0x78};
  f.append(mask, 4);
  for (std::size_t i = 0; i < payload.size(); ++i) f.push_back(payload[i] ^ mask[i % 4]);
  return f;
}

struct Frame {
  int opcode;
  std::string payload;
};

// The next frame from the server (unmasked), or nothing within the timeout.
std::optional<Frame> read_frame(Socket& s, std::chrono::milliseconds timeout) {
  const auto head = s.read(2, timeout);
  if (!head) return std::nullopt;
  std::uint64_t length = static_cast<unsigned char>((*head)[1]) & 0x7F;
  const std::size_t extra = length == 126 ? 2 : length == 127 ? 8 : 0;
  if (extra != 0) {
    const auto bytes = s.read(extra, timeout);
    if (!bytes) return std::nullopt;
    length = 0;
    for (char c : *bytes) length = length << 8 | static_cast<unsigned char>(c);
  }
  const auto payload = s.read(static_cast<std::size_t>(length), timeout);
  if (!payload) return std::nullopt;
  return Frame{static_cast<unsigned char>((*head)[0]) & 0x0F, *payload};
}

std::vector<Channel> two_channels() {
  return {{"/a", "stac.A", R"({"type":"object"})"}, {"/b", "stac.B", R"({"type":"object"})"}};
}

TEST(FoxgloveServer, ClientsConnectingTogetherAreHeldToTheLimit) {
  ServerOptions options;
  options.port = 0;
  options.max_clients = 4;
  std::string error;
  auto server = FoxgloveServer::start(options, two_channels(), error);
  ASSERT_TRUE(server) << error;
  // Thirty connections send their handshakes before any answer is read: the server sees them
  // all in progress at once, as a crowd of simultaneous connects does.
  std::vector<std::unique_ptr<Socket>> sockets;
  for (int i = 0; i < 30; ++i) {
    sockets.push_back(std::make_unique<Socket>(server->port()));
    ASSERT_TRUE(sockets.back()->connected());
  }
  for (auto& s : sockets) ASSERT_TRUE(s->write(handshake(server->port())));
  int accepted = 0, refused = 0;
  for (auto& s : sockets) {
    const int status = handshake_status(*s);
    accepted += status == 101;
    refused += status == 503;
  }
  EXPECT_EQ(accepted, 4);
  EXPECT_EQ(refused, 26);
  const ServerCounts counts = server->counts();
  EXPECT_EQ(counts.clients_accepted, 4u);
  EXPECT_EQ(counts.clients_refused, 26u);
  EXPECT_EQ(counts.clients_now, 4u);
  // When the accepted ones leave, others may come.
  sockets.clear();
  for (int i = 0; i < 100 && server->counts().clients_now != 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  Socket late(server->port());
  ASSERT_TRUE(late.write(handshake(server->port())));
  EXPECT_EQ(handshake_status(late), 101);
}

TEST(FoxgloveServer, AClientGetsOneSubscriptionPerChannelAndNoIdPast32Bits) {
  ServerOptions options;
  options.port = 0;
  std::string error;
  auto server = FoxgloveServer::start(options, two_channels(), error);
  ASSERT_TRUE(server) << error;
  Socket client(server->port());
  ASSERT_TRUE(client.write(handshake(server->port())));
  ASSERT_EQ(handshake_status(client), 101);
  ASSERT_TRUE(client.write(text_frame(
      R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":1},{"id":8,"channelId":1},)"
      R"({"id":4294967303,"channelId":2},{"id":9,"channelId":2}]})")));
  for (int i = 0; i < 250 && !server->subscribed(1); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(server->subscribed(0));
  ASSERT_TRUE(server->subscribed(1));
  server->publish(0, 1, R"({"x":1})");
  server->publish(1, 2, R"({"x":2})");
  // serverInfo, advertise, two statuses (the second subscription to channel 1, the wide id),
  // then one message per channel: under ids 7 and 9.
  std::vector<std::string> statuses;
  std::vector<std::uint32_t> message_ids;
  while (const auto frame = read_frame(client, std::chrono::milliseconds(1500))) {
    if (frame->opcode == 0x1 && frame->payload.find(R"("op":"status")") != std::string::npos)
      statuses.push_back(frame->payload);
    if (frame->opcode == 0x2 && frame->payload.size() >= 5) {
      std::uint32_t id = 0;
      for (int b = 4; b >= 1; --b) id = id << 8 | static_cast<unsigned char>(frame->payload[b]);
      message_ids.push_back(id);
    }
  }
  ASSERT_EQ(statuses.size(), 2u);
  EXPECT_NE(statuses[0].find("already subscribed to channel 1"), std::string::npos) << statuses[0];
  EXPECT_NE(statuses[1].find("4294967303 is over 2^32-1"), std::string::npos) << statuses[1];
  EXPECT_EQ(message_ids, (std::vector<std::uint32_t>{7, 9}));
  EXPECT_EQ(server->counts().bad_client_messages, 2u);
}

}  // namespace
}  // namespace stac::view

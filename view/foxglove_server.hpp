// A Foxglove WebSocket protocol server (foxglove.websocket.v1, JSON-encoded channels), the
// transport of `stac view` (docs/view.md). It advertises a fixed set of channels; each client
// subscribes to the ones it wants and gets every message published on them while it keeps up:
// a client with more than max_client_buffer_bytes still unsent is skipped (counted per channel),
// so a slow or vanished viewer never grows memory or slows the caller. Networking runs on the
// server's own thread (websocketpp on standalone asio); publish() may be called from any thread.
// This header is C++17, as its source must be (websocketpp 0.8 does not compile as C++20).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace stac::view {

struct Channel {
  std::string topic;        // e.g. "/stac/point_cloud"
  std::string schema_name;  // e.g. "foxglove.PointCloud"
  std::string schema;       // its JSON schema (the messages are JSON)
};

struct ServerOptions {
  std::string address = "127.0.0.1";  // IPv4 address to listen on
  std::uint16_t port = 8765;          // 0: any free port (port() says which)
  std::string name = "stac view";     // serverInfo's name
  std::size_t max_clients = 16;       // more are refused at the handshake (ones in progress count)
  std::size_t max_client_buffer_bytes = 16u << 20;  // per client, unsent bytes
  std::size_t max_pending_messages = 64;            // handed over, not yet on the server thread
};

struct ChannelCounts {
  std::uint64_t published = 0;            // publish() calls
  std::uint64_t sent = 0;                 // messages queued to a subscribed client
  std::uint64_t dropped_slow_client = 0;  // a subscribed client had too much unsent
  std::uint64_t dropped_backlog = 0;      // the server thread was max_pending_messages behind
};

// One client's messages (every channel), for the first kClientRecords clients accepted.
struct ClientCounts {
  std::uint64_t number = 0;  // 1 for the first client accepted
  std::string peer;          // its address and port
  std::uint64_t sent = 0;
  std::uint64_t dropped_slow_client = 0;  // it had too much unsent
};
inline constexpr std::size_t kClientRecords = 64;

struct ServerCounts {
  std::uint64_t clients_accepted = 0;
  std::uint64_t clients_refused = 0;  // no foxglove.websocket.v1 subprotocol, or too many clients
  std::uint64_t bad_client_messages = 0;  // not JSON, unknown op, unknown channel (status sent)
  std::size_t clients_now = 0;
  std::vector<ChannelCounts> channels;  // in the order given to start()
  std::vector<ClientCounts> clients;    // in the order accepted, kClientRecords at most
};

class FoxgloveServer {
 public:
  // Listens and starts the server thread. Errors (address in use, bad address) are returned in
  // `error` with a null result.
  static std::unique_ptr<FoxgloveServer> start(const ServerOptions& options,
                                               std::vector<Channel> channels, std::string& error);
  ~FoxgloveServer();  // closes the connections and joins the thread
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  [[nodiscard]] std::uint16_t port() const noexcept;
  // True while some client is subscribed to `channel` (to skip building unwanted messages).
  [[nodiscard]] bool subscribed(std::size_t channel) const noexcept;
  // Sends `json` to every client subscribed to `channel`, stamped `time_ns` (the sample's time).
  void publish(std::size_t channel, std::uint64_t time_ns, std::string json);
  [[nodiscard]] ServerCounts counts() const;

  struct Impl;

 private:
  explicit FoxgloveServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace stac::view

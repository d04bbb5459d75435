// The Foxglove WebSocket server on websocketpp + standalone asio. Compiled as C++17 (its own
// library, view/CMakeLists.txt). Everything that touches connections or subscriptions runs
// on the server thread: publish() posts there, bounded by max_pending_messages.
#define ASIO_STANDALONE
#include "view/foxglove_server.hpp"

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>
#include <utility>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include "view/client_messages.hpp"

namespace stac::view {
namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;
constexpr const char* kSubprotocol = "foxglove.websocket.v1";
constexpr std::uint8_t kMessageDataOpcode = 0x01;
constexpr std::size_t kMaxClientMessageBytes = std::size_t{64} * 1024;
// A connection must finish its WebSocket handshake within this, and answer a close within it.
constexpr long kHandshakeTimeoutMs = 5000;

struct Client {
  Handle handle;
  Subscriptions subscriptions;          // the client's id -> channel
  std::size_t record = kClientRecords;  // its ServerCounts::clients entry (none past the last)
};

// Little-endian bytes of v appended to out.
template <class T>
void put_le(std::string& out, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i)
    out.push_back(static_cast<char>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xFF));
}

}  // namespace

struct FoxgloveServer::Impl {
  ServerOptions options;
  std::vector<Channel> channels;
  WsServer server;
  std::thread thread;
  std::uint16_t port = 0;
  // Server thread only:
  std::map<Handle, Client, std::owner_less<Handle>> clients;
  // Handshakes accepted (validate said yes) whose connection is not open yet: they count against
  // max_clients too, or connections arriving together would all pass before any is open.
  std::set<Handle, std::owner_less<Handle>> admitted;
  struct ClientDelta {
    std::size_t record;
    std::uint64_t sent, slow;
  };
  std::vector<ClientDelta> per_client;  // deliver()'s, kept to reuse its storage
  // Any thread:
  std::vector<std::atomic<int>> subscribers;  // per channel: subscriptions to it
  std::atomic<std::size_t> pending{0};
  std::atomic<std::size_t> open_clients{0};
  mutable std::mutex counts_mutex;  // guards counts (updated on the server thread and in publish)
  ServerCounts counts;

  explicit Impl(std::size_t n) : subscribers(n) { counts.channels.resize(n); }

  void count(const std::function<void(ServerCounts&)>& f) {
    const std::lock_guard<std::mutex> lock(counts_mutex);
    f(counts);
  }

  void send_text(const Handle& h, const nlohmann::json& j) {
    websocketpp::lib::error_code ec;
    server.send(h, j.dump(), websocketpp::frame::opcode::text, ec);
  }

  void status(const Handle& h, int level, const std::string& message) {
    send_text(h, {{"op", "status"}, {"level", level}, {"message", message}});
    if (level == 2) count([](ServerCounts& c) { ++c.bad_client_messages; });
  }

  bool validate(const Handle& h) {
    WsServer::connection_ptr con = server.get_con_from_hdl(h);
    bool speaks = false;
    for (const std::string& p : con->get_requested_subprotocols())
      speaks = speaks || p == kSubprotocol;
    if (!speaks || clients.size() + admitted.size() >= options.max_clients) {
      con->set_status(speaks ? websocketpp::http::status_code::service_unavailable
                             : websocketpp::http::status_code::bad_request);
      count([](ServerCounts& c) { ++c.clients_refused; });
      return false;
    }
    con->select_subprotocol(kSubprotocol);
    admitted.insert(h);
    return true;
  }

  void open(const Handle& h) {
    admitted.erase(h);
    Client& client = clients[h] = Client{h, {}};
    ++open_clients;
    websocketpp::lib::error_code ec;
    WsServer::connection_ptr con = server.get_con_from_hdl(h, ec);
    const std::string peer = ec || !con ? std::string("?") : con->get_remote_endpoint();
    count([&](ServerCounts& c) {
      ++c.clients_accepted;
      c.clients_now = clients.size();
      if (c.clients.size() < kClientRecords) {
        client.record = c.clients.size();
        c.clients.push_back({c.clients_accepted, peer, 0, 0});
      }
    });
    send_text(h, {{"op", "serverInfo"},
                  {"name", options.name},
                  {"capabilities", nlohmann::json::array()},
                  {"supportedEncodings", nlohmann::json::array()},
                  {"metadata", nlohmann::json::object()},
                  {"sessionId",
                   std::to_string(std::chrono::steady_clock::now().time_since_epoch().count())}});
    nlohmann::json list = nlohmann::json::array();
    for (std::size_t i = 0; i < channels.size(); ++i) {
      list.push_back({{"id", i + 1},
                      {"topic", channels[i].topic},
                      {"encoding", "json"},
                      {"schemaName", channels[i].schema_name},
                      {"schema", channels[i].schema},
                      {"schemaEncoding", "jsonschema"}});
    }
    send_text(h, {{"op", "advertise"}, {"channels", list}});
  }

  void closed(const Handle& h) {
    admitted.erase(h);  // a handshake accepted that failed before the connection opened
    auto it = clients.find(h);
    if (it == clients.end()) return;
    for (const auto& [id, channel] : it->second.subscriptions) --subscribers[channel];
    clients.erase(it);
    --open_clients;
    count([this](ServerCounts& c) { c.clients_now = clients.size(); });
  }

  void message(const Handle& h, const WsServer::message_ptr& m) {
    auto it = clients.find(h);
    if (it == clients.end()) return;
    Client& client = it->second;
    if (m->get_opcode() != websocketpp::frame::opcode::text) {
      status(h, 2, "stac view takes JSON text messages only (subscribe, unsubscribe)");
      return;
    }
    const ClientMessageEffect effect =
        apply_client_message(m->get_payload(), channels.size(), client.subscriptions);
    for (const auto& [channel, change] : effect.subscriber_changes) subscribers[channel] += change;
    for (const std::string& e : effect.errors) status(h, 2, e);
  }

  // On the server thread: the message to each subscriber that keeps up.
  void deliver(std::size_t channel, std::uint64_t time_ns, const std::string& json) {
    std::uint64_t sent = 0, slow = 0;
    per_client.clear();  // (record, sent, slow) of this message
    for (auto& [handle, client] : clients) {
      websocketpp::lib::error_code ec;
      WsServer::connection_ptr con = server.get_con_from_hdl(handle, ec);
      if (ec || !con) continue;
      for (const auto& [id, ch] : client.subscriptions) {
        if (ch != channel) continue;
        if (con->get_buffered_amount() > options.max_client_buffer_bytes) {
          ++slow;
          per_client.push_back({client.record, 0, 1});
          continue;
        }
        std::string frame;
        frame.reserve(13 + json.size());
        frame.push_back(static_cast<char>(kMessageDataOpcode));
        put_le(frame, id);
        put_le(frame, time_ns);
        frame += json;
        con->send(frame, websocketpp::frame::opcode::binary);
        ++sent;
        per_client.push_back({client.record, 1, 0});
      }
    }
    count([&](ServerCounts& c) {
      c.channels[channel].sent += sent;
      c.channels[channel].dropped_slow_client += slow;
      for (const ClientDelta& d : per_client) {
        if (d.record >= c.clients.size()) continue;
        c.clients[d.record].sent += d.sent;
        c.clients[d.record].dropped_slow_client += d.slow;
      }
    });
  }
};

FoxgloveServer::FoxgloveServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

std::unique_ptr<FoxgloveServer> FoxgloveServer::start(const ServerOptions& options,
                                                      std::vector<Channel> channels,
                                                      std::string& error) {
  auto impl = std::make_unique<Impl>(channels.size());
  impl->options = options;
  impl->channels = std::move(channels);
  Impl& s = *impl;
  WsServer& ws = s.server;
  ws.clear_access_channels(websocketpp::log::alevel::all);
  ws.clear_error_channels(websocketpp::log::elevel::all);
  websocketpp::lib::error_code ec;
  ws.init_asio(ec);
  if (ec) {
    error = "cannot start the WebSocket server: " + ec.message();
    return nullptr;
  }
  ws.set_reuse_addr(true);
  ws.set_max_message_size(kMaxClientMessageBytes);
  ws.set_open_handshake_timeout(kHandshakeTimeoutMs);
  ws.set_close_handshake_timeout(kHandshakeTimeoutMs);
  ws.set_validate_handler([&s](const Handle& h) { return s.validate(h); });
  ws.set_open_handler([&s](const Handle& h) { s.open(h); });
  ws.set_close_handler([&s](const Handle& h) { s.closed(h); });
  ws.set_fail_handler([&s](const Handle& h) { s.closed(h); });
  ws.set_message_handler(
      [&s](const Handle& h, const WsServer::message_ptr& m) { s.message(h, m); });
  asio::error_code aec;
  const asio::ip::address address = asio::ip::make_address(options.address, aec);
  if (aec) {
    error = "'" + options.address + "' is not an IP address";
    return nullptr;
  }
  ws.listen(asio::ip::tcp::endpoint(address, options.port), ec);
  if (ec) {
    error = "cannot listen on " + options.address + ":" + std::to_string(options.port) + ": " +
            ec.message() +
            (options.port != 0 ? " (is another stac view running? --port 0 takes a free one)" : "");
    return nullptr;
  }
  ws.start_accept(ec);
  if (ec) {
    error = "cannot accept connections: " + ec.message();
    return nullptr;
  }
  s.port = ws.get_local_endpoint(aec).port();
  s.thread = std::thread([&ws] { ws.run(); });
  return std::unique_ptr<FoxgloveServer>(new FoxgloveServer(std::move(impl)));
}

FoxgloveServer::~FoxgloveServer() {
  Impl& s = *impl_;
  asio::post(s.server.get_io_service(), [&s] {
    websocketpp::lib::error_code ec;
    s.server.stop_listening(ec);
    for (auto& [handle, client] : s.clients)
      s.server.close(handle, websocketpp::close::status::going_away, "stac view stops", ec);
  });
  // The closes finish on the server thread; then no work is left and run() returns. A client that
  // never answers its close is cut after a short wait.
  for (int i = 0; i < 100 && !s.server.stopped(); ++i) {
    if (s.open_clients.load() == 0 && s.pending.load() == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  s.server.stop();
  if (s.thread.joinable()) s.thread.join();
}

std::uint16_t FoxgloveServer::port() const noexcept {
  return impl_->port;
}

bool FoxgloveServer::subscribed(std::size_t channel) const noexcept {
  return channel < impl_->subscribers.size() && impl_->subscribers[channel].load() > 0;
}

void FoxgloveServer::publish(std::size_t channel, std::uint64_t time_ns, std::string json) {
  Impl& s = *impl_;
  if (channel >= s.channels.size()) return;
  const bool behind = s.pending.load() >= s.options.max_pending_messages;
  s.count([&](ServerCounts& c) {
    ++c.channels[channel].published;
    if (behind) ++c.channels[channel].dropped_backlog;
  });
  if (behind) return;
  ++s.pending;
  asio::post(s.server.get_io_service(), [&s, channel, time_ns, j = std::move(json)] {
    s.deliver(channel, time_ns, j);
    --s.pending;
  });
}

ServerCounts FoxgloveServer::counts() const {
  const std::lock_guard<std::mutex> lock(impl_->counts_mutex);
  return impl_->counts;
}

}  // namespace stac::view

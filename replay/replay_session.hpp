// A replay session (`stac replay`): a capture's UDP payloads sent again over a socket and its TCP
// streams served as TCP servers, at the recorded pace on one clock (for hardware-in-the-loop runs
// and tests), with faults on demand and a candump log's frames sent beside them as cannelloni
// datagrams; the achieved rate and the pacing error reported per stream.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::replay {

struct SessionOptions {
  std::string in;  // the capture
  std::string to = "127.0.0.1";
  int port = -1;         // -1: each datagram's captured destination port
  int filter_port = -1;  // -1: every captured UDP port
  double rate = 1.0;     // speed factor
  bool fast = false;     // no pacing
  std::uint64_t loops = 1;
  bool forever = false;
  std::vector<std::string> tcp_ports;  // "P" or "P:LISTEN_PORT"; empty: every captured one
  std::string tcp_listen = "127.0.0.1";
  bool no_tcp = false;
  bool wait_tcp = false;  // start once a client is connected to every served port
  std::string faults;     // replay/faults.hpp
  std::string can_log;    // a candump log sent as cannelloni datagrams
  int can_port = 20000;
};

// Its report lines, whole, as it goes (what it opened, then what each stream sent).
using Say = std::function<void(const std::string&)>;

// Runs the session until every pass is sent or `stop` is set (then it reports what was sent); an
// error says what to fix.
rt::Status run_session(const SessionOptions& options, std::atomic<bool>& stop, const Say& say);

}  // namespace stac::replay

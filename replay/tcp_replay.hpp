// Serves the server->client byte stream of a captured TCP connection (e.g. the Applanix POS LV
// Real-Time Data port 5602) as a TCP server: the bytes sent from the captured server port are
// reassembled in order (retransmissions dropped, holes skipped and counted; TcpReassembler) and
// written to the connected client, each chunk at its segment's capture time divided by a rate
// on an absolute CLOCK_MONOTONIC schedule (replay_pacing.hpp; shareable with a UdpReplay of the
// same capture), or as fast as the client takes them.
//
// The stream runs like a live device's: it follows the clock whether or not a client is
// connected. One client at a time; a client that connects (again) gets the stream from the next
// chunk on; chunks due while none is connected are not sent (counted as unserved); the same
// with fast (no clock), so call wait_for_client() first. At the end of the last pass the
// connection is closed (the client sees end of stream).
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "replay/faults.hpp"
#include "replay/replay_pacing.hpp"
#include "rt/expected.hpp"
#include "rt/unique_fd.hpp"

namespace stac::replay {

struct TcpReplayConfig {
  std::uint16_t server_port = 5602;          // captured server port whose stream is served
  std::string listen_address = "127.0.0.1";  // IPv4 address to listen on
  std::optional<std::uint16_t> listen_port;  // default: server_port; 0: any free port
  double rate = 1.0;                         // > 0: recorded time differences are divided by it
  bool fast = false;                         // no pacing
  std::uint64_t loops = 1;                   // passes over the stream; 0: until stopped
  int stall_timeout_ms = 2000;               // a client that takes no byte this long is dropped
};

struct TcpReplayPlan {         // one pass (found by open())
  std::uint64_t segments = 0;  // captured segments with payload from the server port
  std::uint64_t bytes = 0;     // stream bytes after reassembly
  std::int64_t first_stamp_ns = 0;
  std::int64_t span_ns = 0;         // first to last segment with payload
  std::int64_t pass_period_ns = 0;  // span plus one mean gap between segments
  std::uint64_t streams = 0;        // captured connections (concatenated into one stream)
  std::uint64_t retransmitted = 0, gaps = 0, gap_bytes = 0;
};

struct TcpReplayReport {
  std::uint64_t bytes = 0;           // accepted by the client's socket
  std::uint64_t segments = 0;        // chunks written to a client
  std::uint64_t unserved_bytes = 0;  // due while no client was connected
  std::uint64_t clients = 0;         // connections served (incl. one from wait_for_client())
  std::uint64_t disconnects = 0;     // clients gone (closed, reset) or dropped for stalling
  std::uint64_t stalls = 0;          // of which dropped after stall_timeout_ms
  std::uint64_t passes = 0;          // passes completed
  bool stopped = false;              // ended by the stop flag
  std::int64_t scheduled_ns = 0;     // scheduled time of the last chunk, from the clock's start
  std::int64_t elapsed_ns = 0;       // measured time from the clock's start to the last write
  // |write time - scheduled time| of the chunks written (median and p99 to 1 us, floor; max
  // exact); -1 with fast or when none was written.
  std::int64_t error_median_ns = -1, error_p99_ns = -1, error_max_ns = -1;
  std::optional<StreamFaultCounts> faults;  // what the faults did (after inject())
};

class TcpReplay {
 public:
  // The captured server ports: source ports of SYN+ACK segments, else of payload segments sent
  // from a lower port to a higher one. Fails naming the file when it cannot be read.
  static rt::Result<std::vector<std::uint16_t>> server_ports(const std::filesystem::path& capture);

  // Plans the stream and starts listening. Fails naming the file when it is missing or damaged
  // or holds no stream bytes from config.server_port (listing the server ports it has), when
  // rate <= 0, or naming address and port when listening fails (in use, bad address).
  static rt::Result<TcpReplay> open(const std::filesystem::path& capture,
                                    const TcpReplayConfig& config);

  const TcpReplayPlan& plan() const noexcept { return plan_; }
  std::uint16_t listen_port() const noexcept { return listen_port_; }  // the bound one

  // Faults for the stream (faults.hpp), their capture time counted from `zero_stamp_ns` in
  // each pass.
  void inject(const StreamFaultPlan& plan, std::int64_t zero_stamp_ns);

  // Blocks until a client is connected (true) or `stop` is set (false).
  bool wait_for_client(const std::atomic<bool>& stop) noexcept;

  // Serves the passes; returns early (stopped = true) once `stop` is set (seen within 50 ms).
  // Without `shared`, the clock starts at the call with the stream's first segment. Fails only
  // when the capture cannot be read again. No allocation per chunk.
  rt::Result<TcpReplayReport> run(const std::atomic<bool>& stop,
                                  const ReplayClock* shared = nullptr);

 private:
  TcpReplay() = default;
  void accept_pending() noexcept;
  void check_client(TcpReplayReport& report) noexcept;
  void drop_client(TcpReplayReport& report) noexcept;
  bool write_all(std::span<const std::uint8_t> chunk, const std::atomic<bool>& stop,
                 TcpReplayReport& report) noexcept;

  std::filesystem::path capture_;
  TcpReplayConfig config_;
  TcpReplayPlan plan_;
  rt::UniqueFd listen_fd_;
  rt::UniqueFd client_fd_;
  std::uint16_t listen_port_ = 0;
  std::uint64_t accepted_ = 0;  // connections accepted since open()
  std::optional<StreamFaultInjector> faults_;
  std::int64_t faults_zero_ns_ = 0;
};

}  // namespace stac::replay

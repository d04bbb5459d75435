// Applanix messages from a file: a pcap/pcapng capture (UDP datagrams, then in-order TCP
// streams reassembled from the segments) or a raw byte stream as logged from the Real-Time
// Data port. The file kind is told by its first bytes. Offline use; the per-message path does
// not allocate.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/applanix/stream_parser.hpp"
#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/tcp_stream.hpp"

namespace stac::applanix {

struct CaptureCounters {
  std::uint64_t datagrams = 0;  // UDP payloads parsed
  std::uint64_t segments = 0;   // TCP segments added to the reassembler
  std::uint64_t raw_bytes = 0;  // bytes read from a raw stream file
};

class CaptureReader {
 public:
  // port: UDP datagrams to this port and TCP segments from it (the POS side). Without one:
  // the POS ports 5600-5603. Fails naming the file when it cannot be read.
  static rt::Result<CaptureReader> open(const std::filesystem::path& path,
                                        std::optional<std::uint16_t> port = {});

  // The next message: all UDP messages in capture order first, then the TCP streams' messages
  // (a pcap holding both gives them grouped by transport). False at the end or on a read error.
  bool next(Parsed& out) noexcept;

  bool is_pcap() const noexcept { return is_pcap_; }
  // Empty, or why reading stopped early (a damaged capture or file).
  const std::string& error() const noexcept { return error_; }
  const StreamParser& parser() const noexcept { return parser_; }
  const CaptureCounters& counters() const noexcept { return counters_; }
  const io::TcpReassemblerCounters& tcp_counters() const noexcept {
    return reassembler_.counters();
  }
  const io::PcapCounters& pcap_counters() const noexcept { return pcap_totals_; }

 private:
  struct FileCloser {
    void operator()(std::FILE* f) const noexcept;
  };
  CaptureReader() = default;
  bool wanted(std::uint16_t port) const noexcept;
  bool refill() noexcept;  // feeds the parser its next chunk; false at the end
  void finish_pass() noexcept;

  std::filesystem::path path_;
  std::optional<std::uint16_t> port_;
  std::unique_ptr<io::PcapReader> pcap_;
  bool is_pcap_ = false;
  int pass_ = 0;  // pcap: 0 UDP, 1 TCP, 2 done
  bool tcp_finished_ = false;
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::vector<std::uint8_t> block_;
  StreamParser parser_{65536};
  io::TcpReassembler reassembler_;
  io::PcapCounters pcap_totals_;
  CaptureCounters counters_;
  std::string error_;
};

}  // namespace stac::applanix

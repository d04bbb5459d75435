// Reads UDP datagrams (next) or TCP segments (next_tcp) from a pcap or pcapng file (libpcap) with
// nanosecond stamps. Link types: Ethernet (with 802.1Q/802.1ad tags), Linux cooked v1 and v2, raw
// IPv4. Frames of other protocols, fragments, and frames shorter than their headers say are
// skipped and counted. Use one reader for one of the two calls.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "drivers/io/datagram.hpp"
#include "drivers/io/tcp_stream.hpp"
#include "rt/expected.hpp"

struct pcap;

namespace stac::io {

struct PcapFilter {
  std::optional<std::uint16_t> udp_dst_port;  // keep only datagrams to this port
  std::optional<std::uint16_t> udp_src_port;  // and/or from this port
};

struct TcpFilter {                        // for next_tcp()
  std::optional<std::uint16_t> src_port;  // keep only segments from this port
  std::optional<std::uint16_t> dst_port;  // and/or to this port
};

struct PcapCounters {
  std::uint64_t frames = 0;           // records read
  std::uint64_t datagrams = 0;        // UDP datagrams returned
  std::uint64_t non_ipv4 = 0;         // other link-layer payloads (ARP, IPv6, ...)
  std::uint64_t non_udp = 0;          // next(): IPv4 but not UDP (TCP, ICMP, ...)
  std::uint64_t segments = 0;         // next_tcp(): TCP segments returned
  std::uint64_t non_tcp = 0;          // next_tcp(): IPv4 but not TCP
  std::uint64_t filtered_out = 0;     // UDP on other ports
  std::uint64_t fragments = 0;        // IPv4 fragments (not reassembled)
  std::uint64_t truncated_frame = 0;  // captured shorter than its headers or UDP length say
  std::uint64_t bad_header = 0;       // impossible IPv4/UDP header fields
};

class PcapReader {
 public:
  // Fails with the file name and libpcap's reason (missing file, not a capture, unknown link).
  static rt::Result<PcapReader> open(const std::filesystem::path& path,
                                     const PcapFilter& filter = {},
                                     const TcpFilter& tcp_filter = {});
  // The same over bytes in memory (they must outlive the reader); `name` stands for the file in
  // messages.
  static rt::Result<PcapReader> open_memory(std::span<const std::uint8_t> bytes,
                                            const std::string& name, const PcapFilter& filter = {},
                                            const TcpFilter& tcp_filter = {});

  // The next datagram that passes the filter; false at the end of the file or on a damaged
  // record (error() then says which). No allocation.
  bool next(Datagram& out) noexcept;

  // The next TCP segment that passes the filter (payload possibly empty: SYN, FIN, ACK); same
  // end and error rules as next(). Feed one direction to a TcpReassembler for the byte stream.
  bool next_tcp(TcpSegment& out) noexcept;

  // Empty, or why reading stopped early (a truncated or corrupt file), naming file and record.
  const std::string& error() const noexcept { return error_; }
  const PcapCounters& counters() const noexcept { return counters_; }
  // Bytes of the file consumed so far (for progress bars).
  std::uint64_t bytes_read() const noexcept { return bytes_read_; }

 private:
  struct Closer {
    void operator()(pcap* p) const noexcept;
  };
  PcapReader() = default;
  // Takes an opened handle: checks its link type.
  static rt::Result<PcapReader> adopt(pcap* p, const std::filesystem::path& path,
                                      const PcapFilter& filter, const TcpFilter& tcp_filter);
  bool parse(const std::uint8_t* frame, std::uint32_t caplen, Datagram& out) noexcept;
  bool parse_tcp(const std::uint8_t* frame, std::uint32_t caplen, TcpSegment& out) noexcept;
  // The IPv4 header of a frame (link layer, version, lengths checked) or nullptr (counted);
  // ip_bytes: captured bytes from the start of the IP header.
  const std::uint8_t* ipv4(const std::uint8_t* frame, std::uint32_t caplen,
                           std::uint32_t& ip_bytes) noexcept;
  const std::uint8_t* next_frame(std::int64_t& stamp_ns, std::uint32_t& caplen) noexcept;

  std::unique_ptr<pcap, Closer> handle_;
  std::string path_;
  std::string error_;
  PcapFilter filter_;
  TcpFilter tcp_filter_;
  int link_type_ = 0;
  PcapCounters counters_;
  std::uint64_t bytes_read_ = 24;  // file header
};

}  // namespace stac::io

// Writes UDP datagrams as Ethernet/IPv4/UDP frames (and TCP segments as Ethernet/IPv4/TCP) into a
// pcap file with nanosecond stamps (libpcap), readable by Wireshark, VeloView and PcapReader. For
// `stac record` and simulators.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "drivers/io/datagram.hpp"
#include "drivers/io/tcp_stream.hpp"
#include "rt/expected.hpp"

struct pcap;
struct pcap_dumper;

namespace stac::io {

class PcapWriter {
 public:
  static rt::Result<PcapWriter> open(const std::filesystem::path& path);

  // Payloads up to 65507 bytes; larger ones fail. Stamp and addresses come from `d`.
  rt::Status write_udp(const Datagram& d) noexcept;
  // One TCP segment with s.seq and s.flags (ACK number 0, window 65535, no options and no TCP
  // checksum); payloads up to 65495 bytes. For tests and replays of TCP streams.
  rt::Status write_tcp(const TcpSegment& s) noexcept;
  // Flushes and closes; reports a failed write (disk full, ...). Also run by the destructor.
  rt::Status close() noexcept;

 private:
  struct Closer {
    void operator()(pcap* p) const noexcept;
  };
  struct DumpCloser {
    void operator()(pcap_dumper* d) const noexcept;
  };
  PcapWriter() = default;
  void write_frame(std::uint8_t protocol, std::uint32_t src_ip, std::uint32_t dst_ip,
                   std::size_t l4_bytes, std::int64_t stamp_ns) noexcept;

  std::unique_ptr<pcap, Closer> handle_;
  std::unique_ptr<pcap_dumper, DumpCloser> dumper_;
  std::string path_;
  std::unique_ptr<std::array<std::uint8_t, 65536>> frame_;
  std::uint16_t ip_id_ = 0;
};

}  // namespace stac::io

// Writes UDP datagrams as Ethernet/IPv4/UDP frames into a pcap file with nanosecond stamps
// (libpcap), readable by Wireshark, VeloView and PcapReader. For `stac record` and simulators.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "drivers/io/datagram.hpp"
#include "rt/expected.hpp"

struct pcap;
struct pcap_dumper;

namespace stac::io {

class PcapWriter {
 public:
  static rt::Result<PcapWriter> open(const std::filesystem::path& path);

  // Payloads up to 65507 bytes; larger ones fail. Stamp and addresses come from `d`.
  rt::Result<bool> write_udp(const Datagram& d) noexcept;
  // Flushes and closes; reports a failed write (disk full, ...). Also run by the destructor.
  rt::Result<bool> close() noexcept;

 private:
  struct Closer {
    void operator()(pcap* p) const noexcept;
  };
  struct DumpCloser {
    void operator()(pcap_dumper* d) const noexcept;
  };
  PcapWriter() = default;

  std::unique_ptr<pcap, Closer> handle_;
  std::unique_ptr<pcap_dumper, DumpCloser> dumper_;
  std::string path_;
  std::unique_ptr<std::array<std::uint8_t, 65536>> frame_;
  std::uint16_t ip_id_ = 0;
};

}  // namespace stac::io

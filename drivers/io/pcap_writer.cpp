#include "drivers/io/pcap_writer.hpp"

#include <pcap/pcap.h>

#include <cstdio>
#include <cstring>

namespace stac::io {
namespace {

constexpr std::size_t kEthernet = 14, kIpv4 = 20, kUdp = 8, kTcp = 20;
constexpr std::size_t kMaxPayload = 65535 - kIpv4 - kUdp;

void put16(std::uint8_t* p, std::uint32_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}
void put32(std::uint8_t* p, std::uint32_t v) noexcept {
  put16(p, v >> 16);
  put16(p + 2, v & 0xFFFFu);
}

std::uint16_t ipv4_checksum(const std::uint8_t* h) noexcept {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i < kIpv4; i += 2)
    sum += static_cast<std::uint32_t>((h[i] << 8) | h[i + 1]);
  while (sum >> 16) sum = (sum & 0xFFFFu) + (sum >> 16);
  return static_cast<std::uint16_t>(~sum);
}

}  // namespace

void PcapWriter::Closer::operator()(pcap* p) const noexcept {
  if (p != nullptr) pcap_close(p);
}
void PcapWriter::DumpCloser::operator()(pcap_dumper* d) const noexcept {
  if (d != nullptr) pcap_dump_close(d);
}

rt::Result<PcapWriter> PcapWriter::open(const std::filesystem::path& path) {
  PcapWriter w;
  w.path_ = path.string();
  w.handle_.reset(
      pcap_open_dead_with_tstamp_precision(DLT_EN10MB, 65535, PCAP_TSTAMP_PRECISION_NANO));
  if (!w.handle_) return rt::make_error(w.path_ + ": libpcap could not start a capture file");
  w.dumper_.reset(pcap_dump_open(w.handle_.get(), path.c_str()));
  if (!w.dumper_) {
    return rt::make_error(w.path_ + ": cannot create: " + pcap_geterr(w.handle_.get()));
  }
  w.frame_ = std::make_unique<std::array<std::uint8_t, 65536>>();
  std::uint8_t* f = w.frame_->data();
  std::memset(f, 0xFF, 6);  // destination: broadcast
  const std::uint8_t src_mac[6] = {0x60, 0x76, 0x88, 0x00, 0x00, 0x01};
  std::memcpy(f + 6, src_mac, 6);
  put16(f + 12, 0x0800);  // IPv4
  return w;
}

void PcapWriter::write_frame(std::uint8_t protocol, std::uint32_t src_ip, std::uint32_t dst_ip,
                             std::size_t l4_bytes, std::int64_t stamp_ns) noexcept {
  std::uint8_t* f = frame_->data();
  std::uint8_t* ip = f + kEthernet;
  ip[0] = 0x45;
  ip[1] = 0;
  put16(ip + 2, static_cast<std::uint32_t>(kIpv4 + l4_bytes));
  put16(ip + 4, ip_id_++);
  put16(ip + 6, 0x4000);  // don't fragment
  ip[8] = 64;
  ip[9] = protocol;
  put16(ip + 10, 0);
  put32(ip + 12, src_ip);
  put32(ip + 16, dst_ip);
  put16(ip + 10, ipv4_checksum(ip));
  pcap_pkthdr h{};
  h.ts.tv_sec = static_cast<time_t>(stamp_ns / 1'000'000'000);
  h.ts.tv_usec = static_cast<suseconds_t>(stamp_ns % 1'000'000'000);  // ns (nano precision)
  h.caplen = h.len = static_cast<bpf_u_int32>(kEthernet + kIpv4 + l4_bytes);
  pcap_dump(reinterpret_cast<u_char*>(dumper_.get()), &h, f);
}

rt::Status PcapWriter::write_udp(const Datagram& d) noexcept {
  if (!dumper_) return rt::make_error(path_ + ": already closed");
  if (d.payload.size() > kMaxPayload) {
    return rt::make_error(path_ + ": a UDP payload of " + std::to_string(d.payload.size()) +
                          " bytes does not fit one datagram");
  }
  std::uint8_t* udp = frame_->data() + kEthernet + kIpv4;
  const auto udp_len = static_cast<std::uint32_t>(kUdp + d.payload.size());
  put16(udp, d.src_port);
  put16(udp + 2, d.dst_port);
  put16(udp + 4, udp_len);
  put16(udp + 6, 0);  // no UDP checksum (allowed for IPv4)
  if (!d.payload.empty()) std::memcpy(udp + kUdp, d.payload.data(), d.payload.size());
  write_frame(17, d.src_ip, d.dst_ip, udp_len, d.stamp_ns);
  return {};
}

rt::Status PcapWriter::write_tcp(const TcpSegment& s) noexcept {
  if (!dumper_) return rt::make_error(path_ + ": already closed");
  if (s.payload.size() > kMaxPayload + kUdp - kTcp) {
    return rt::make_error(path_ + ": a TCP payload of " + std::to_string(s.payload.size()) +
                          " bytes does not fit one segment");
  }
  std::uint8_t* tcp = frame_->data() + kEthernet + kIpv4;
  put16(tcp, s.src_port);
  put16(tcp + 2, s.dst_port);
  put32(tcp + 4, s.seq);
  put32(tcp + 8, 0);          // acknowledgement number
  tcp[12] = (kTcp / 4) << 4;  // data offset, no options
  tcp[13] = s.flags;
  put16(tcp + 14, 65535);  // window
  put16(tcp + 16, 0);      // checksum not computed
  put16(tcp + 18, 0);      // urgent pointer
  if (!s.payload.empty()) std::memcpy(tcp + kTcp, s.payload.data(), s.payload.size());
  write_frame(6, s.src_ip, s.dst_ip, kTcp + s.payload.size(), s.stamp_ns);
  return {};
}

rt::Status PcapWriter::close() noexcept {
  if (!dumper_) return {};
  const bool flushed = pcap_dump_flush(dumper_.get()) == 0;
  const bool ok = flushed && std::ferror(pcap_dump_file(dumper_.get())) == 0;
  dumper_.reset();
  if (!ok) return rt::make_error(path_ + ": write failed (disk full?)");
  return {};
}

}  // namespace stac::io

#include "drivers/io/pcap_reader.hpp"

#include <arpa/inet.h>
#include <pcap/pcap.h>

#include <cstdio>
#include <cstring>

namespace stac::io {
namespace {

constexpr int kLinkEthernet = DLT_EN10MB;
constexpr int kLinkCooked = DLT_LINUX_SLL;  // 113
constexpr int kLinkCooked2 = 276;           // DLT_LINUX_SLL2
constexpr int kLinkRaw = DLT_RAW;
constexpr int kLinkIpv4 = 228;  // DLT_IPV4
constexpr std::uint16_t kEtherIpv4 = 0x0800;
constexpr std::uint16_t kEtherVlan = 0x8100;
constexpr std::uint16_t kEtherQinQ = 0x88A8;
constexpr std::uint8_t kProtoUdp = 17;
constexpr std::uint8_t kProtoTcp = 6;

std::uint16_t be16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
std::uint32_t be32(const std::uint8_t* p) noexcept {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | p[3];
}

}  // namespace

bool parse_ipv4(const char* text, std::uint32_t& out) noexcept {
  in_addr a{};
  if (inet_pton(AF_INET, text, &a) != 1) return false;
  out = ntohl(a.s_addr);
  return true;
}

void PcapReader::Closer::operator()(pcap* p) const noexcept {
  if (p != nullptr) pcap_close(p);
}

rt::Result<PcapReader> PcapReader::open(const std::filesystem::path& path, const PcapFilter& filter,
                                        const TcpFilter& tcp_filter) {
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  pcap* p =
      pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, errbuf);
  if (p == nullptr) {
    return rt::make_error(path.string() + ": cannot read as a pcap capture: " + errbuf);
  }
  return adopt(p, path, filter, tcp_filter);
}

rt::Result<PcapReader> PcapReader::open_memory(std::span<const std::uint8_t> bytes,
                                               const std::string& name, const PcapFilter& filter,
                                               const TcpFilter& tcp_filter) {
  if (bytes.empty()) return rt::make_error(name + ": cannot read as a pcap capture: empty");
  // libpcap reads a FILE*; fmemopen gives one over the bytes (read only: the cast is safe), and
  // pcap_close closes it.
  FILE* f = fmemopen(const_cast<std::uint8_t*>(bytes.data()), bytes.size(), "rb");
  if (f == nullptr) return rt::make_error(name + ": cannot read as a pcap capture: fmemopen");
  char errbuf[PCAP_ERRBUF_SIZE] = {};
  pcap* p = pcap_fopen_offline_with_tstamp_precision(f, PCAP_TSTAMP_PRECISION_NANO, errbuf);
  if (p == nullptr) {
    std::fclose(f);
    return rt::make_error(name + ": cannot read as a pcap capture: " + errbuf);
  }
  return adopt(p, name, filter, tcp_filter);
}

rt::Result<PcapReader> PcapReader::adopt(pcap* p, const std::filesystem::path& path,
                                         const PcapFilter& filter, const TcpFilter& tcp_filter) {
  PcapReader r;
  r.handle_.reset(p);
  r.path_ = path.string();
  r.filter_ = filter;
  r.tcp_filter_ = tcp_filter;
  r.link_type_ = pcap_datalink(p);
  switch (r.link_type_) {
    case kLinkEthernet:
    case kLinkCooked:
    case kLinkCooked2:
    case kLinkRaw:
    case kLinkIpv4:
      break;
    default:
      return rt::make_error(path.string() + ": link type " + std::to_string(r.link_type_) + " (" +
                            (pcap_datalink_val_to_name(r.link_type_)
                                 ? pcap_datalink_val_to_name(r.link_type_)
                                 : "?") +
                            ") is not supported; use Ethernet, Linux cooked or raw IP captures");
  }
  return r;
}

const std::uint8_t* PcapReader::ipv4(const std::uint8_t* f, std::uint32_t caplen,
                                     std::uint32_t& ip_bytes) noexcept {
  std::uint32_t off = 0;
  std::uint16_t proto = kEtherIpv4;
  switch (link_type_) {
    case kLinkEthernet:
      if (caplen < 14) {
        ++counters_.truncated_frame;
        return nullptr;
      }
      proto = be16(f + 12);
      off = 14;
      while (proto == kEtherVlan || proto == kEtherQinQ) {
        if (caplen < off + 4) {
          ++counters_.truncated_frame;
          return nullptr;
        }
        proto = be16(f + off + 2);
        off += 4;
      }
      break;
    case kLinkCooked:
      if (caplen < 16) {
        ++counters_.truncated_frame;
        return nullptr;
      }
      proto = be16(f + 14);
      off = 16;
      break;
    case kLinkCooked2:
      if (caplen < 20) {
        ++counters_.truncated_frame;
        return nullptr;
      }
      proto = be16(f);
      off = 20;
      break;
    default:  // raw IP
      break;
  }
  if (proto != kEtherIpv4 || caplen < off + 20 || (f[off] >> 4) != 4) {
    if (proto != kEtherIpv4 || (caplen >= off + 1 && (f[off] >> 4) != 4)) {
      ++counters_.non_ipv4;
    } else {
      ++counters_.truncated_frame;
    }
    return nullptr;
  }
  const std::uint8_t* ip = f + off;
  const std::uint32_t ihl = (ip[0] & 0x0Fu) * 4u;
  const std::uint16_t total = be16(ip + 2);
  if (ihl < 20 || total < ihl) {
    ++counters_.bad_header;
    return nullptr;
  }
  ip_bytes = caplen - off;
  return ip;
}

bool PcapReader::parse(const std::uint8_t* f, std::uint32_t caplen, Datagram& out) noexcept {
  std::uint32_t ip_bytes = 0;
  const std::uint8_t* ip = ipv4(f, caplen, ip_bytes);
  if (ip == nullptr) return false;
  const std::uint32_t ihl = (ip[0] & 0x0Fu) * 4u;
  const std::uint16_t total = be16(ip + 2);
  if (ip[9] != kProtoUdp) {
    ++counters_.non_udp;
    return false;
  }
  const std::uint16_t frag = be16(ip + 6);
  if ((frag & 0x2000u) != 0 || (frag & 0x1FFFu) != 0) {
    ++counters_.fragments;
    return false;
  }
  if (ip_bytes < ihl + 8) {
    ++counters_.truncated_frame;
    return false;
  }
  const std::uint8_t* udp = ip + ihl;
  const std::uint16_t udp_len = be16(udp + 4);
  if (udp_len < 8 || udp_len > total - ihl) {
    ++counters_.bad_header;
    return false;
  }
  if (ip_bytes < ihl + udp_len) {
    ++counters_.truncated_frame;
    return false;
  }
  out.src_ip = be32(ip + 12);
  out.dst_ip = be32(ip + 16);
  out.src_port = be16(udp);
  out.dst_port = be16(udp + 2);
  if ((filter_.udp_dst_port && out.dst_port != *filter_.udp_dst_port) ||
      (filter_.udp_src_port && out.src_port != *filter_.udp_src_port)) {
    ++counters_.filtered_out;
    return false;
  }
  out.payload = {udp + 8, static_cast<std::size_t>(udp_len - 8)};
  return true;
}

bool PcapReader::parse_tcp(const std::uint8_t* f, std::uint32_t caplen, TcpSegment& out) noexcept {
  std::uint32_t ip_bytes = 0;
  const std::uint8_t* ip = ipv4(f, caplen, ip_bytes);
  if (ip == nullptr) return false;
  const std::uint32_t ihl = (ip[0] & 0x0Fu) * 4u;
  const std::uint16_t total = be16(ip + 2);
  if (ip[9] != kProtoTcp) {
    ++counters_.non_tcp;
    return false;
  }
  const std::uint16_t frag = be16(ip + 6);
  if ((frag & 0x2000u) != 0 || (frag & 0x1FFFu) != 0) {
    ++counters_.fragments;
    return false;
  }
  if (ip_bytes < ihl + 20) {
    ++counters_.truncated_frame;
    return false;
  }
  const std::uint8_t* tcp = ip + ihl;
  const std::uint32_t data_offset = (tcp[12] >> 4) * 4u;
  if (data_offset < 20 || ihl + data_offset > total) {
    ++counters_.bad_header;
    return false;
  }
  if (ip_bytes < total) {
    ++counters_.truncated_frame;
    return false;
  }
  out.src_ip = be32(ip + 12);
  out.dst_ip = be32(ip + 16);
  out.src_port = be16(tcp);
  out.dst_port = be16(tcp + 2);
  if ((tcp_filter_.dst_port && out.dst_port != *tcp_filter_.dst_port) ||
      (tcp_filter_.src_port && out.src_port != *tcp_filter_.src_port)) {
    ++counters_.filtered_out;
    return false;
  }
  out.seq = be32(tcp + 4);
  out.flags = tcp[13];
  out.payload = {tcp + data_offset, static_cast<std::size_t>(total - ihl - data_offset)};
  return true;
}

const std::uint8_t* PcapReader::next_frame(std::int64_t& stamp_ns, std::uint32_t& caplen) noexcept {
  if (!handle_ || !error_.empty()) return nullptr;
  pcap_pkthdr* header = nullptr;
  const std::uint8_t* data = nullptr;
  const int rc = pcap_next_ex(handle_.get(), &header, &data);
  if (rc == PCAP_ERROR_BREAK) return nullptr;  // end of file
  if (rc != 1) {
    // Only reached on a damaged file: building the message may allocate, once.
    error_ = path_ + ": stopped after " + std::to_string(counters_.frames) +
             " records: " + pcap_geterr(handle_.get()) + " (truncated or corrupt capture)";
    return nullptr;
  }
  ++counters_.frames;
  bytes_read_ += 16 + header->caplen;
  // Nanosecond precision was requested at open: tv_usec holds nanoseconds.
  stamp_ns = static_cast<std::int64_t>(header->ts.tv_sec) * 1'000'000'000 + header->ts.tv_usec;
  caplen = header->caplen;
  return data;
}

bool PcapReader::next(Datagram& out) noexcept {
  std::int64_t stamp_ns = 0;
  std::uint32_t caplen = 0;
  while (const std::uint8_t* data = next_frame(stamp_ns, caplen)) {
    if (!parse(data, caplen, out)) continue;
    out.stamp_ns = stamp_ns;
    ++counters_.datagrams;
    return true;
  }
  return false;
}

bool PcapReader::next_tcp(TcpSegment& out) noexcept {
  std::int64_t stamp_ns = 0;
  std::uint32_t caplen = 0;
  while (const std::uint8_t* data = next_frame(stamp_ns, caplen)) {
    if (!parse_tcp(data, caplen, out)) continue;
    out.stamp_ns = stamp_ns;
    ++counters_.segments;
    return true;
  }
  return false;
}

}  // namespace stac::io

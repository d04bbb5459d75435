// One UDP datagram with where and when it was seen. The payload views storage owned by the
// source (reader or receiver) and stays valid until that source's next call.
#pragma once

#include <cstdint>
#include <span>

namespace stac::io {

struct Datagram {
  std::span<const std::uint8_t> payload;
  std::int64_t stamp_ns = 0;  // receive time, ns since the Unix epoch (pcap or kernel stamp)
  std::uint32_t src_ip = 0;   // IPv4, host byte order
  std::uint32_t dst_ip = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
};

// "a.b.c.d" -> host-order address; false when the text is not a dotted IPv4 address.
bool parse_ipv4(const char* text, std::uint32_t& out) noexcept;

}  // namespace stac::io

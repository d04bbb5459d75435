#include "drivers/can/cannelloni.hpp"

#include <algorithm>

namespace stac::can {
namespace {

std::uint32_t be32(const std::uint8_t* p) noexcept {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

}  // namespace

bool parse_cannelloni_header(std::span<const std::uint8_t> datagram,
                             CannelloniHeader& header) noexcept {
  if (datagram.size() < kCannelloniHeaderBytes) return false;
  header.version = datagram[0];
  header.op_code = datagram[1];
  header.sequence = datagram[2];
  header.count = static_cast<std::uint16_t>((datagram[3] << 8) | datagram[4]);
  return true;
}

CannelloniFrameKind parse_cannelloni_frame(std::span<const std::uint8_t> datagram, std::size_t at,
                                           Frame& frame, std::size_t& next) noexcept {
  if (at > datagram.size() || datagram.size() - at < 5) return CannelloniFrameKind::kTruncated;
  const std::uint8_t* p = datagram.data() + at;
  const std::uint8_t len = p[4];
  if ((len & kCannelloniFdFlag) != 0) {  // flags byte, then up to 64 data bytes
    const std::size_t bytes = 6u + (len & 0x7Fu);
    if ((len & 0x7Fu) > 64 || datagram.size() - at < bytes) return CannelloniFrameKind::kTruncated;
    next = at + bytes;
    return CannelloniFrameKind::kFd;
  }
  if (len > kMaxDataBytes || datagram.size() - at < 5u + len)
    return CannelloniFrameKind::kTruncated;
  from_socketcan_id(be32(p), frame);
  frame.dlc = len;
  frame.data = {};
  for (std::uint8_t i = 0; i < len; ++i) frame.data[i] = p[5 + i];
  next = at + 5u + len;
  return CannelloniFrameKind::kClassic;
}

std::size_t encode_cannelloni(std::span<const Frame> frames, std::uint8_t sequence,
                              std::span<std::uint8_t> out) noexcept {
  if (frames.size() > 0xFFFF || out.size() < kCannelloniHeaderBytes) return 0;
  std::size_t at = kCannelloniHeaderBytes;
  for (const Frame& f : frames) {
    // As cannelloni does: len is the DLC, and that many data bytes follow (a remote frame too).
    const std::uint8_t len = std::min(f.dlc, kMaxDataBytes);
    if (out.size() - at < 5u + len) return 0;
    const std::uint32_t id = to_socketcan_id(f);
    out[at] = static_cast<std::uint8_t>(id >> 24);
    out[at + 1] = static_cast<std::uint8_t>(id >> 16);
    out[at + 2] = static_cast<std::uint8_t>(id >> 8);
    out[at + 3] = static_cast<std::uint8_t>(id);
    out[at + 4] = len;
    for (std::uint8_t i = 0; i < len; ++i) out[at + 5 + i] = f.data[i];
    at += 5u + len;
  }
  out[0] = kCannelloniVersion;
  out[1] = kCannelloniData;
  out[2] = sequence;
  out[3] = static_cast<std::uint8_t>(frames.size() >> 8);
  out[4] = static_cast<std::uint8_t>(frames.size());
  return at;
}

rt::Result<CannelloniReader> CannelloniReader::open(const CannelloniConfig& config) {
  io::UdpReceiverConfig u;
  u.bind_address = config.bind_address;
  u.port = config.port;
  u.receive_buffer_bytes = 1 << 20;
  u.batch = 1;
  u.max_payload = static_cast<int>(kCannelloniMaxDatagram);
  auto udp = io::UdpReceiver::open(u);
  if (!udp) return rt::make_error("cannelloni (CAN over UDP): " + udp.error().message);
  return CannelloniReader(std::move(*udp));
}

void CannelloniReader::stop() noexcept {
  udp_.stop();
}

CannelloniCounters CannelloniReader::counters() const noexcept {
  CannelloniCounters c = counters_;
  c.kernel_drops = udp_.counters().kernel_drops;
  return c;
}

void CannelloniReader::begin() noexcept {
  ++counters_.datagrams;
  CannelloniHeader h;
  if (!parse_cannelloni_header(datagram_.payload, h) || h.version != kCannelloniVersion ||
      h.op_code != kCannelloniData) {
    ++counters_.malformed;
    left_ = 0;
    return;
  }
  // Sequence numbers count per sender: another address or port (a gateway restarted on a new
  // socket, or a second one) starts its own count instead of showing a gap.
  const bool same_sender =
      have_sequence_ && datagram_.src_ip == sender_ip_ && datagram_.src_port == sender_port_;
  if (same_sender) counters_.lost += static_cast<std::uint8_t>(h.sequence - last_sequence_ - 1);
  have_sequence_ = true;
  sender_ip_ = datagram_.src_ip;
  sender_port_ = datagram_.src_port;
  last_sequence_ = h.sequence;
  at_ = kCannelloniHeaderBytes;
  left_ = h.count;
  if (left_ == 0 && datagram_.payload.size() != kCannelloniHeaderBytes) ++counters_.malformed;
}

int CannelloniReader::read(std::span<Frame> out, int timeout_ms) noexcept {
  int count = 0;
  bool received = false;
  while (static_cast<std::size_t>(count) < out.size()) {
    if (left_ == 0) {
      // Waits only for the first datagram of a call; later ones only when already there.
      const int n = udp_.receive({&datagram_, 1}, received ? 0 : timeout_ms);
      received = true;
      if (n == io::UdpReceiver::kStopped) return kStopped;
      if (n < 0) return count > 0 ? count : kError;
      if (n == 0) break;
      begin();
      continue;
    }
    Frame& f = out[static_cast<std::size_t>(count)];
    std::size_t next = 0;
    switch (parse_cannelloni_frame(datagram_.payload, at_, f, next)) {
      case CannelloniFrameKind::kClassic:
        f.stamp_ns = datagram_.stamp_ns;
        ++count;
        ++counters_.frames;
        break;
      case CannelloniFrameKind::kFd:
        ++counters_.can_fd;
        break;
      case CannelloniFrameKind::kTruncated:
        ++counters_.malformed;
        left_ = 0;
        continue;
    }
    at_ = next;
    --left_;
  }
  return count;
}

}  // namespace stac::can

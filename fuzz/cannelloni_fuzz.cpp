// cannelloni datagrams (CAN over UDP, drivers/can/cannelloni.hpp) as CannelloniReader walks them:
// the header, then frame after frame while the count lasts, stopping at the first truncated one.
// Every position must advance and stay inside the datagram; every classic frame re-encodes to a
// datagram that parses back to the same frame.
#include <array>
#include <cstddef>
#include <cstdint>

#include "drivers/can/cannelloni.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace stac::can;
  const std::span<const std::uint8_t> datagram(data, size);
  CannelloniHeader header;
  if (!parse_cannelloni_header(datagram, header)) return 0;
  std::size_t at = kCannelloniHeaderBytes;
  for (std::uint16_t left = header.count; left > 0; --left) {
    Frame f;
    std::size_t next = 0;
    const CannelloniFrameKind kind = parse_cannelloni_frame(datagram, at, f, next);
    if (kind == CannelloniFrameKind::kTruncated) break;
    if (next <= at || next > size) __builtin_trap();
    if (kind == CannelloniFrameKind::kClassic) {
      if (f.dlc > kMaxDataBytes) __builtin_trap();
      std::array<std::uint8_t, kCannelloniHeaderBytes + 5 + kMaxDataBytes> again{};
      const std::size_t n = encode_cannelloni({&f, 1}, header.sequence, again);
      Frame back;
      std::size_t end = 0;
      if (n == 0 ||
          parse_cannelloni_frame(std::span(again).first(n), kCannelloniHeaderBytes, back, end) !=
              CannelloniFrameKind::kClassic ||
          end != n || back.id != f.id || back.extended != f.extended || back.dlc != f.dlc ||
          back.data != f.data)
        __builtin_trap();
    }
    at = next;
  }
  return 0;
}

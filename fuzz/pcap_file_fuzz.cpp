// Capture files: the input as a capture in memory (the same libpcap reading over fmemopen, no
// file per input), read as UDP datagrams (what `stac decode`, `process`
// and `replay` read) and as TCP segments put back into a byte stream (the INS over TCP). libpcap
// parses the file's records; the reader checks every link, IPv4, UDP and TCP header itself.
#include <cstddef>
#include <cstdint>
#include <span>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/tcp_stream.hpp"

// Where touch() leaves its sums, so that the reads cannot be optimized away.
volatile std::uint8_t pcap_fuzz_sink = 0;

namespace {

// Reads every byte a returned view claims, so that AddressSanitizer checks it lies in the record.
void touch(std::span<const std::uint8_t> bytes) {
  std::uint8_t sum = 0;
  for (const std::uint8_t b : bytes) sum = static_cast<std::uint8_t>(sum + b);
  pcap_fuzz_sink = sum;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  if (auto udp = stac::io::PcapReader::open_memory(bytes, "fuzz.pcap")) {
    stac::io::Datagram d;
    while (udp->next(d)) touch(d.payload);
  }
  if (auto tcp = stac::io::PcapReader::open_memory(bytes, "fuzz.pcap")) {
    stac::io::TcpReassembler stream(4, 2048);
    stac::io::TcpSegment s;
    std::span<const std::uint8_t> chunk;
    while (tcp->next_tcp(s)) {
      (void)stream.add(s);
      touch(s.payload);
      while (stream.next(chunk)) touch(chunk);
    }
    stream.finish();
    while (stream.next(chunk)) touch(chunk);
  }
  return 0;
}

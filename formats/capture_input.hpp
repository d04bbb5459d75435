// What a command reading a capture says about its input (stac decode, process, segment): the
// frames it skipped and the sensor packets it dropped, by cause, and why a capture gave nothing.
#pragma once

#include <cstdint>
#include <string>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/scan_assembler.hpp"

namespace stac::formats {

// "N frames: P to port X, T truncated (...), ..." (the causes that are not zero).
std::string capture_frames_summary(const io::PcapCounters& pc, std::uint64_t packets,
                                   std::uint16_t port);
// "wrong size N, invalid block N, duplicate N, late firings N, points over capacity N; estimated
// packets lost N, ..." (every cause, zero or not).
std::string packet_drops_summary(const velodyne::AssemblerCounters& a);
// Why a capture gave no complete scan: no packet to the port (and the likely reason: truncated
// frames, datagrams to other ports), or packets that were all dropped (by cause), or too few.
std::string nothing_decoded_reason(const std::string& capture, const io::PcapCounters& pc,
                                   const velodyne::AssemblerCounters& a, std::uint16_t port);

// The error of a capture that cannot be read to its end (the reader's error, which names the file,
// the record and the cause), for every command that reads one: it is never only a warning.
std::string capture_breaks_off(const std::string& reader_error);

}  // namespace stac::formats

#include "formats/capture_scans.hpp"

#include "drivers/io/pcap_reader.hpp"
#include "formats/capture_input.hpp"

namespace stac::formats {

rt::Result<std::uint64_t> for_each_complete_scan(
    const std::filesystem::path& capture, const velodyne::Calibration& calibration,
    const settings::VelodyneSettings& settings,
    const std::function<bool(const velodyne::Scan&)>& on_scan) {
  auto reader = io::PcapReader::open(
      capture, io::PcapFilter{.udp_dst_port = settings.port, .udp_src_port = {}});
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  velodyne::ScanStream stream(calibration, settings.assembler, 2);
  std::uint64_t complete = 0;
  bool more = true;
  const auto drain = [&] {
    while (const velodyne::Scan* scan = stream.take()) {
      if (more && scan->header.complete()) {
        ++complete;
        more = on_scan(*scan);
      }
      stream.release();
    }
  };
  io::Datagram d;
  while (more && reader->next(d)) {
    if (stream.add_packet(d.payload, d.stamp_ns)) drain();
  }
  if (more) {
    (void)stream.finish();
    drain();
  }
  if (complete == 0) {
    return rt::make_error(nothing_decoded_reason(capture.string(), reader->counters(),
                                                 stream.assembler().counters(), settings.port));
  }
  return complete;
}

}  // namespace stac::formats

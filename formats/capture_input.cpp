#include "formats/capture_input.hpp"

namespace stac::formats {

namespace {

std::string n(std::uint64_t v) {
  return std::to_string(v);
}

}  // namespace

std::string capture_frames_summary(const io::PcapCounters& pc, std::uint64_t packets,
                                   std::uint16_t port) {
  std::string s = n(pc.frames) + " frames: " + n(packets) + " UDP to port " + n(port);
  const auto add = [&](std::uint64_t v, const char* what) {
    if (v > 0) s += ", " + n(v) + " " + what;
  };
  add(pc.truncated_frame,
      "truncated (captured shorter than their headers say: a snap length below the packet size?)");
  add(pc.filtered_out, "UDP to other ports");
  add(pc.non_udp, "IPv4 not UDP (TCP, ICMP, ...)");
  add(pc.non_ipv4, "not IPv4");
  add(pc.fragments, "IPv4 fragments");
  add(pc.bad_header, "with impossible IPv4/UDP headers");
  return s;
}

namespace {

std::string other_model_summary(const velodyne::AssemblerCounters& a) {
  std::string s;
  if (a.other_model_dropped > 0) {
    s += "; another model's packets " + n(a.other_model_dropped) +
         " (their bytes name a model other than the one the capture's first packets named: "
         "another sensor on the port? dropped, not decoded as this one's lasers)";
  }
  if (a.model_mismatch > a.other_model_dropped) {
    s += "; packets naming another model " + n(a.model_mismatch - a.other_model_dropped) +
         " (decoded as the configured model: check velodyne.model, or --model auto)";
  }
  return s;
}

}  // namespace

std::string packet_drops_summary(const velodyne::AssemblerCounters& a) {
  return "wrong size " + n(a.wrong_size) + ", invalid block " + n(a.invalid_block) +
         ", duplicate " + n(a.duplicates) + ", late firings " + n(a.late_firings) +
         ", points over capacity " + n(a.points_dropped) + "; estimated packets lost " +
         n(a.packets_lost) + ", scans closed by silence " + n(a.time_gaps) + ", by timeout " +
         n(a.timeouts) + other_model_summary(a);
}

std::string nothing_decoded_reason(const std::string& capture, const io::PcapCounters& pc,
                                   const velodyne::AssemblerCounters& a, std::uint16_t port) {
  if (a.packets == 0) {
    std::string s = capture + ": no UDP packet to port " + n(port) + " in the capture";
    if (pc.truncated_frame > 0) {
      return s + ": " + n(pc.truncated_frame) +
             " frames are truncated (captured shorter than their headers say); capture again with "
             "the full snap length (tcpdump -s 0)";
    }
    if (pc.filtered_out > 0)
      return s + " (" + n(pc.filtered_out) + " UDP datagrams to other ports: wrong --port?)";
    return s + " (wrong --port?)";
  }
  const std::uint64_t dropped =
      a.wrong_size + a.invalid_block + a.duplicates + a.other_model_dropped;
  if (dropped == a.packets) {
    return capture + ": none of its " + n(a.packets) + " packets to port " + n(port) +
           " is an HDL-64E data packet: wrong size " + n(a.wrong_size) +
           " (1206 bytes expected), invalid block " + n(a.invalid_block) + ", duplicate " +
           n(a.duplicates);
  }
  return capture + ": no complete scan in its " + n(a.packets) + " packets to port " + n(port) +
         " (dropped: " + packet_drops_summary(a) +
         "); a complete scan turns once from the cut angle back to it";
}

std::string capture_breaks_off(const std::string& reader_error) {
  return reader_error + " (the capture breaks off there; what comes after it is lost)";
}

}  // namespace stac::formats

// The built-in default capture of `stac demo`: an HDL-64E S2.1 turning at 600 rpm in a walled
// yard with a few box-shaped objects and a pole, ray-cast per laser and firing time with the
// beam angles of a real calibration. Deliberately simple (ideal beams from the sensor origin,
// no noise): the ground-truth simulator is `stac sim` (docs/simulator.md once it lands).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/packet.hpp"

namespace stac::tools {

struct DemoPacket {
  std::array<std::uint8_t, velodyne::kPacketSize> bytes;
  std::int64_t receive_stamp_ns;  // after the packet's last firing, as a capture would stamp it
};

std::vector<DemoPacket> make_demo_capture(const velodyne::Calibration& calibration, double seconds,
                                          std::int64_t start_ns);

}  // namespace stac::tools

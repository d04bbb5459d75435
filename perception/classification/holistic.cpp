#include "perception/classification/holistic.hpp"

namespace stac::classification {

Layout holistic_layout() {
  return {{"max_speed_mps", 1},
          {"mean_speed_mps", 1},
          {"max_accel_mps2", 1},
          {"mean_accel_mps2", 1},
          {"max_angular_velocity_rps", 1},
          {"segment_count", 1},
          {"box_length_m", 1},
          {"box_width_m", 1},
          {"box_height_m", 1}};
}

void holistic_descriptor(const tracking::Track& track, HolisticDescriptor& out) noexcept {
  const tracking::HolisticFeatures& f = track.features;
  out = {f.max_speed_mps(),
         f.mean_speed_mps(),
         f.max_accel_mps2(),
         f.mean_accel_mps2(),
         f.max_angular_velocity_rps(),
         static_cast<float>(f.segment_count()),
         track.length,
         track.width,
         track.height};
}

}  // namespace stac::classification

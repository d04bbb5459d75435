#include "perception/classification/holistic.hpp"

#include <algorithm>
#include <limits>
#include <string>

namespace stac::classification {

Layout holistic_layout() {
  Layout layout = {{"max_speed_mps", 1},
                   {"mean_speed_mps", 1},
                   {"max_accel_mps2", 1},
                   {"mean_accel_mps2", 1},
                   {"max_angular_velocity_rps", 1},
                   {"segment_count", 1},
                   {"box_length_m", 1},
                   {"box_width_m", 1},
                   {"box_height_m", 1}};
  for (const auto& s : descriptors::spaces())
    layout.push_back({"accumulated." + std::string(s.name), static_cast<std::uint32_t>(s.size)});
  return layout;
}

void holistic_descriptor(const tracking::Track& track, const descriptors::Descriptors* accumulated,
                         HolisticDescriptor& out) noexcept {
  const tracking::HolisticFeatures& f = track.features;
  const float motion[kHolisticMotionDimensions] = {f.max_speed_mps(),
                                                   f.mean_speed_mps(),
                                                   f.max_accel_mps2(),
                                                   f.mean_accel_mps2(),
                                                   f.max_angular_velocity_rps(),
                                                   static_cast<float>(f.segment_count()),
                                                   track.length,
                                                   track.width,
                                                   track.height};
  std::copy(std::begin(motion), std::end(motion), out.begin());
  const auto rest = out.begin() + kHolisticMotionDimensions;
  if (accumulated != nullptr && accumulated->status == descriptors::Status::kOk)
    std::copy(accumulated->values.begin(), accumulated->values.end(), rest);
  else
    std::fill(rest, out.end(), std::numeric_limits<float>::quiet_NaN());
}

}  // namespace stac::classification

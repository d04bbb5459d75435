// The holistic descriptor of a track (thesis ch. 1): motion statistics from
// tracking::HolisticFeatures plus the track's smoothed box. The segment descriptors of the
// accumulated cloud, which the thesis also uses, are not part of it yet (docs/classification.md).
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include "perception/classification/grid_classifier.hpp"
#include "perception/tracking/track.hpp"

namespace stac::classification {

// Elements, in order: max speed (m/s), mean speed (m/s), max accel (m/s^2), mean accel (m/s^2),
// max angular velocity (rad/s), segment count, box length, width, height (m, smoothed).
inline constexpr std::size_t kHolisticDimensions = 9;
using HolisticDescriptor = std::array<float, kHolisticDimensions>;

Layout holistic_layout();  // one named space per element

void holistic_descriptor(const tracking::Track& track, HolisticDescriptor& out) noexcept;

}  // namespace stac::classification

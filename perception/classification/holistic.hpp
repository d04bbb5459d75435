// The holistic descriptor of a track (thesis ch. 1): motion statistics from
// tracking::HolisticFeatures, the track's smoothed box, and the 29 segment descriptor spaces of
// the track's accumulated cloud (AccumulatedCloud, described by descriptors::DescriptorPipeline).
#pragma once

#include <array>
#include <cstddef>

#include "perception/classification/grid_classifier.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "perception/tracking/track.hpp"

namespace stac::classification {

// Elements 0..8: max speed (m/s), mean speed (m/s), max accel (m/s^2), mean accel (m/s^2),
// max angular velocity (rad/s), segment count, box length, width, height (m, smoothed).
// Elements 9..939: the accumulated cloud's descriptors (descriptors::spaces() order).
inline constexpr std::size_t kHolisticMotionDimensions = 9;
inline constexpr std::size_t kHolisticDimensions =
    kHolisticMotionDimensions + descriptors::kDimensions;
using HolisticDescriptor = std::array<float, kHolisticDimensions>;

// The motion elements' names, then "accumulated." + each descriptor space name.
Layout holistic_layout();

// `accumulated` null or kEmpty: its elements are NaN, which add nothing in classify() (no
// evidence rather than false evidence).
void holistic_descriptor(const tracking::Track& track, const descriptors::Descriptors* accumulated,
                         HolisticDescriptor& out) noexcept;

}  // namespace stac::classification

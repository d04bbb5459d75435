// One track's place in the tracker's pool, and the per-detection match codes (internal to
// perception/tracking).
#pragma once

#include <cstdint>

#include "perception/tracking/kalman.hpp"
#include "perception/tracking/track.hpp"
#include "perception/tracking/tracker.hpp"

namespace stac::tracking {

inline constexpr std::int32_t kUnmatched = -1;  // det_match_: no track (spawns one)
inline constexpr std::int32_t kAbsorbed = -2;   // det_match_: joined a matched track's measurement
// host_ per detection: 0 none joined it; kHost a fragment did; kBodyHost one inside a known body
// did (FragmentConfig::known_margin_m), so its measurement never lengthens that extent.
inline constexpr std::uint8_t kHost = 1, kBodyHost = 2;

struct Tracker::Slot {
  Track track;
  KalmanFilter kf;
  std::int32_t measured = -1;  // index in merged_ of the measurement of this scan, -1: none
  float known_length = 0;      // longest tall measurement so far (body.memory_length_m), m
  float known_width = 0;       // widest tall measurement so far (the body's width), m
  // The two longest tall measurements of one segment (no union, not end-on), m: the second is
  // the body's length for a piece anchored at its visible end (one view of two vehicles as one
  // segment does not make it).
  float single_first = 0, known_single = 0;
  // Heading of the last tall measurement at least body.memory_length_m long that was not an
  // end-on face (whose yaw is the sensor's ray): the body's, for its faces and its joins (rad).
  float known_yaw = 0;
};

}  // namespace stac::tracking

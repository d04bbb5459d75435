// Known bodies (internal to perception/tracking; body.cpp): what the tracker's association and
// fragment joining ask of a track's remembered extent.
#pragma once

#include <Eigen/Core>

#include "perception/tracking/tracker.hpp"

namespace stac::tracking {

// The centre of the body `known` m long along `body_yaw` whose end-on face d is (its near end
// kept, the body extending away from the sensor). False, centre unchanged, when d is no such
// face (BodyConfig::memory_length_m; body.cpp says when).
bool anchored_centre(const TrackerConfig& c, float known, float body_yaw, const Detection& d,
                     Eigen::Vector2f& centre);

}  // namespace stac::tracking

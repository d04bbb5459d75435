// The world frame of a tracks file against the truth's (`stac eval`): a truth written in another
// frame is brought into the tracks' frame, or refused with what to do.
//   tracks enu, origin A; truth origin B   transformed from ENU at B to ENU at A (exact: through
//                                          geodetic coordinates; headings and velocities turned by
//                                          the frames' angle at each box)
//   tracks vehicle (no pose)               the truth in the vehicle frame of its first scan, if
//                                          the ego stayed put; refused if it moved
//   either side unrecorded                 assumed the same, said so
#pragma once

#include <string>
#include <vector>

#include "evaluation/tracks_jsonl.hpp"
#include "rt/expected.hpp"

namespace stac::evaluation {

// Origins farther apart than this are not the same drive: refused.
constexpr double kMaxOriginDistanceM = 100'000.0;
// Parked: the truth's ego within this of its first pose for a vehicle-frame comparison.
constexpr double kParkedToleranceM = 0.5;
constexpr double kParkedToleranceRad = 0.02;

// Rewrites `truth` into the frame of `tracks`; returns one sentence on what was done.
rt::Result<std::string> truth_in_tracks_frame(std::vector<TruthScanRecord>& truth,
                                              const std::vector<TracksScan>& tracks);

}  // namespace stac::evaluation

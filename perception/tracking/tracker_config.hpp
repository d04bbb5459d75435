// The tracker's configuration, one struct per part of the tracker (docs/tracking.md explains each
// rule and why it is there; config/stac.yaml's `tracking:` section sets them, flat key names).
#pragma once

#include <cstddef>
#include <cstdint>

namespace stac::tracking {

// Kalman filter (kalman.hpp): constant velocity in x,y, z a random walk.
struct KalmanConfig {
  double accel_std_mps2 = 2.0;            // white-noise acceleration in x,y (m/s^2)
  double z_velocity_std_mps = 0.5;        // z random walk (m/s)
  double measurement_std_m = 0.25;        // position noise in x,y (m)
  double measurement_z_std_m = 0.3;       // position noise in z (m)
  double initial_velocity_std_mps = 6.0;  // velocity std of a new track (m/s)
};

// Association (association.cpp): a track-detection pair is allowed when both gates pass.
struct GateConfig {
  double mahalanobis_sq = 9.21;  // squared Mahalanobis distance in x,y (chi^2, 2 dof, 99%)
  double distance_m = 3.0;       // Euclidean x,y distance to the prediction (m)
};

// Life cycle: tentative -> confirmed -> coasting -> deleted.
struct LifeCycleConfig {
  std::uint32_t confirm_hits = 3;           // hits that confirm a tentative track
  std::uint32_t confirm_large_points = 50;  // a hit this large (points; 0: off) confirms after...
  std::uint32_t confirm_large_hits = 2;     // ...this many hits
  std::uint32_t tentative_max_misses = 1;   // consecutive misses that delete a tentative track
  std::uint32_t max_coast_scans = 20;       // consecutive misses that delete a coasting track
  double max_position_std_m = 1.5;          // x,y position std that deletes a coasting track (m)
};

// What one object's box may span (fragments, overlaps and known bodies).
struct ObjectSizeConfig {
  double max_length_m = 6.0;    // a car's union at most this long...
  double max_width_m = 2.6;     // ...and this wide (m)
  double tall_height_m = 2.1;   // boxes this high are a tall vehicle's (m; 0: none)
  double tall_length_m = 16.5;  // a union of tall pieces at most this long (m)
};

// People and bicyclists: never joined to another object; they take only low pieces.
struct PersonConfig {
  double max_length_m = 2.2;       // at most this long (m), and
  double max_width_m = 1.0;        // at most this wide (m) and
  double min_height_m = 1.0;       // at least this tall (m; lower pieces: legs, a wheel), or
  double wide_m = 1.4;             // at most this wide (m) and
  double wide_min_height_m = 1.6;  // at least this tall (m; people pushing a bike)
  double gap_m = 0.3;              // a person takes low pieces at most this far (m)
  double strip_length_m = 1.0;     // a box at least this long (m) and
  double strip_width_m = 0.1;      // at most this wide (m; 0: off) is a flat surface, no person
};

// Fragments and merging (fragments.cpp).
struct FragmentConfig {
  double gap_m = 2.0;                   // an unmatched piece joins a matched box this near (m)
  double velocity_mps = 1.5;            // a younger piece's track merges at this velocity gap
  std::uint32_t established_hits = 10;  // a piece's track this old is an object of its own
  double known_margin_m = 0.5;          // pieces inside a known body grown by this join (<0 off)
  double overlap_margin_m = 1.0;        // tracks inside an older box grown by this merge (<0 off)
};

// End-on vehicles (body.cpp, complete_end_on): a face across the ray is a vehicle's end.
struct EndOnConfig {
  double length_m = 4.5;      // the body's length given to a face (m; 0: off)
  double min_range_m = 15.0;  // only faces at least this far (m, sensor to box centre)
  double min_width_m = 1.2;   // across the ray, at least (m)
  double max_width_m = 2.7;   // and at most (m)
  double max_depth_m = 1.6;   // along the ray, at most (m)
  double min_height_m = 0.0;  // at least this tall (m)
};

// Known extent of tall vehicles (body.cpp): a track remembers its body's length.
struct BodyConfig {
  double memory_length_m = 6.0;  // a remembered length this long measures faces (m; 0: off)
  bool gating = true;            // tall pieces of a known body measure its centre
};

struct TrackerConfig {
  std::size_t max_tracks = 512;       // track pool; spawns beyond it are counted, not made
  std::size_t max_detections = 1024;  // per scan; beyond it dropped and counted
                                      // (each 1..100000, their product at most 2^22)
  KalmanConfig kalman;
  GateConfig gate;
  LifeCycleConfig life;
  // The x,y measured: the oriented box's centre (true) or the points' centroid (the thesis).
  bool position_from_box = true;
  ObjectSizeConfig object;
  PersonConfig person;
  FragmentConfig fragments;
  EndOnConfig end_on;
  BodyConfig body;
  double box_smoothing = 0.3;          // weight of a new box in the exponential average (0..1]
  double min_heading_speed_mps = 0.5;  // holistic features: slower headings are not compared
};

}  // namespace stac::tracking

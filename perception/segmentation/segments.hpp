// The output of Segmenter::segment() for one scan: fixed-capacity storage, filled in place.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "rt/fixed_vector.hpp"

namespace stac::segmentation {

// A box about the vertical axis: centre (m, sensor frame), length >= width along yaw
// (rad, in (-pi/2, pi/2], counter-clockwise from x), height = z_max - z_min.
struct OrientedBox {
  float cx = 0, cy = 0, cz = 0;
  float length = 0, width = 0, height = 0;
  float yaw = 0;
};

struct Segment {
  std::uint32_t first = 0;  // its point indices: Segments::point_indices[first, first + count)
  std::uint32_t count = 0;  // obstacle points
  float centroid[3] = {0, 0, 0};  // mean of its points (m)
  float z_min = 0, z_max = 0;     // height span (m, sensor frame)
  OrientedBox box;                // yaw from the principal axis of the XY footprint
  std::uint32_t cells = 0;        // obstacle grid cells it covers
};

// Per scan. Every input point ends in exactly one of: ignored_invalid, ignored_out_of_range,
// ignored_over_capacity, ignored_below, dropped_cell_overflow, ground_points, ignored_above,
// obstacle_points.
struct SegmentCounters {
  std::uint64_t points_in = 0;
  std::uint64_t ignored_invalid = 0;        // NaN or infinite coordinates
  std::uint64_t ignored_out_of_range = 0;   // outside [min_range_m, range_m]
  std::uint64_t ignored_over_capacity = 0;  // beyond max_points
  std::uint64_t ignored_below = 0;          // impossibly far below the ground (reflections)
  std::uint64_t dropped_cell_overflow = 0;  // their cell could not be added (max_occupied_cells)
  std::uint64_t ground_points = 0;          // near the ground, or low bumps no obstacle reached
  std::uint64_t ignored_above = 0;          // more than max_height_m above ground
  std::uint64_t obstacle_points = 0;  // above the clearance in obstacle cells (kept or dropped)
  std::uint64_t occupied_cells = 0;
  std::uint64_t obstacle_cells = 0;
  std::uint64_t clusters = 0;           // connected components of obstacle cells
  std::uint64_t split_segments = 0;     // extra parts made by splitting clusters (kept or dropped)
  std::uint64_t dropped_too_small = 0;  // clusters under min_segment_points
  std::uint64_t dropped_too_large = 0;  // over max_segment_points or max_segment_extent_m
  std::uint64_t dropped_segment_overflow = 0;  // kept clusters beyond max_segments
};

struct Segments {
  Segments() = default;
  Segments(std::size_t max_segments, std::size_t max_points)
      : segments(max_segments), point_indices(max_points) {}

  rt::FixedVector<Segment> segments;
  rt::FixedVector<std::uint32_t> point_indices;  // indices into the input PointView
  SegmentCounters counters;

  [[nodiscard]] std::span<const std::uint32_t> indices(const Segment& s) const noexcept {
    return {point_indices.data() + s.first, s.count};
  }
};

}  // namespace stac::segmentation

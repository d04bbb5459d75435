// Association (docs/tracking.md): every track-detection pair gated (Mahalanobis and distance,
// a known body's pieces and faces at the body's centre), then the assignment solved globally per
// connected component of the allowed pairs.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "perception/tracking/body.hpp"
#include "perception/tracking/shapes.hpp"
#include "perception/tracking/slot.hpp"
#include "perception/tracking/tracker.hpp"

namespace stac::tracking {
namespace {

constexpr double kForbidden = 1e9;  // cost of a pair outside the gate (dropped after solving)

}  // namespace

Tracker::Gated Tracker::gate(std::span<const Detection> detections) noexcept {
  const std::size_t nt = live_.size(), nd = detections.size();
  std::size_t nrows = 0, ncols = 0;
  std::fill_n(col_of_det_.begin(), nd, -1);
  std::fill_n(det_match_.begin(), nd, -1);
  // A pair farther apart than the distance gate along x or y fails it (cheap test first; the
  // margin keeps it exact under rounding).
  const double gate_axis = config_.gate.distance_m * (1 + 1e-9);
  for (std::size_t di = 0; di < nd; ++di) {
    positions_[di] = detections[di].position(config_.position_from_box).cast<double>();
  }
  for (std::size_t ti = 0; ti < nt; ++ti) {
    const Slot& s = slots_[live_[ti]];
    const Eigen::Matrix2d sxy = s.kf.xy_innovation(config_.kalman);
    const Eigen::Matrix2d sinv = sxy.inverse();
    const Eigen::Vector2d predicted = s.kf.x.head<2>();
    float* costs = &pair_cost_[ti * nd];
    bool any = false;
    // A track of known extent measures an end-on detection at its anchored centre, up to half
    // its length from the box's.
    const bool known = shapes::knows_extent(config_, s.known_length);
    const double reach = known ? gate_axis + 0.5 * s.known_length : gate_axis;
    for (std::size_t di = 0; di < nd; ++di) {
      Eigen::Vector2d e = positions_[di] - predicted;
      costs[di] = -1.0f;
      if (!(std::abs(e.x()) <= reach && std::abs(e.y()) <= reach)) continue;
      Eigen::Vector2f centre = Eigen::Vector2f::Zero();
      Eigen::Matrix2d spread;
      float gap = 0;
      double m2 = 0;
      if (known && piece(s, detections[di], di, spread, gap, centre)) {
        // A piece of the known body: its centre, with the spread of where in the body it lies;
        // the distance gate applies to the nearest centre at which the body covers it.
        if (!(gap <= config_.gate.distance_m)) continue;
        e = centre.cast<double>() - predicted;
        m2 = e.dot((sxy + spread).inverse() * e);
        if (!(m2 <= config_.gate.mahalanobis_sq)) continue;
      } else {
        if (known &&
            anchored_centre(config_, s.known_length, s.known_yaw, detections[di], centre)) {
          e = centre.cast<double>() - predicted;
        }
        if (!(std::abs(e.x()) <= gate_axis && std::abs(e.y()) <= gate_axis)) continue;
        m2 = e.dot(sinv * e);
        if (!(m2 <= config_.gate.mahalanobis_sq && e.norm() <= config_.gate.distance_m)) continue;
      }
      costs[di] = static_cast<float>(m2);
      any = true;
      if (col_of_det_[di] < 0) {
        col_of_det_[di] = static_cast<std::int32_t>(ncols);
        cols_[ncols++] = static_cast<std::uint32_t>(di);
      }
    }
    if (any) rows_[nrows++] = static_cast<std::uint32_t>(ti);
  }
  return {nrows, ncols};
}

void Tracker::assign(std::size_t nd, std::size_t nrows, std::size_t ncols) noexcept {
  // Union-find over rows [0, nrows) and columns [nrows, nrows + ncols).
  const std::size_t nodes = nrows + ncols;
  for (std::size_t i = 0; i < nodes; ++i) parent_[i] = static_cast<std::uint32_t>(i);
  const auto find = [&](std::uint32_t a) {
    while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
    return a;
  };
  for (std::size_t ri = 0; ri < nrows; ++ri) {
    const float* costs = &pair_cost_[rows_[ri] * nd];
    for (std::size_t ci = 0; ci < ncols; ++ci) {
      if (costs[cols_[ci]] < 0) continue;
      const std::uint32_t a = find(static_cast<std::uint32_t>(ri)),
                          b = find(static_cast<std::uint32_t>(nrows + ci));
      if (a != b) parent_[std::max(a, b)] = std::min(a, b);  // the root is a component's first row
    }
  }
  // Components numbered by their first row; members listed in increasing order, rows of
  // component k at [start[2k], start[2k + 1]), its columns at [start[2k + 1], start[2k + 2]).
  std::size_t components = 0;
  for (std::size_t i = 0; i < nodes; ++i) {
    const std::uint32_t root = find(static_cast<std::uint32_t>(i));
    component_[i] = root == i ? static_cast<std::uint32_t>(components++) : component_[root];
  }
  std::fill_n(component_start_.begin(), 2 * components + 1, 0u);
  for (std::size_t i = 0; i < nodes; ++i)
    ++component_start_[2 * component_[i] + (i < nrows ? 1 : 2)];
  for (std::size_t k = 1; k <= 2 * components; ++k) component_start_[k] += component_start_[k - 1];
  for (std::size_t i = 0; i < nodes; ++i) {
    component_members_[component_start_[2 * component_[i] + (i < nrows ? 0 : 1)]++] =
        static_cast<std::uint32_t>(i < nrows ? i : i - nrows);
  }
  for (std::size_t k = 2 * components; k > 0; --k) component_start_[k] = component_start_[k - 1];
  component_start_[0] = 0;
  bool failed = false;
  for (std::size_t k = 0; k < components; ++k) {
    const std::uint32_t* rows = &component_members_[component_start_[2 * k]];
    const std::uint32_t* cols = &component_members_[component_start_[2 * k + 1]];
    const std::size_t nr = component_start_[2 * k + 1] - component_start_[2 * k];
    const std::size_t nc = component_start_[2 * k + 2] - component_start_[2 * k + 1];
    if (nr == 1 && nc == 1) {  // one allowed pair: it is the match
      det_match_[cols_[cols[0]]] = static_cast<std::int32_t>(rows_[rows[0]]);
      continue;
    }
    for (std::size_t ri = 0; ri < nr; ++ri) {
      const float* costs = &pair_cost_[rows_[rows[ri]] * nd];
      for (std::size_t ci = 0; ci < nc; ++ci) {
        const float c = costs[cols_[cols[ci]]];
        cost_[ri * nc + ci] = c < 0 ? kForbidden : static_cast<double>(c);
      }
    }
    if (!solver_.solve({cost_.data(), nr * nc}, nr, nc, {row_to_col_.data(), nr})) {
      failed = true;
      continue;
    }
    for (std::size_t ri = 0; ri < nr; ++ri) {
      const int ci = row_to_col_[ri];
      if (ci < 0 || cost_[ri * nc + static_cast<std::size_t>(ci)] >= kForbidden) continue;
      det_match_[cols_[cols[ci]]] = static_cast<std::int32_t>(rows_[rows[ri]]);
    }
  }
  if (failed) ++counters_.solver_failures;
}

}  // namespace stac::tracking

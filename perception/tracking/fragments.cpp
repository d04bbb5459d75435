// Fragments and merging (docs/tracking.md): pieces of one object left unmatched join a matched
// neighbour's measurement; tracks inside an older track's box merge into it.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "perception/tracking/body.hpp"
#include "perception/tracking/shapes.hpp"
#include "perception/tracking/slot.hpp"
#include "perception/tracking/tracker.hpp"

namespace stac::tracking {

using namespace shapes;  // NOLINT(google-build-using-namespace): the tracker's own box rules

namespace {

// Detection h grown into its union u (about h's centre, in `heading`) with fragment f.
void join(Detection& h, const Detection& f, const Extent& u, float heading) noexcept {
  const Eigen::Vector2f centre = h.position(true);
  const float ch = std::cos(heading), sh = std::sin(heading);
  h.yaw = heading;
  const float uc = 0.5f * (u.u0 + u.u1), vc = 0.5f * (u.v0 + u.v1);
  const float total = static_cast<float>(h.points + f.points);
  h.centroid =
      (h.centroid * static_cast<float>(h.points) + f.centroid * static_cast<float>(f.points)) /
      total;
  h.box_center = centre + Eigen::Vector2f(ch * uc - sh * vc, sh * uc + ch * vc);
  h.length = u.u1 - u.u0;
  h.width = u.v1 - u.v0;
  if (h.width > h.length) {
    std::swap(h.length, h.width);
    h.yaw = static_cast<float>(wrap_pi(h.yaw + std::numbers::pi / 2));
  }
  h.height = std::max(h.height, f.height);
  h.end_on = false;  // a union: its heading no longer points away from the sensor
  h.points += f.points;
}

}  // namespace

// The host a fragment joins (best == nd: none) and their union.
struct Tracker::HostChoice {
  std::size_t best = 0;
  float gap = 0;
  Extent union_box{};
  float heading = 0, area = 0;
  bool known = false;  // inside a host's known body
};

void Tracker::absorb_fragments(std::span<const Detection> detections) noexcept {
  const std::size_t nd = detections.size();
  start_merged(detections);
  std::fill_n(merged_track_.begin(), live_.size(), std::uint8_t{0});
  if (config_.fragments.gap_m <= 0) return;
  const auto max_len =
      static_cast<float>(longest_object(config_, config_.object.tall_height_m > 0));
  const auto max_wid = static_cast<float>(config_.object.max_width_m);
  const auto max_gap = static_cast<float>(config_.fragments.gap_m);
  const float reach_sq = max_len * max_len + max_wid * max_wid;
  for (std::size_t fi = 0; fi < nd; ++fi) {
    const Detection& f = detections[fi];
    if (det_match_[fi] == kAbsorbed || host_[fi] != 0 || !f.centroid.allFinite() ||
        !f.position(true).allFinite()) {
      continue;
    }
    const Slot* own =
        det_match_[fi] >= 0 ? &slots_[live_[static_cast<std::size_t>(det_match_[fi])]] : nullptr;
    const HostChoice c = find_host(fi, f, own, nd, max_gap, reach_sq);
    if (c.best == nd) continue;
    join(merged_[c.best], f, c.union_box, c.heading);
    host_[c.best] = c.known || host_[c.best] == kBodyHost ? kBodyHost : kHost;
    if (own != nullptr) {
      merged_track_[static_cast<std::size_t>(det_match_[fi])] = 1;
      ++counters_.deleted_merged;
    }
    det_match_[fi] = kAbsorbed;
    ++counters_.absorbed_detections;
  }
}

// Each detection as measured, no host yet. An end-on face matched to a track of known extent is
// that body (its face kept) before any fragment joins it.
void Tracker::start_merged(std::span<const Detection> detections) noexcept {
  for (std::size_t di = 0; di < detections.size(); ++di) {
    merged_[di] = detections[di];
    host_[di] = 0;
    if (det_match_[di] >= 0) {
      const Slot& slot = slots_[live_[static_cast<std::size_t>(det_match_[di])]];
      Detection& m = merged_[di];
      Eigen::Vector2f centre = Eigen::Vector2f::Zero();
      if (anchored_centre(config_, slot.known_length, slot.known_yaw, m, centre)) {
        m.box_center = centre;
        m.length = slot.known_length;
        ++counters_.anchored_detections;
      }
    }
  }
}

// The matched measurement nearest to fragment fi (box gap) whose union with it still fits; a
// matched fragment (own: its track) only joins an older track moving with it.
Tracker::HostChoice Tracker::find_host(std::size_t fi, const Detection& f, const Slot* own,
                                       std::size_t nd, float max_gap,
                                       float reach_sq) const noexcept {
  // A person-like piece joins only the known body of a truck it lies in (inside_known_body).
  const bool f_person = narrow_and_tall(config_, f.length, f.width, f.height);
  // A fragment whose own track is established joins only a person (its own legs), never a car.
  const bool established = own != nullptr && config_.fragments.established_hits > 0 &&
                           own->track.hits >= config_.fragments.established_hits;
  HostChoice c;
  c.best = nd;
  c.gap = max_gap;
  const Eigen::Vector2f fc = f.position(true);
  for (std::size_t hi = 0; hi < nd; ++hi) {
    if (hi == fi || det_match_[hi] < 0) continue;
    // A union that fits has a diagonal of at most reach: farther centres never fit (cheap test).
    if ((merged_[hi].position(true) - fc).squaredNorm() > reach_sq) continue;
    // A person or bicyclist takes only low pieces (legs, a wheel), whatever their tracks' ages,
    // and stays narrow.
    const Detection& h = merged_[hi];
    const bool narrow_host = narrow_and_tall(config_, h.length, h.width, h.height);
    const Slot& host = slots_[live_[static_cast<std::size_t>(det_match_[hi])]];
    const bool in_body = !narrow_host && inside_known_body(host, f);
    if (f_person && !in_body) continue;
    if (narrow_host && f.height >= config_.person.min_height_m) continue;
    if (own != nullptr && !narrow_host) {
      if (established || !older(host.track, own->track)) continue;
      if (own->track.state != TrackState::kTentative &&
          (host.kf.x.tail<2>() - own->kf.x.tail<2>()).norm() > config_.fragments.velocity_mps) {
        continue;
      }
    }
    // Inside the body of a host track of known extent: joined in the body's heading (its
    // last whole view), the first such host taken.
    if (in_body) {
      const Eigen::Vector2f centre = h.position(true);
      c.best = hi, c.heading = host.known_yaw, c.known = true;
      c.union_box = hull(extent_in(h, centre, c.heading), extent_in(f, centre, c.heading));
      break;
    }
    try_union(hi, f, narrow_host, c);
  }
  return c;
}

// The union of host hi with fragment f in the host's heading or the fragment's, whichever fits
// tighter (a piece's principal axis may be diagonal to the car), taken into c when nearer.
void Tracker::try_union(std::size_t hi, const Detection& f, bool narrow_host,
                        HostChoice& c) const noexcept {
  const Detection& h = merged_[hi];
  const Eigen::Vector2f centre = h.position(true);
  for (const float heading : {h.yaw, f.yaw}) {
    const Extent a = extent_in(h, centre, heading), b = extent_in(f, centre, heading);
    const float gu = std::max(0.0f, std::max(a.u0, b.u0) - std::min(a.u1, b.u1));
    const float gv = std::max(0.0f, std::max(a.v0, b.v0) - std::min(a.v1, b.v1));
    const float gap = std::hypot(gu, gv);
    if (!(gap <= c.gap) || (narrow_host && gap > config_.person.gap_m)) continue;
    const Extent u = hull(a, b);
    const float lu = u.u1 - u.u0, lv = u.v1 - u.v0;
    if (!fits_one_object(config_, lu, lv, tall(config_, h.height) && tall(config_, f.height)))
      continue;
    if (narrow_host && !narrow_and_tall(config_, lu, lv, h.height)) continue;
    if (c.best == hi && lu * lv >= c.area) continue;
    c.best = hi, c.gap = gap, c.union_box = u, c.heading = heading, c.area = lu * lv;
  }
}

// A's box grown for the pair tests of merge_overlapping, refreshed when a is corrected.
struct Tracker::GrownBox {
  bool narrow = false;  // a person-like track: takes only low tracks (legs) into its box
  float grow = 0, reach = 0, ca = 1, sa = 0;
  void refresh(const Track& t) noexcept {
    reach = 0.5f * std::hypot(t.length + 2 * grow, t.width + 2 * grow);
    ca = std::cos(t.yaw), sa = std::sin(t.yaw);
  }
};

void Tracker::merge_overlapping(std::int64_t stamp_ns) noexcept {
  if (config_.fragments.overlap_margin_m < 0) return;
  const std::size_t n = live_.size();
  std::fill_n(merged_track_.begin(), n, std::uint8_t{0});
  // The tracks' x,y in one compact array for the pair loop (kept current when a is corrected).
  for (std::size_t i = 0; i < n; ++i) track_xy_[i] = slots_[live_[i]].kf.x.head<2>();
  // The tracks sorted by x: the pairs within a's reach lie in a window of that order (a track
  // corrected below is moved to its new place).
  for (std::size_t i = 0; i < n; ++i) order_[i] = static_cast<std::uint32_t>(i);
  std::sort(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(n),
            [this](std::uint32_t p, std::uint32_t q) { return x_before(p, q); });
  for (std::size_t k = 0; k < n; ++k) rank_[order_[k]] = static_cast<std::uint32_t>(k);
  for (std::size_t i = 0; i < n; ++i) {
    if (merged_track_[i] == 0) merge_into(i, stamp_ns);
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (merged_track_[i] != 0) {
      (void)free_.push_back(live_[i]);
    } else {
      live_[kept++] = live_[i];
    }
  }
  (void)live_.resize(kept);
}

// The order of merge_overlapping's sweep: by x, then by index.
bool Tracker::x_before(std::uint32_t p, std::uint32_t q) const noexcept {
  return track_xy_[p].x() < track_xy_[q].x() || (track_xy_[p].x() == track_xy_[q].x() && p < q);
}

// Track t moved to its place in order_ after its x changed.
void Tracker::move_to_place(std::uint32_t t) noexcept {
  const std::size_t n = live_.size();
  std::size_t k = rank_[t];
  for (; k > 0 && x_before(t, order_[k - 1]); --k) {
    order_[k] = order_[k - 1];
    rank_[order_[k]] = static_cast<std::uint32_t>(k);
  }
  for (; k + 1 < n && x_before(order_[k + 1], t); ++k) {
    order_[k] = order_[k + 1];
    rank_[order_[k]] = static_cast<std::uint32_t>(k);
  }
  order_[k] = t;
  rank_[t] = static_cast<std::uint32_t>(k);
}

// The tracks within live track i's box (grown) merged into it. Both boxes must fit what one
// fragmented object's box may (a hedge, a wall or a canopy beside a parked car does not), and
// a's changes only when it merges: one that does not fit never will.
void Tracker::merge_into(std::size_t i, std::int64_t stamp_ns) noexcept {
  const Slot& a = slots_[live_[i]];
  GrownBox g;
  g.narrow = narrow_and_tall(config_, a.track.length, a.track.width, a.track.height);
  if (!g.narrow &&
      !fits_one_object(config_, a.track.length, a.track.width, tall(config_, a.track.height))) {
    return;
  }
  g.grow = g.narrow ? static_cast<float>(config_.person.gap_m)
                    : static_cast<float>(config_.fragments.overlap_margin_m);
  g.refresh(a.track);
  // The tracks from j = `from` on within reach along x (a margin above rounding: every pair
  // outside fails the circle test), tried in the order of j as a scan of all pairs would; when
  // a moves, its remaining pairs are gathered again around its new place.
  const std::size_t n = live_.size();
  for (std::size_t from = 0;;) {
    const double window = static_cast<double>(g.reach) * (1 + 1e-5), xi = track_xy_[i].x();
    std::size_t candidates = 0;
    for (std::size_t k = rank_[i]; k-- > 0 && xi - track_xy_[order_[k]].x() <= window;) {
      if (order_[k] >= from) candidate_[candidates++] = order_[k];
    }
    for (std::size_t k = rank_[i] + 1; k < n && track_xy_[order_[k]].x() - xi <= window; ++k) {
      if (order_[k] >= from) candidate_[candidates++] = order_[k];
    }
    std::sort(candidate_.begin(), candidate_.begin() + static_cast<std::ptrdiff_t>(candidates));
    bool moved = false;
    for (std::size_t c = 0; c < candidates && !moved; ++c) {
      moved = try_merge(i, candidate_[c], g, stamp_ns);
      from = candidate_[c] + 1;
    }
    if (!moved) break;
    move_to_place(static_cast<std::uint32_t>(i));
  }
}

// Tries the pair (live track i = a, live track j); true when a was corrected (it moved).
bool Tracker::try_merge(std::size_t i, std::size_t j, GrownBox& g, std::int64_t stamp_ns) noexcept {
  if (j == i || merged_track_[j] != 0) return false;
  Slot& a = slots_[live_[i]];
  const float dx = static_cast<float>(track_xy_[j].x() - track_xy_[i].x()),
              dy = static_cast<float>(track_xy_[j].y() - track_xy_[i].y());
  if (dx * dx + dy * dy > g.reach * g.reach) return false;  // outside the grown box's circle
  const Slot& b = slots_[live_[j]];
  if (narrow_and_tall(config_, b.track.length, b.track.width, b.track.height) ||
      (g.narrow ? b.track.height >= config_.person.min_height_m : !older(a.track, b.track))) {
    return false;
  }
  if (std::abs(g.ca * dx + g.sa * dy) > 0.5f * a.track.length + g.grow ||
      std::abs(-g.sa * dx + g.ca * dy) > 0.5f * a.track.width + g.grow) {
    return false;
  }
  const auto fits = [&](const Track& t) {
    return fits_one_object(config_, t.length, t.width, tall(config_, t.height));
  };
  if (!g.narrow && (!fits(a.track) || !fits(b.track))) return false;
  // b is the same object as the older a: a keeps its id (and its velocity); if only b was
  // measured in this scan, b's measurement corrects a.
  bool moved = false;
  if (a.track.segment < 0 && b.measured >= 0) {
    // Learns the extent from any measurement, a known body's union too (unlike step 4).
    const auto bi = static_cast<std::size_t>(b.measured);
    Eigen::Matrix2d spread;
    float gap = 0;
    Eigen::Vector2f centre = Eigen::Vector2f::Zero();
    Detection m = merged_[bi];
    const bool is_piece = piece(a, m, bi, spread, gap, centre);
    if (is_piece) m.box_center = centre;
    correct(a, m, stamp_ns, true, is_piece ? &spread : nullptr, host_[bi] == 0);
    track_xy_[i] = a.kf.x.head<2>();
    a.measured = b.measured;
    g.refresh(a.track);
    moved = true;
  }
  merged_track_[j] = 1;
  ++counters_.deleted_overlap;
  return moved;
}

}  // namespace stac::tracking

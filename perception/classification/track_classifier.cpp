#include "perception/classification/track_classifier.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace stac::classification {

const char* validate(const TrackClassifierConfig& c) noexcept {
  if (c.max_tracks < 1 || c.max_tracks > 100'000) return "max_tracks must be in [1, 100000]";
  if (c.accumulated_points < 1 || c.accumulated_points > 1'000'000)
    return "accumulated_points must be in [1, 1000000]";
  if (c.holistic_every < 1 || c.holistic_every > 10'000)
    return "holistic_every must be in [1, 10000]";
  if (c.max_tracks * c.accumulated_points > 33'554'432)
    return "max_tracks x accumulated_points must be at most 33554432 (the tracks' accumulated "
           "clouds, allocated at start-up)";
  if (c.max_points < 1 || c.max_points > 10'000'000) return "max_points must be in [1, 1e7]";
  return descriptors::validate(c.descriptors);
}

namespace {

const TrackClassifierConfig& checked(const TrackClassifierConfig& c) {
  if (const char* e = validate(c); e[0] != '\0')
    throw std::invalid_argument(std::string("classification: ") + e);
  return c;
}

}  // namespace

TrackClassifier::TrackClassifier(const TrackClassifierConfig& config,
                                 std::shared_ptr<const TrackClassifierModel> model)
    : config_(checked(config)), model_(std::move(model)), describer_(config.descriptors) {
  if (model_ != nullptr && (model_->segment.dimensions() != descriptors::kDimensions ||
                            model_->holistic.dimensions() != kHolisticDimensions)) {
    throw std::invalid_argument(
        "classification: the model's descriptor sizes are not this build's (retrain it)");
  }
  deferred_tracks_ = rt::FixedVector<tracking::Track>(config.max_tracks);
  deferred_ = segmentation::Segments(config.max_tracks, config.max_points);
  batch_.resize(config.max_tracks);
  pending_ = rt::FixedVector<Pending>(config.max_tracks);
  rows_.resize(config.max_tracks);
  sums_.resize(config.max_tracks);
  segment_log_odds_.resize(config.max_tracks);
  slots_.reserve(config.max_tracks);
  for (std::size_t i = 0; i < config.max_tracks; ++i)
    slots_.emplace_back(config.accumulated_points);
}

void TrackClassifier::classify_pending() noexcept {
  const std::size_t n = pending_.size();
  if (n == 0) return;
  const GridClassifier& segment = model_->segment;
  const GridClassifier& holistic = model_->holistic;
  constexpr std::size_t kMotion = kHolisticMotionDimensions;
  // H_S(z_t) of every pending segment: prior + the sum over its elements, as classify().
  for (std::size_t j = 0; j < n; ++j) {
    rows_[j] = batch_[j].values.data();
    sums_[j] = LogOdds{};
  }
  (void)segment.partial_batch({rows_.data(), n}, 0, segment.dimensions(), {sums_.data(), n});
  for (std::size_t j = 0; j < n; ++j) {
    segment_log_odds_[j] = segment.model().prior;
    for (std::size_t k = 0; k < kClassCount; ++k) segment_log_odds_[j][k] += sums_[j][k];
  }
  // The accumulated clouds described in this scan: their part of the holistic sum. A cloud with
  // no descriptors has NaN elements there, which add nothing: its part stays zero.
  std::size_t refreshed = 0;
  for (std::size_t j = 0; j < n; ++j) {
    Slot& s = *pending_[j].slot;
    if (!pending_[j].refresh) continue;
    s.accumulated_sum = LogOdds{};
    if (s.accumulated.status != descriptors::Status::kOk) continue;
    rows_[refreshed] = s.accumulated.values.data();
    sums_[refreshed] = LogOdds{};
    ++refreshed;
  }
  (void)holistic.partial_batch({rows_.data(), refreshed}, kMotion, holistic.dimensions(),
                               {sums_.data(), refreshed});
  refreshed = 0;
  for (std::size_t j = 0; j < n; ++j) {
    Slot& s = *pending_[j].slot;
    if (pending_[j].refresh && s.accumulated.status == descriptors::Status::kOk)
      s.accumulated_sum = sums_[refreshed++];
  }
  for (std::size_t j = 0; j < n; ++j) {
    Slot& s = *pending_[j].slot;
    LogOdds hh = s.accumulated_sum;
    (void)holistic.partial(pending_[j].motion, 0, kMotion, hh);
    s.evidence.add_segment(segment_log_odds_[j], segment.model().prior);
    for (std::size_t k = 0; k < kClassCount; ++k) hh[k] += holistic.model().prior[k];
    const LogOdds track = track_log_odds(*model_, s.evidence, hh);
    s.cls.classified = true;
    s.cls.log_odds = track;
    s.cls.label = predict(track);
    s.cls.segments = s.evidence.segments;
    s.pending = false;
  }
  pending_.clear();
}

void TrackClassifier::update(const float* xyzi, std::size_t stride_bytes,
                             const segmentation::Segments& segments,
                             std::span<const tracking::Track> tracks) noexcept {
  for (const tracking::Track& t : tracks) {
    if (t.slot >= slots_.size()) {
      ++counters_.slot_mismatch;
      continue;
    }
    Slot& s = slots_[t.slot];
    if (s.pending) classify_pending();  // a slot twice in one scan (never expected): in order
    if (s.cls.id != t.id) {             // a new track in this pool slot: forget the one before
      s.cloud.clear(t.id + 1);
      s.evidence.reset();
      s.cls = TrackClass{};
      s.cls.id = t.id;
      s.since_holistic = 0;
      s.accumulated_ok = false;
    }
    if (t.segment < 0 || static_cast<std::size_t>(t.segment) >= segments.segments.size()) continue;
    const segmentation::Segment& seg = segments.segments[static_cast<std::size_t>(t.segment)];
    const descriptors::SegmentView view{xyzi, stride_bytes, segments.indices(seg), 0};
    descriptors::Descriptors& described = batch_[pending_.size()];
    describer_.compute(view, described);
    ++counters_.segments_described;
    if (described.status != descriptors::Status::kOk) {
      ++counters_.segments_empty;
      continue;
    }
    s.cloud.add_segment(view);
    const bool refresh = !s.accumulated_ok || ++s.since_holistic >= config_.holistic_every;
    if (refresh) {
      describer_.compute(s.cloud.view(), s.accumulated);
      ++counters_.holistic_described;
      s.accumulated_ok = true;
      s.since_holistic = 0;
    }
    holistic_descriptor(t, &s.accumulated, holistic_);
    if (observer_ != nullptr) observer_->on_update(t, described.values, holistic_);
    if (model_ == nullptr) continue;
    Pending* p = pending_.append();  // room: pending_ and batch_ hold max_tracks
    p->slot = &s;
    p->refresh = refresh;
    std::copy(holistic_.begin(), holistic_.begin() + kHolisticMotionDimensions, p->motion.begin());
    s.pending = true;
    if (pending_.size() == pending_.capacity()) classify_pending();
  }
  if (model_ != nullptr) classify_pending();
}

void TrackClassifier::report(const tracking::TrackerOutput& tracked,
                             rt::FixedVector<TrackClass>& out) const noexcept {
  out.clear();
  for (const tracking::Track& t : tracked.tracks) {
    TrackClass* c = out.append();
    if (c == nullptr) break;
    if (t.slot < slots_.size() && slots_[t.slot].cls.id == t.id) {
      *c = slots_[t.slot].cls;
    } else {  // not seen by update() yet (deferred), or out of the pool
      *c = TrackClass{};
      c->id = t.id;
    }
  }
}

void TrackClassifier::classify(const float* xyzi, std::size_t stride_bytes,
                               const segmentation::Segments& segments,
                               const tracking::TrackerOutput& tracked,
                               rt::FixedVector<TrackClass>& out) noexcept {
  update(xyzi, stride_bytes, segments,
         std::span<const tracking::Track>(tracked.tracks.data(), tracked.tracks.size()));
  report(tracked, out);
}

void TrackClassifier::defer(const segmentation::Segments& segments,
                            const tracking::TrackerOutput& tracked) noexcept {
  deferred_tracks_.clear();
  deferred_.segments.clear();
  deferred_.point_indices.clear();
  for (const tracking::Track& t : tracked.tracks) {
    tracking::Track* copy = deferred_tracks_.append();
    if (copy == nullptr) break;
    *copy = t;
    copy->segment = -1;
    if (t.segment < 0 || static_cast<std::size_t>(t.segment) >= segments.segments.size()) continue;
    const segmentation::Segment& seg = segments.segments[static_cast<std::size_t>(t.segment)];
    const std::span<const std::uint32_t> indices = segments.indices(seg);
    const std::size_t first = deferred_.point_indices.size();
    segmentation::Segment* kept = deferred_.segments.append();
    if (kept == nullptr || !deferred_.point_indices.resize(first + indices.size())) {
      if (kept != nullptr) (void)deferred_.segments.resize(deferred_.segments.size() - 1);
      ++counters_.deferred_overflow;
      continue;
    }
    std::copy(indices.begin(), indices.end(), deferred_.point_indices.data() + first);
    *kept = seg;
    kept->first = static_cast<std::uint32_t>(first);
    copy->segment = static_cast<std::int32_t>(deferred_.segments.size() - 1);
  }
}

void TrackClassifier::update_deferred(const float* xyzi, std::size_t stride_bytes) noexcept {
  update(xyzi, stride_bytes, deferred_,
         std::span<const tracking::Track>(deferred_tracks_.data(), deferred_tracks_.size()));
  deferred_tracks_.clear();
}

}  // namespace stac::classification

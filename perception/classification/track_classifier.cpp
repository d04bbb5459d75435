#include "perception/classification/track_classifier.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "rt/clock.hpp"

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
  kept_tracks_ = rt::FixedVector<Kept>(config.max_tracks);
  kept_segments_ = segmentation::Segments(config.max_tracks, config.max_points);
  batch_.resize(config.max_tracks);
  pending_ = rt::FixedVector<Pending>(config.max_tracks);
  rows_.resize(config.max_tracks);
  sums_.resize(config.max_tracks);
  segment_log_odds_.resize(config.max_tracks);
  slots_to_sum_.reserve(config.max_tracks);
  slot_scan_.assign(config.max_tracks, 0);
  slot_kept_.assign(config.max_tracks, 0);
  slots_.reserve(config.max_tracks);
  for (std::size_t i = 0; i < config.max_tracks; ++i)
    slots_.emplace_back(config.accumulated_points);
}

std::string TrackClassifier::check_swap(const TrackClassifierModel& model) const {
  if (model_ == nullptr) return "no model is loaded: a model can only replace another";
  if (model.segment.dimensions() != descriptors::kDimensions ||
      model.holistic.dimensions() != kHolisticDimensions)
    return "the model's descriptor sizes are not this build's (retrain it)";
  if (model.classes != model_->classes)
    return "its classes (" + joined(model.classes) + ") are not the running model's (" +
           joined(model_->classes) + "): restart with it instead";
  return "";
}

void TrackClassifier::set_model(const std::shared_ptr<const TrackClassifierModel>& model) noexcept {
  if (model == nullptr || model_ == nullptr) return;
  model_ = model;
  for (Slot& s : slots_) {
    s.evidence.reset();
    if (s.described > 0) slots_to_sum_.push_back(&s);  // room: max_tracks
  }
  sum_accumulated();
}

void TrackClassifier::sum_accumulated() noexcept {
  // A description with no point (kEmpty) would be NaN elements, which add nothing: its part
  // stays zero.
  const GridClassifier& holistic = model_->holistic;
  std::size_t n = 0;
  for (Slot* s : slots_to_sum_) {
    s->accumulated_sum = LogOdds{};
    if (s->accumulated.status != descriptors::Status::kOk) continue;
    rows_[n] = s->accumulated.values.data();
    sums_[n] = LogOdds{};
    ++n;
  }
  (void)holistic.partial_batch({rows_.data(), n}, kHolisticMotionDimensions, holistic.dimensions(),
                               {sums_.data(), n});
  n = 0;
  for (Slot* s : slots_to_sum_)
    if (s->accumulated.status == descriptors::Status::kOk) s->accumulated_sum = sums_[n++];
  slots_to_sum_.clear();
}

void TrackClassifier::classify_pending() noexcept {
  const std::size_t n = pending_.size();
  if (n == 0) return;
  const GridClassifier& segment = model_->segment;
  const GridClassifier& holistic = model_->holistic;
  // H_S(z_t) of every pending segment: prior + the sum over its elements, as classify().
  for (std::size_t j = 0; j < n; ++j) {
    rows_[j] = batch_[j].values.data();
    sums_[j] = LogOdds{};
  }
  (void)segment.partial_batch({rows_.data(), n}, 0, segment.dimensions(), {sums_.data(), n});
  for (std::size_t j = 0; j < n; ++j) {
    segment_log_odds_[j] = segment.model().prior;
    for (std::size_t k = 0; k < segment.classes(); ++k) segment_log_odds_[j][k] += sums_[j][k];
  }
  // The tracks first seen in this scan: their segment is their accumulated description.
  for (std::size_t j = 0; j < n; ++j)
    if (pending_[j].refresh) slots_to_sum_.push_back(pending_[j].slot);  // room: max_tracks
  sum_accumulated();
  for (std::size_t j = 0; j < n; ++j) {
    Slot& s = *pending_[j].slot;
    LogOdds hh = s.accumulated_sum;
    (void)holistic.partial(pending_[j].motion, 0, kHolisticMotionDimensions, hh);
    s.evidence.add_segment(segment_log_odds_[j], segment.model().prior);
    for (std::size_t k = 0; k < holistic.classes(); ++k) hh[k] += holistic.model().prior[k];
    const LogOdds track = track_log_odds(*model_, s.evidence, hh);
    s.cls.classified = true;
    s.cls.log_odds = track;
    s.cls.label = predict(track, model_->classes.size());
    s.cls.segments = s.evidence.segments;
    s.class_scan = scans_;
  }
  pending_.clear();
}

void TrackClassifier::update_one(const float* xyzi, std::size_t stride_bytes, Kept& k) noexcept {
  k.classified = true;
  const tracking::Track& t = k.track;
  Slot& s = slots_[t.slot];  // begin() kept in-range slots, one track each
  if (s.cls.id != t.id) {    // a new track in this pool slot: forget the one before
    s.cloud.clear(t.id + 1);
    s.evidence.reset();
    s.cls = TrackClass{};
    s.cls.id = t.id;
    s.described = 0;
    s.since_holistic = 0;
  }
  const segmentation::Segment& seg = kept_segments_.segments[static_cast<std::size_t>(t.segment)];
  const descriptors::SegmentView view{xyzi, stride_bytes, kept_segments_.indices(seg), 0};
  descriptors::Descriptors& described = batch_[pending_.size()];
  describer_.compute(view, described);
  ++counters_.segments_described;
  if (described.status != descriptors::Status::kOk) {
    ++counters_.segments_empty;
    return;
  }
  k.accumulate = true;
  const bool first = ++s.described == 1;
  if (first) s.accumulated = described;  // the cloud will be this segment: its description
  holistic_descriptor(t, &s.accumulated, holistic_);
  if (observer_ != nullptr) observer_->on_update(t, described.values, holistic_);
  if (model_ == nullptr) return;
  Pending* p = pending_.append();  // room: pending_ and batch_ hold max_tracks
  p->slot = &s;
  p->refresh = first;
  std::copy(holistic_.begin(), holistic_.begin() + kHolisticMotionDimensions, p->motion.begin());
  if (pending_.size() == pending_.capacity()) classify_pending();
}

void TrackClassifier::begin(const segmentation::Segments& segments,
                            const tracking::TrackerOutput& tracked) noexcept {
  kept_tracks_.clear();
  kept_segments_.segments.clear();
  kept_segments_.point_indices.clear();
  ++scans_;
  std::uint32_t position = 0;
  for (const tracking::Track& t : tracked.tracks) {
    ++position;
    if (t.slot >= slots_.size()) {
      ++counters_.slot_mismatch;
      continue;
    }
    if (t.segment < 0 || static_cast<std::size_t>(t.segment) >= segments.segments.size()) continue;
    const segmentation::Segment& seg = segments.segments[static_cast<std::size_t>(t.segment)];
    const std::span<const std::uint32_t> indices = segments.indices(seg);
    const std::size_t first = kept_segments_.point_indices.size();
    const bool twice = slot_scan_[t.slot] == scans_;  // the later track takes the slot
    if (twice) ++counters_.slot_mismatch;
    Kept* k = twice ? &kept_tracks_[slot_kept_[t.slot]] : kept_tracks_.append();
    segmentation::Segment* copy = k != nullptr ? kept_segments_.segments.append() : nullptr;
    if (copy == nullptr || !kept_segments_.point_indices.resize(first + indices.size())) {
      if (copy != nullptr) (void)kept_segments_.segments.resize(kept_segments_.segments.size() - 1);
      if (k != nullptr && !twice) (void)kept_tracks_.resize(kept_tracks_.size() - 1);
      ++counters_.kept_overflow;
      continue;
    }
    std::copy(indices.begin(), indices.end(), kept_segments_.point_indices.data() + first);
    *copy = seg;
    copy->first = static_cast<std::uint32_t>(first);
    k->track = t;
    k->track.segment = static_cast<std::int32_t>(kept_segments_.segments.size() - 1);
    const Slot& s = slots_[t.slot];
    k->priority = s.cls.id == t.id ? s.described : 0;
    k->classified = false;
    k->accumulate = false;
    k->position = position;
    slot_scan_[t.slot] = scans_;
    slot_kept_[t.slot] = static_cast<std::uint32_t>(k - kept_tracks_.data());
  }
  std::sort(kept_tracks_.data(), kept_tracks_.data() + kept_tracks_.size(),
            [](const Kept& a, const Kept& b) {
              return a.priority != b.priority ? a.priority < b.priority : a.position < b.position;
            });
}

UpdateCount TrackClassifier::update(const float* xyzi, std::size_t stride_bytes,
                                    const UpdateLimit& limit) noexcept {
  const bool timed = limit.until_ns != UpdateLimit::kNoLimit;
  UpdateCount count;
  for (Kept& k : std::span<Kept>(kept_tracks_.data(), kept_tracks_.size())) {
    if (k.classified || (!limit.tentative && k.track.state == tracking::TrackState::kTentative))
      continue;
    if (count.late > 0 || (timed && rt::realtime_ns() >= limit.until_ns)) {
      ++count.late;
      continue;
    }
    update_one(xyzi, stride_bytes, k);
    ++count.classified;
  }
  if (model_ != nullptr) classify_pending();
  return count;
}

void TrackClassifier::finish(const float* xyzi, std::size_t stride_bytes) noexcept {
  (void)update(xyzi, stride_bytes, UpdateLimit{});
  for (const Kept& k : std::span<const Kept>(kept_tracks_.data(), kept_tracks_.size())) {
    if (!k.accumulate) continue;
    Slot& s = slots_[k.track.slot];
    const segmentation::Segment& seg =
        kept_segments_.segments[static_cast<std::size_t>(k.track.segment)];
    s.cloud.add_segment({xyzi, stride_bytes, kept_segments_.indices(seg), 0});
    if (++s.since_holistic < config_.holistic_every) continue;
    describer_.compute(s.cloud.view(), s.accumulated);
    ++counters_.holistic_described;
    s.since_holistic = 0;
    if (model_ != nullptr) slots_to_sum_.push_back(&s);  // room: max_tracks
  }
  if (model_ != nullptr) sum_accumulated();
  kept_tracks_.clear();
}

void TrackClassifier::report(const tracking::TrackerOutput& tracked,
                             rt::FixedVector<TrackClass>& out) const noexcept {
  out.clear();
  for (const tracking::Track& t : tracked.tracks) {
    TrackClass* c = out.append();
    if (c == nullptr) break;
    if (t.slot < slots_.size() && slots_[t.slot].cls.id == t.id) {
      *c = slots_[t.slot].cls;
      c->age = c->classified ? static_cast<std::uint32_t>(scans_ - slots_[t.slot].class_scan) : 0;
    } else {  // not classified yet, or out of the pool
      *c = TrackClass{};
      c->id = t.id;
    }
  }
}

void TrackClassifier::classify(const float* xyzi, std::size_t stride_bytes,
                               const segmentation::Segments& segments,
                               const tracking::TrackerOutput& tracked,
                               rt::FixedVector<TrackClass>& out) noexcept {
  begin(segments, tracked);
  (void)update(xyzi, stride_bytes, UpdateLimit{});
  finish(xyzi, stride_bytes);
  report(tracked, out);
}

}  // namespace stac::classification

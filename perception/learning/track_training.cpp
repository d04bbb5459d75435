#include "perception/learning/track_training.hpp"

#include <string>
#include <utility>

#include "rt/splitmix64.hpp"

namespace stac::learning {

TrackSample track_sample(const classification::TrackClassifierModel& model,
                         const TrackExample& track, std::size_t segment_dimensions) noexcept {
  TrackSample s;
  s.label = track.label;
  classification::TrackEvidence evidence;
  classification::LogOdds h{};
  for (std::size_t i = 0; i + segment_dimensions <= track.segments.size(); i += segment_dimensions)
    (void)add_segment(model, std::span(track.segments).subspan(i, segment_dimensions), evidence, h);
  s.segment_mean = evidence.segment_mean();
  (void)model.holistic.classify(track.holistic, s.holistic);
  return s;
}

rt::Result<classification::AdbfParams> fit_filter(const classification::TrackClassifierModel& model,
                                                  std::span<const TrackExample> tracks,
                                                  std::size_t segment_dimensions,
                                                  const LogisticConfig& config) {
  std::vector<TrackSample> samples;
  samples.reserve(tracks.size());
  for (const TrackExample& t : tracks)
    samples.push_back(track_sample(model, t, segment_dimensions));
  return fit_adbf(samples, model.holistic.model().prior, model.classes.size(), config);
}

rt::Result<classification::TrackClassifierModel> train_track_classifier(
    std::span<const TrackExample> tracks, const classification::ClassNames& classes,
    const classification::ExpectedLayouts& layouts, const TrackTrainingConfig& config) {
  if (const std::string bad = classification::check_class_names(classes); !bad.empty())
    return rt::make_error("classes: " + bad);
  const std::size_t seg_dims = classification::layout_dimensions(layouts.segment);
  const std::size_t hol_dims = classification::layout_dimensions(layouts.holistic);
  if (!(config.held_out_fraction > 0.0 && config.held_out_fraction < 1.0))
    return rt::make_error("held_out_fraction must be in (0, 1)");

  // Split by track (a track's segments are never on both sides).
  rt::SplitMix64 rng(config.split_seed);
  std::vector<const TrackExample*> held_out;
  TrainingSet segments{seg_dims, classes.size(), {}, {}};
  TrainingSet holistic{hol_dims, classes.size(), {}, {}};
  for (std::size_t m = 0; m < tracks.size(); ++m) {
    const TrackExample& t = tracks[m];
    if (t.segments.empty() || t.segments.size() % seg_dims != 0 || t.holistic.size() != hol_dims)
      return rt::make_error("track " + std::to_string(m) + " has " +
                            std::to_string(t.segments.size()) + " segment values and " +
                            std::to_string(t.holistic.size()) +
                            " holistic values; the layouts need a positive multiple of " +
                            std::to_string(seg_dims) + " and " + std::to_string(hol_dims));
    if (rng.uniform() < config.held_out_fraction) {
      held_out.push_back(&t);
      continue;
    }
    for (std::size_t i = 0; i < t.segments.size(); i += seg_dims)
      segments.add(std::span(t.segments).subspan(i, seg_dims), t.label);
    holistic.add(t.holistic, t.label);
  }
  if (held_out.empty() || holistic.size() == 0)
    return rt::make_error("the split left no training or no held-out track (" +
                          std::to_string(tracks.size()) + " tracks)");

  if (config.ensemble < 1 || config.ensemble > 64)
    return rt::make_error("ensemble must be in [1, 64]");
  classification::TrackClassifierModel model;
  model.classes = classes;
  const std::size_t per_member = config.segment.rounds + config.holistic.rounds;
  const double total = static_cast<double>(per_member * config.ensemble);
  const auto report = [&](std::size_t before) {
    return [&config, before, total](std::size_t done) {
      if (config.progress) config.progress(static_cast<double>(before + done) / total);
    };
  };
  std::vector<GridClassifier> seg_members, hol_members;
  for (std::size_t k = 0; k < config.ensemble; ++k) {
    BoostingConfig seg_config = config.segment, hol_config = config.holistic;
    seg_config.seed += 2 * k;
    hol_config.seed += 2 * k;
    auto seg = train_boosting(segments, layouts.segment, seg_config, report(k * per_member));
    if (!seg) return rt::make_error("segment classifier: " + seg.error().message);
    auto hol = train_boosting(holistic, layouts.holistic, hol_config,
                              report(k * per_member + config.segment.rounds));
    if (!hol) return rt::make_error("holistic classifier: " + hol.error().message);
    seg_members.push_back(std::move(seg).value());
    hol_members.push_back(std::move(hol).value());
  }
  auto seg = average_classifiers(seg_members);
  if (!seg) return rt::make_error("segment classifier: " + seg.error().message);
  auto hol = average_classifiers(hol_members);
  if (!hol) return rt::make_error("holistic classifier: " + hol.error().message);
  model.segment = std::move(seg).value();
  model.holistic = std::move(hol).value();

  std::vector<TrackSample> samples;
  samples.reserve(held_out.size());
  for (const TrackExample* t : held_out) samples.push_back(track_sample(model, *t, seg_dims));
  auto adbf = fit_adbf(samples, model.holistic.model().prior, classes.size(), config.filter);
  if (!adbf) return rt::make_error("filter: " + adbf.error().message);
  model.adbf = *adbf;
  return model;
}

}  // namespace stac::learning

// Training a whole track classifier (what `stac train` runs, without the files): the segment and
// holistic boosting classifiers on one part of the labelled tracks, then the augmented discrete
// Bayes filter's parameters on the held-out rest (thesis ch. 1).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "perception/classification/model.hpp"
#include "perception/learning/boosting.hpp"
#include "perception/learning/logistic.hpp"

namespace stac::learning {

// One labelled track: its segments' descriptors (row-major, segment layout) and its holistic
// descriptor (holistic layout; NaN where absent).
struct TrackExample {
  ClassIndex label = classification::kBackground;  // an index into the classes trained
  std::vector<float> segments;
  std::vector<float> holistic;
};

struct TrackTrainingConfig {
  BoostingConfig segment;
  BoostingConfig holistic;
  LogisticConfig filter;
  double held_out_fraction = 0.3;  // tracks kept for the filter fit, drawn with split_seed
  std::uint64_t split_seed = 1;
  // Boosting runs per classifier (seeds segment.seed + 2k, holistic.seed + 2k), averaged into
  // one table (average_classifiers): the runtime cost is that of one.
  std::size_t ensemble = 1;
  // Optional: told the fraction of the boosting rounds (segment, then holistic) done, in [0, 1].
  std::function<void(double)> progress;
};

// One track through `model`'s classifiers, as the filter's fit sees it: its holistic log odds
// (its holistic descriptor) and the mean of its segments' evidence.
TrackSample track_sample(const classification::TrackClassifierModel& model,
                         const TrackExample& track, std::size_t segment_dimensions) noexcept;

// The augmented filter's alpha, beta, gamma fitted (fit_adbf) on labelled tracks through
// `model`'s classifiers.
rt::Result<classification::AdbfParams> fit_filter(const classification::TrackClassifierModel& model,
                                                  std::span<const TrackExample> tracks,
                                                  std::size_t segment_dimensions,
                                                  const LogisticConfig& config);

// A model of the classes `classes` (labels index them). Fails with a message on class names
// check_class_names refuses, a label past them, an empty split, descriptors of the wrong size,
// or a failed fit.
rt::Result<classification::TrackClassifierModel> train_track_classifier(
    std::span<const TrackExample> tracks, const classification::ClassNames& classes,
    const classification::ExpectedLayouts& layouts, const TrackTrainingConfig& config);

}  // namespace stac::learning

// Offline training of the parametric boosting classifier (thesis ch. 2; docs/classification.md):
// grid ranges from the data, then GentleBoost rounds over 1-vs-all problems with shared weak
// classifiers (one bin, one response per class). Training allocates; it is not real time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "perception/classification/grid_classifier.hpp"
#include "rt/expected.hpp"
#include "rt/splitmix64.hpp"

namespace stac::learning {

using classification::ClassIndex;
using classification::GridClassifier;
using classification::LogOdds;

// Examples as rows of `dimensions` floats, each labelled with a class index 0..classes-1 or
// classification::kBackground (negative for every class).
struct TrainingSet {
  std::size_t dimensions = 0;
  std::size_t classes = classification::kDefaultClassCount;  // 1..kMaxClasses
  std::vector<float> features;                               // size() * dimensions, row-major
  std::vector<ClassIndex> labels;

  void add(std::span<const float> x, ClassIndex label);  // x.size() must be dimensions
  [[nodiscard]] std::size_t size() const noexcept { return labels.size(); }
  [[nodiscard]] std::span<const float> row(std::size_t i) const noexcept {
    return {features.data() + i * dimensions, dimensions};
  }
};

struct BoostingConfig {
  std::size_t rounds = 1000;              // weak classifiers added
  std::size_t candidates_per_round = 24;  // cells sampled from the boosting weights per round
  std::vector<std::uint32_t> resolutions{10, 100};  // bins per grid
  double range_percentile = 0.01;  // grid range: [p, 1-p] quantiles of the training values...
  double range_widen = 0.01;       // ...widened by this fraction of the range on each side
  float max_response = 4.0f;       // |response| cap per weak classifier (log odds)
  std::uint64_t seed = 1;          // same seed, same data, same model
  // Bit k set: class k is kept as it is (a model's classes while a user teaches new ones,
  // docs/learning.md "A new class"): its responses, and so its weights, never change, and its
  // weights neither draw candidates nor count in a candidate's gain.
  std::uint32_t frozen = 0;
};

// Empty when the configuration is usable, else what is wrong.
const char* validate(const BoostingConfig& config) noexcept;

// Statistics of one cell for one class: boosting weight of positives and of negatives in it.
struct CellStats {
  double positive = 0, negative = 0;
};
// Newton step of the loss sum w*exp(-y*c/2) at c = 0: 2*sum(w*y)/sum(w*|y|) (the 1/2 of thesis
// eq. 1.1 makes H a log odds; the factor 2 follows from it), 0 for an empty cell, capped.
float newton_response(const CellStats& s, float max_response) noexcept;
// The cell's loss after adding response c: positive*exp(-c/2) + negative*exp(c/2).
double loss_after(const CellStats& s, float c) noexcept;

// The prior log odds of a training set: L0 = log((n_pos+1)/(n_neg+1)) per class (0 past them).
LogOdds prior_log_odds(const TrainingSet& data) noexcept;

// A classifier with data-derived grids, prior log odds L0 = log((n_pos+1)/(n_neg+1)) per class
// and an all-zero table, for data.classes classes. Fails on an empty set, a layout whose size is
// not `dimensions`, a class count not 1..kMaxClasses, a label past it or a configuration
// validate() refuses.
rt::Result<GridClassifier> initial_classifier(const TrainingSet& data,
                                              const classification::Layout& layout,
                                              const BoostingConfig& config);

class BoostingTrainer {
 public:
  // Precomputes every example's bin in every grid; weights w = exp(-y*H/2) per (example, class).
  // `data` must outlive the trainer (it is read, not copied).
  BoostingTrainer(const TrainingSet& data, GridClassifier initial, const BoostingConfig& config);
  void run(std::size_t rounds);
  [[nodiscard]] double loss() const noexcept;  // sum of w over examples and classes
  [[nodiscard]] std::size_t rounds_done() const noexcept { return rounds_; }
  [[nodiscard]] const GridClassifier& classifier() const noexcept { return classifier_; }

 private:
  void round();
  const TrainingSet& data_;
  GridClassifier classifier_;
  BoostingConfig config_;
  std::vector<std::uint16_t> bins_;  // [grid][example]
  std::vector<double> weights_;      // [example][class]
  std::vector<double> cumulative_;   // per example, for sampling
  rt::SplitMix64 rng_;
  std::size_t rounds_ = 0;
};

// initial_classifier + config.rounds rounds; `on_rounds` (optional) is told the rounds done about
// every 1% of them (progress bars). The model does not depend on it.
rt::Result<GridClassifier> train_boosting(const TrainingSet& data,
                                          const classification::Layout& layout,
                                          const BoostingConfig& config,
                                          const std::function<void(std::size_t)>& on_rounds = {});

// The mean of classifiers on the same grids (train_boosting runs on the same data and
// resolutions with different seeds): responses averaged cell by cell, so the mean classifies at
// the cost of one. Fails when there is none, or their layouts, grids or priors differ.
rt::Result<GridClassifier> average_classifiers(std::span<const GridClassifier> members);

}  // namespace stac::learning

// Synthetic labelled examples for the classification tests (deterministic for a seed).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "perception/learning/boosting.hpp"

namespace stac::classification::testing {

inline Layout flat_layout(std::size_t dimensions, const std::string& prefix = "x") {
  Layout l;
  for (std::size_t e = 0; e < dimensions; ++e) l.push_back({prefix + std::to_string(e), 1});
  return l;
}

inline ObjectClass random_class(std::mt19937& rng) {
  return static_cast<ObjectClass>(std::uniform_int_distribution<int>(0, 3)(rng));
}

// Element 0 alone tells the class: class c lies in [2c, 2c + 1); the rest is noise.
inline learning::TrainingSet separable(std::size_t n, std::size_t dimensions, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  learning::TrainingSet set{dimensions, {}, {}};
  std::vector<float> x(dimensions);
  for (std::size_t i = 0; i < n; ++i) {
    const ObjectClass c = random_class(rng);
    for (auto& v : x) v = 10.0f * u(rng);
    x[0] = 2.0f * static_cast<float>(c) + u(rng);
    set.add(x, c);
  }
  return set;
}

// Overlapping classes a linear model cannot separate: element c is near 0 for class c and about
// +-2 (either side) otherwise, with unit noise; a fraction of the labels is then flipped.
inline learning::TrainingSet noisy(std::size_t n, std::size_t dimensions, double label_noise,
                                   unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 0.7f);
  std::bernoulli_distribution side(0.5), flip(label_noise);
  learning::TrainingSet set{dimensions, {}, {}};
  std::vector<float> x(dimensions);
  for (std::size_t i = 0; i < n; ++i) {
    const ObjectClass c = random_class(rng);
    for (std::size_t e = 0; e < dimensions; ++e) {
      const bool own = e < 4 && static_cast<std::size_t>(c) == e;
      x[e] = (e < 4 && !own ? (side(rng) ? 2.0f : -2.0f) : 0.0f) + noise(rng);
    }
    set.add(x, flip(rng) ? random_class(rng) : c);
  }
  return set;
}

// train_boosting; a failure is a test failure (and an empty classifier that classifies nothing).
inline GridClassifier trained(const learning::TrainingSet& set, const Layout& layout,
                              const learning::BoostingConfig& config) {
  auto c = learning::train_boosting(set, layout, config);
  if (!c.has_value()) {
    ADD_FAILURE() << c.error().message;
    return {};
  }
  return std::move(c).value();
}

inline double accuracy(const GridClassifier& c, const learning::TrainingSet& set) {
  std::size_t right = 0;
  for (std::size_t i = 0; i < set.size(); ++i) {
    LogOdds h{};
    if (c.classify(set.row(i), h) && predict(h) == set.labels[i]) ++right;
  }
  return static_cast<double>(right) / static_cast<double>(set.size());
}

}  // namespace stac::classification::testing

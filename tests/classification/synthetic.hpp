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

// The label of ordinal k: class k, background for k = classes.
inline ClassIndex label_of(int k, std::size_t classes = kDefaultClassCount) {
  return static_cast<std::size_t>(k) == classes ? kBackground : static_cast<ClassIndex>(k);
}
// A class index 0..classes-1 or background, equally likely.
inline ClassIndex random_class(std::mt19937& rng, std::size_t classes = kDefaultClassCount) {
  return label_of(std::uniform_int_distribution<int>(0, static_cast<int>(classes))(rng), classes);
}
// 0..classes-1 for a class, `classes` for background.
inline std::size_t ordinal(ClassIndex c, std::size_t classes = kDefaultClassCount) {
  return c == kBackground ? classes : c;
}

// Element 0 alone tells the class: class c lies in [2c, 2c + 1) (background: c = classes); the
// rest is noise.
inline learning::TrainingSet separable(std::size_t n, std::size_t dimensions, unsigned seed,
                                       std::size_t classes = kDefaultClassCount) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  learning::TrainingSet set{dimensions, classes, {}, {}};
  std::vector<float> x(dimensions);
  for (std::size_t i = 0; i < n; ++i) {
    const ClassIndex c = random_class(rng, classes);
    for (auto& v : x) v = 10.0f * u(rng);
    x[0] = 2.0f * static_cast<float>(ordinal(c, classes)) + u(rng);
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
  learning::TrainingSet set{dimensions, kDefaultClassCount, {}, {}};
  std::vector<float> x(dimensions);
  for (std::size_t i = 0; i < n; ++i) {
    const ClassIndex c = random_class(rng);
    for (std::size_t e = 0; e < dimensions; ++e) {
      const bool own = e < 4 && ordinal(c) == e;
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
    if (c.classify(set.row(i), h) && predict(h, c.classes()) == set.labels[i]) ++right;
  }
  return static_cast<double>(right) / static_cast<double>(set.size());
}

}  // namespace stac::classification::testing

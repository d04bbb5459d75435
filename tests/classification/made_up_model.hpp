// A full-size track classifier model with made-up responses, for tests and benchmarks whose
// subject is the classify stage's work (the same amount of it whatever the numbers; a trained
// model's bins are spread wider over the tables, so it misses the cache more):
// grids over [-1, 1] of every segment and holistic descriptor element (10 and 100 bins),
// responses cycling through small values of both signs.
#pragma once

#include <memory>

#include "perception/classification/holistic.hpp"
#include "perception/classification/model.hpp"

namespace stac::classification::testing {

inline rt::Result<GridClassifier> made_up_grid(Layout layout) {
  GridModel m;
  m.layout = std::move(layout);
  m.resolutions = {10, 100};
  m.prior = {-1.0f, -1.5f, -2.0f};
  const std::size_t dims = layout_dimensions(m.layout);
  m.lower.assign(2 * dims, -1.0f);
  for (std::size_t g = 0; g < 2 * dims; ++g) m.scale.push_back(g % 2 == 0 ? 5.0f : 50.0f);
  for (std::size_t c = 0; c < dims * 110 * m.classes; ++c)
    m.table.push_back(0.001f * static_cast<float>(static_cast<int>(c % 7) - 3));
  return GridClassifier::create(std::move(m));
}

// This build's segment and holistic layouts; an error only if GridClassifier::create refuses.
inline rt::Result<std::shared_ptr<const TrackClassifierModel>> made_up_model() {
  auto segment = made_up_grid(segment_layout());
  if (!segment) return rt::Unexpected<rt::Error>{segment.error()};
  auto holistic = made_up_grid(holistic_layout());
  if (!holistic) return rt::Unexpected<rt::Error>{holistic.error()};
  return std::make_shared<const TrackClassifierModel>(
      TrackClassifierModel{std::move(*segment), std::move(*holistic), {}});
}

}  // namespace stac::classification::testing

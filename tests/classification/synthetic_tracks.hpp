// Synthetic labelled tracks for the track-level learning tests (deterministic for a seed).
#pragma once

#include <random>
#include <vector>

#include "perception/classification/model.hpp"
#include "perception/learning/track_training.hpp"
#include "synthetic.hpp"

namespace stac::classification::testing {

inline ExpectedLayouts layouts() {
  return {{{"shape", 4}, {"noise", 2}}, {{"speed", 1}, {"size", 1}}};
}

// Segments: element c of "shape" is near 0 for class c, +-2 otherwise, under heavy per-frame
// noise and a per-track bias (segments of a track are not independent). Holistic: a speed and a
// size per class, noisy enough that neither part alone is reliable.
// `frame_noise` and `track_bias` scale the two noises (1: the default, hard per segment).
inline std::vector<learning::TrackExample> synthetic_tracks(int n, unsigned seed,
                                                            float frame_noise = 1.0f,
                                                            float track_bias = 1.0f) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::bernoulli_distribution side(0.5);
  std::uniform_int_distribution<int> label(0, 3), length(10, 30);
  const float speed[4] = {8.0f, 1.4f, 4.5f, 0.5f}, size[4] = {4.5f, 0.6f, 1.8f, 1.5f};
  std::vector<learning::TrackExample> tracks;
  for (int m = 0; m < n; ++m) {
    learning::TrackExample t;
    const int c = label(rng);
    t.label = label_of(c);
    float bias[6];
    for (float& b : bias) b = track_bias * 0.8f * g(rng);
    for (int f = length(rng); f > 0; --f)
      for (int e = 0; e < 6; ++e) {
        const float base = e < 4 && e != c ? (side(rng) ? 2.0f : -2.0f) : 0.0f;
        t.segments.push_back(base + bias[e] + frame_noise * 1.6f * g(rng));
      }
    t.holistic = {speed[c] + 2.0f * g(rng), size[c] + 1.0f * g(rng)};
    tracks.push_back(std::move(t));
  }
  return tracks;
}

}  // namespace stac::classification::testing

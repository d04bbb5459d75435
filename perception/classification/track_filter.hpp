// Discrete Bayes filters over a track (thesis ch. 1, eq. 1.3-1.4; docs/classification.md). A
// track keeps a TrackEvidence: fixed memory (a running sum and a count), never a list of frames.
// Every function is noexcept and allocation-free, and works on all kMaxClasses entries: the
// entries past a model's class count stay 0 when the inputs' are 0.
#pragma once

#include <array>
#include <cstdint>

#include "perception/classification/grid_classifier.hpp"

namespace stac::classification {

// Per-track running segment evidence: sum over segments t of (H_S(z_t) - L0_S) per class.
struct TrackEvidence {
  std::array<double, kMaxClasses> segment_sum{};  // double: no drift over long tracks
  std::uint32_t segments = 0;

  // One classified segment: its log odds H_S(z_t) and the segment classifier's prior L0_S.
  void add_segment(const LogOdds& segment_log_odds, const LogOdds& segment_prior) noexcept;
  void reset() noexcept { *this = TrackEvidence{}; }
  // (1/T) sum_t (H_S(z_t) - L0_S); zero before the first segment.
  [[nodiscard]] LogOdds segment_mean() const noexcept;
};

// Per class: H_A = alpha*L0_H + beta*(H_H(w) - L0_H) + gamma*(1/T) sum_t (H_S(z_t) - L0_S).
// The defaults (all 1) make it the normalized filter; fit them with learning::fit_adbf. Entries
// past the model's class count are unused (a model file holds the first K).
struct AdbfParams {
  static constexpr LogOdds kOnes = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
  static_assert(kMaxClasses == 8);
  LogOdds alpha = kOnes;
  LogOdds beta = kOnes;
  LogOdds gamma = kOnes;
};

// Naive DBF: base + sum_t (H_S(z_t) - L0_S). `base` is the holistic log odds H_H(w) (eq. 1.3)
// or, without a holistic classifier, the prior L0.
LogOdds naive_dbf(const TrackEvidence& evidence, const LogOdds& base) noexcept;
// Normalized DBF: base + (1/T) sum_t (H_S(z_t) - L0_S).
LogOdds normalized_dbf(const TrackEvidence& evidence, const LogOdds& base) noexcept;
// Augmented DBF (eq. 1.4): holistic_prior is L0_H, holistic is H_H(w).
LogOdds augmented_dbf(const TrackEvidence& evidence, const LogOdds& holistic_prior,
                      const LogOdds& holistic, const AdbfParams& params) noexcept;

}  // namespace stac::classification

#include "perception/classification/track_filter.hpp"

namespace stac::classification {

void TrackEvidence::add_segment(const LogOdds& segment_log_odds,
                                const LogOdds& segment_prior) noexcept {
  for (std::size_t k = 0; k < kMaxClasses; ++k)
    segment_sum[k] += static_cast<double>(segment_log_odds[k]) - segment_prior[k];
  ++segments;
}

LogOdds TrackEvidence::segment_mean() const noexcept {
  LogOdds mean{};
  if (segments == 0) return mean;
  for (std::size_t k = 0; k < kMaxClasses; ++k)
    mean[k] = static_cast<float>(segment_sum[k] / segments);
  return mean;
}

LogOdds naive_dbf(const TrackEvidence& evidence, const LogOdds& base) noexcept {
  LogOdds out{};
  for (std::size_t k = 0; k < kMaxClasses; ++k)
    out[k] = static_cast<float>(base[k] + evidence.segment_sum[k]);
  return out;
}

LogOdds normalized_dbf(const TrackEvidence& evidence, const LogOdds& base) noexcept {
  const LogOdds mean = evidence.segment_mean();
  LogOdds out{};
  for (std::size_t k = 0; k < kMaxClasses; ++k) out[k] = base[k] + mean[k];
  return out;
}

LogOdds augmented_dbf(const TrackEvidence& evidence, const LogOdds& holistic_prior,
                      const LogOdds& holistic, const AdbfParams& params) noexcept {
  const LogOdds mean = evidence.segment_mean();
  LogOdds out{};
  for (std::size_t k = 0; k < kMaxClasses; ++k)
    out[k] = params.alpha[k] * holistic_prior[k] +
             params.beta[k] * (holistic[k] - holistic_prior[k]) + params.gamma[k] * mean[k];
  return out;
}

}  // namespace stac::classification

// L2-regularized logistic regression by Newton's method, and the augmented discrete Bayes
// filter's alpha, beta, gamma per class fitted with it on held-out tracks (thesis eq. 1.5).
#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "perception/classification/track_filter.hpp"
#include "rt/expected.hpp"

namespace stac::learning {

struct LogisticConfig {
  double l2 = 1e-3;          // lambda of (lambda/2)*|theta|^2, added to the mean log loss
  int max_iterations = 50;   // Newton steps
  double tolerance = 1e-10;  // stop when the step's squared norm is below it
};

// theta minimising mean_m log(1 + exp(-y_m * x_m . theta)) + (l2/2)|theta|^2; y_m in {-1, +1},
// rows of x are examples. Fails when sizes disagree or there is no example.
rt::Result<Eigen::VectorXd> fit_logistic(const Eigen::MatrixXd& x, std::span<const double> y,
                                         const LogisticConfig& config);

// One held-out track: the holistic classifier's log odds H_H(w), the filter's
// (1/T) sum_t (H_S(z_t) - L0_S) (TrackEvidence::segment_mean) and the true class.
struct TrackSample {
  classification::LogOdds holistic{};
  classification::LogOdds segment_mean{};
  classification::ClassIndex label = classification::kBackground;
};

// Per class 0..classes-1, logistic regression on (L0_H, H_H - L0_H, mean) against y = +1 for
// that class (entries past `classes` stay 1).
rt::Result<classification::AdbfParams> fit_adbf(std::span<const TrackSample> tracks,
                                                const classification::LogOdds& holistic_prior,
                                                std::size_t classes, const LogisticConfig& config);

}  // namespace stac::learning

#include "perception/learning/logistic.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <string>

namespace stac::learning {

rt::Result<Eigen::VectorXd> fit_logistic(const Eigen::MatrixXd& x, std::span<const double> y,
                                         const LogisticConfig& config) {
  const auto n = x.rows(), d = x.cols();
  if (n == 0 || d == 0) return rt::make_error("logistic regression has no example");
  if (static_cast<std::size_t>(n) != y.size())
    return rt::make_error("logistic regression has " + std::to_string(n) + " rows and " +
                          std::to_string(y.size()) + " labels");
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(d);
  for (int it = 0; it < config.max_iterations; ++it) {
    Eigen::VectorXd gradient = config.l2 * theta;
    Eigen::MatrixXd hessian = config.l2 * Eigen::MatrixXd::Identity(d, d);
    for (Eigen::Index m = 0; m < n; ++m) {
      const double margin = y[static_cast<std::size_t>(m)] * x.row(m).dot(theta);
      const double p = 1.0 / (1.0 + std::exp(margin));  // sigmoid(-margin)
      gradient -= (y[static_cast<std::size_t>(m)] * p / double(n)) * x.row(m).transpose();
      hessian += (p * (1.0 - p) / double(n)) * x.row(m).transpose() * x.row(m);
    }
    const Eigen::VectorXd step = hessian.ldlt().solve(gradient);
    if (!step.allFinite()) return rt::make_error("logistic regression diverged");
    theta -= step;
    if (step.squaredNorm() < config.tolerance) break;
  }
  return theta;
}

rt::Result<classification::AdbfParams> fit_adbf(std::span<const TrackSample> tracks,
                                                const classification::LogOdds& holistic_prior,
                                                std::size_t classes, const LogisticConfig& config) {
  classification::AdbfParams params;
  if (classes == 0 || classes > classification::kMaxClasses)
    return rt::make_error(std::to_string(classes) + " classes, not 1.." +
                          std::to_string(classification::kMaxClasses));
  const auto n = static_cast<Eigen::Index>(tracks.size());
  Eigen::MatrixXd x(n, 3);
  std::vector<double> y(tracks.size());
  for (std::size_t k = 0; k < classes; ++k) {
    for (Eigen::Index m = 0; m < n; ++m) {
      const TrackSample& t = tracks[static_cast<std::size_t>(m)];
      x(m, 0) = holistic_prior[k];
      x(m, 1) = t.holistic[k] - holistic_prior[k];
      x(m, 2) = t.segment_mean[k];
      y[static_cast<std::size_t>(m)] = static_cast<std::size_t>(t.label) == k ? 1.0 : -1.0;
    }
    auto theta = fit_logistic(x, y, config);
    if (!theta)
      return rt::make_error("fitting the filter of class " + std::to_string(k) + ": " +
                            theta.error().message);
    params.alpha[k] = static_cast<float>((*theta)[0]);
    params.beta[k] = static_cast<float>((*theta)[1]);
    params.gamma[k] = static_cast<float>((*theta)[2]);
  }
  return params;
}

}  // namespace stac::learning

// The track's Kalman filter (thesis ch. 1): state px, py, pz, vx, vy in the world frame;
// constant velocity in x,y under white-noise acceleration, z a random walk; the measurement is
// the position. Fixed-size Eigen types: nothing allocates.
#pragma once

#include <Eigen/Core>

#include "perception/tracking/tracker_config.hpp"

namespace stac::tracking {

struct KalmanFilter {
  using State = Eigen::Matrix<double, 5, 1>;  // px, py, pz, vx, vy
  using Cov = Eigen::Matrix<double, 5, 5>;
  using Meas = Eigen::Matrix<double, 3, 1>;  // px, py, pz
  using MeasCov = Eigen::Matrix<double, 3, 3>;

  State x = State::Zero();
  Cov p = Cov::Identity();

  // A new track at `position`, at rest with the configured velocity uncertainty.
  void start(const Meas& position, const KalmanConfig& c) noexcept;
  // Moves the state dt seconds on (nothing when dt <= 0).
  void predict(double dt, const KalmanConfig& c) noexcept;
  // Corrects with a measured position; `spread` (x,y, m^2) adds to the measurement noise.
  void correct(const Meas& z, const KalmanConfig& c,
               const Eigen::Matrix2d* spread = nullptr) noexcept;
  // The x,y innovation covariance of a position measurement (the association's gate).
  [[nodiscard]] Eigen::Matrix2d xy_innovation(const KalmanConfig& c) const noexcept;
  // sqrt of the largest eigenvalue of the x,y position covariance (m).
  [[nodiscard]] double position_std() const noexcept;
};

}  // namespace stac::tracking

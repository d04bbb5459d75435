#include "perception/tracking/kalman.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace stac::tracking {

void KalmanFilter::start(const Meas& position, const KalmanConfig& c) noexcept {
  x = State::Zero();
  x.head<3>() = position;
  p = Cov::Zero();
  const double r = c.measurement_std_m * c.measurement_std_m;
  const double v = c.initial_velocity_std_mps * c.initial_velocity_std_mps;
  p.diagonal() << r, r, c.measurement_z_std_m * c.measurement_z_std_m, v, v;
}

void KalmanFilter::predict(double dt, const KalmanConfig& c) noexcept {
  if (dt <= 0) return;
  Cov f = Cov::Identity();
  f(0, 3) = dt;
  f(1, 4) = dt;
  x = f * x;
  const double q = c.accel_std_mps2 * c.accel_std_mps2;
  Cov qm = Cov::Zero();
  for (int axis = 0; axis < 2; ++axis) {  // white-noise acceleration, per axis
    qm(axis, axis) = q * dt * dt * dt * dt / 4;
    qm(axis, axis + 3) = qm(axis + 3, axis) = q * dt * dt * dt / 2;
    qm(axis + 3, axis + 3) = q * dt * dt;
  }
  qm(2, 2) = c.z_velocity_std_mps * c.z_velocity_std_mps * dt * dt;
  p = f * p * f.transpose() + qm;
}

void KalmanFilter::correct(const Meas& z, const KalmanConfig& c,
                           const Eigen::Matrix2d* spread) noexcept {
  using Gain = Eigen::Matrix<double, 5, 3>;
  const double r = c.measurement_std_m * c.measurement_std_m;
  const double rz = c.measurement_z_std_m * c.measurement_z_std_m;
  MeasCov rm = MeasCov::Zero();
  rm.diagonal() = Meas(r, r, rz);
  if (spread != nullptr) rm.topLeftCorner<2, 2>() += *spread;
  MeasCov sm = p.topLeftCorner<3, 3>() + rm;
  const Gain k = p.leftCols<3>() * sm.inverse();
  const Meas innovation = z - x.head<3>();
  x += k * innovation;
  Cov ikh = Cov::Identity();
  ikh.leftCols<3>() -= k;
  p = ikh * p * ikh.transpose() + k * rm * k.transpose();  // Joseph form: stays symmetric PSD
}

Eigen::Matrix2d KalmanFilter::xy_innovation(const KalmanConfig& c) const noexcept {
  const double r = c.measurement_std_m * c.measurement_std_m;
  Eigen::Matrix2d sxy = p.topLeftCorner<2, 2>();
  sxy.diagonal() += Eigen::Vector2d(r, r);
  return sxy;
}

double KalmanFilter::position_std() const noexcept {
  // Largest eigenvalue of the symmetric 2x2 x,y block, in closed form.
  const double a = p(0, 0), b = p(0, 1), d = p(1, 1);
  const double mean = 0.5 * (a + d);
  const double spread = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  return std::sqrt(std::max(0.0, mean + spread));
}

}  // namespace stac::tracking

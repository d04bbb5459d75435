#include "perception/tracking/kalman.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace stac::tracking {
namespace {

TEST(KalmanFilter, StartsAtRestWithTheConfiguredUncertainty) {
  const KalmanConfig c;
  KalmanFilter kf;
  kf.start(KalmanFilter::Meas(1, 2, 3), c);
  EXPECT_EQ(kf.x, (KalmanFilter::State() << 1, 2, 3, 0, 0).finished());
  EXPECT_DOUBLE_EQ(kf.p(0, 0), c.measurement_std_m * c.measurement_std_m);
  EXPECT_DOUBLE_EQ(kf.p(2, 2), c.measurement_z_std_m * c.measurement_z_std_m);
  EXPECT_DOUBLE_EQ(kf.p(3, 3), c.initial_velocity_std_mps * c.initial_velocity_std_mps);
  EXPECT_DOUBLE_EQ(kf.position_std(), c.measurement_std_m);
}

TEST(KalmanFilter, PredictMovesAtTheVelocityAndGrowsTheUncertainty) {
  const KalmanConfig c;
  KalmanFilter kf;
  kf.start(KalmanFilter::Meas(0, 0, 0), c);
  kf.x(3) = 10;  // 10 m/s along x
  const double before = kf.position_std();
  kf.predict(0.1, c);
  EXPECT_NEAR(kf.x(0), 1.0, 1e-12);
  EXPECT_GT(kf.position_std(), before);
  const KalmanFilter::State held = kf.x;
  kf.predict(0, c);  // no time: nothing moves
  kf.predict(-0.1, c);
  EXPECT_EQ(kf.x, held);
}

TEST(KalmanFilter, LearnsAConstantVelocityFromPositions) {
  const KalmanConfig c;
  KalmanFilter kf;
  kf.start(KalmanFilter::Meas(0, 0, 1), c);
  for (int k = 1; k <= 50; ++k) {
    kf.predict(0.1, c);
    kf.correct(KalmanFilter::Meas(0.5 * k, -0.2 * k, 1), c);  // 5 m/s x, -2 m/s y
  }
  EXPECT_NEAR(kf.x(3), 5.0, 0.05);
  EXPECT_NEAR(kf.x(4), -2.0, 0.05);
  EXPECT_NEAR(kf.x(2), 1.0, 1e-6);
  EXPECT_LT(kf.position_std(), c.measurement_std_m);
  // The covariance stays symmetric (Joseph form).
  EXPECT_LT((kf.p - kf.p.transpose()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(KalmanFilter, ASpreadMeasurementMovesTheStateLess) {
  const KalmanConfig c;
  KalmanFilter tight, loose;
  tight.start(KalmanFilter::Meas(0, 0, 0), c);
  loose.start(KalmanFilter::Meas(0, 0, 0), c);
  const Eigen::Matrix2d spread = Eigen::Matrix2d::Identity() * 4.0;  // 2 m std along x and y
  tight.correct(KalmanFilter::Meas(1, 0, 0), c);
  loose.correct(KalmanFilter::Meas(1, 0, 0), c, &spread);
  EXPECT_GT(tight.x(0), loose.x(0));
  EXPECT_GT(loose.x(0), 0.0);
  // The gate's innovation covariance is the position covariance plus the measurement noise.
  const Eigen::Matrix2d s = tight.xy_innovation(c);
  EXPECT_DOUBLE_EQ(s(0, 0), tight.p(0, 0) + c.measurement_std_m * c.measurement_std_m);
  EXPECT_DOUBLE_EQ(s(0, 1), tight.p(0, 1));
}

}  // namespace
}  // namespace stac::tracking

// The odometry decoder of the shipped DBC (config/can/vehicle.dbc) and frames of its two messages:
// speed 0x1A0 (VehicleSpeed, Motorola, 0.01 km/h) and yaw rate 0x1B0 (YawRate, Intel, 0.01 deg/s).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <initializer_list>

#include "drivers/can/odometry.hpp"
#include "test_paths.hpp"

namespace stac::testing {

inline constexpr std::uint32_t kSpeedId = 0x1A0;
inline constexpr std::uint32_t kYawRateId = 0x1B0;
// 36.00 km/h = raw 3600 = 0x0E10, high byte first: 10 m/s.
inline constexpr std::initializer_list<std::uint8_t> kTenMetresPerSecond = {0x0E, 0x10};

inline can::OdometryDecoder shipped_decoder() {
  auto db = can::load_dbc(std::filesystem::path(::stac::testing::source_dir()) /
                          "config/can/vehicle.dbc");
  EXPECT_TRUE(db) << db.error().message;
  auto d =
      can::OdometryDecoder::create(*db, {"WheelSpeeds", "VehicleSpeed", "YawRate", "YawRate", 1.0});
  EXPECT_TRUE(d) << d.error().message;
  return std::move(d).value();
}

}  // namespace stac::testing

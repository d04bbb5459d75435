// Test helper: random Applanix messages, encoded with the library's encoders, and the list of
// what a parser should find in them.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "drivers/applanix/groups.hpp"

namespace stac::testing {

struct EncodedMessage {
  std::vector<std::uint8_t> bytes;
  std::uint16_t id = 0;
  bool is_group = true;
};

inline applanix::TimeDistance random_time(std::mt19937& rng) {
  std::uniform_real_distribution<double> sow(0.0, 604800.0);
  applanix::TimeDistance t;
  t.time1_s = sow(rng);
  t.time2_s = sow(rng);
  t.distance_tag_m = sow(rng) / 10.0;
  t.time_types = static_cast<std::uint8_t>((rng() % 3) | ((rng() % 4) << 4));
  t.distance_type = static_cast<std::uint8_t>(rng() % 3);
  return t;
}

inline applanix::Group1 random_group1(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto f = [&](double scale) { return static_cast<float>(u(rng) * scale); };
  applanix::Group1 g;
  g.latitude_deg = u(rng) * 90.0;
  g.longitude_deg = u(rng) * 180.0;
  g.altitude_m = u(rng) * 1000.0;
  g.north_velocity_mps = f(40);
  g.east_velocity_mps = f(40);
  g.down_velocity_mps = f(5);
  g.roll_deg = u(rng) * 180.0;
  g.pitch_deg = u(rng) * 90.0;
  g.heading_deg = (u(rng) + 1.0) * 180.0;
  g.wander_deg = u(rng) * 180.0;
  g.track_deg = f(180);
  g.speed_mps = f(40);
  g.rate_longitudinal_dps = f(30);
  g.rate_transverse_dps = f(30);
  g.rate_down_dps = f(30);
  g.accel_longitudinal_mps2 = f(10);
  g.accel_transverse_mps2 = f(10);
  g.accel_down_mps2 = f(10);
  g.alignment_status = static_cast<std::uint8_t>(rng() % 9);
  return g;
}

inline applanix::Group2 random_group2(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 5.0f);
  applanix::Group2 g;
  for (std::size_t i = 0; i < 3; ++i) {
    g.position_rms_m[i] = u(rng);
    g.velocity_rms_mps[i] = u(rng);
    g.attitude_rms_deg[i] = u(rng);
  }
  g.ellipse_major_m = u(rng);
  g.ellipse_minor_m = u(rng);
  g.ellipse_orientation_deg = u(rng) * 70.0f;
  return g;
}

inline applanix::Group3 random_group3(std::mt19937& rng, std::size_t channels) {
  std::uniform_real_distribution<float> u(0.0f, 90.0f);
  applanix::Group3 g;
  g.solution_status = static_cast<std::int8_t>(static_cast<int>(rng() % 9) - 1);
  g.sv_count = static_cast<std::uint8_t>(channels);
  g.channel_count = channels;
  for (std::size_t i = 0; i < channels; ++i) {
    g.channels[i] = {static_cast<std::uint16_t>(rng() % 200),
                     static_cast<std::uint16_t>(rng() % 16),
                     u(rng) * 4.0f,
                     u(rng),
                     u(rng) / 2.0f,
                     u(rng) / 2.0f};
  }
  g.hdop = u(rng) / 30.0f;
  g.vdop = u(rng) / 30.0f;
  g.dgps_latency_s = u(rng);
  g.dgps_reference_id = static_cast<std::uint16_t>(rng());
  g.gps_week = static_cast<std::uint32_t>(1000 + rng() % 2000);
  g.gps_utc_offset_s = 18.0;
  g.message_latency_s = u(rng) / 90.0f;
  g.geoid_separation_m = -u(rng);
  g.receiver_type = static_cast<std::uint16_t>(rng() % 30);
  g.status = static_cast<std::uint32_t>(rng());
  return g;
}

// One random message: Group 1, 2, 3, another group or a $MSG, chosen by `rng`.
inline EncodedMessage random_message(std::mt19937& rng) {
  EncodedMessage m;
  m.bytes.resize(applanix::kMaxMessageBytes);
  std::size_t n = 0;
  const applanix::TimeDistance t = random_time(rng);
  switch (rng() % 5) {
    case 0:
      m.id = 1;
      n = applanix::encode_group1(random_group1(rng), t, m.bytes);
      break;
    case 1:
      m.id = 2;
      n = applanix::encode_group2(random_group2(rng), t, m.bytes);
      break;
    case 2:
      m.id = 3;
      n = applanix::encode_group3(random_group3(rng, rng() % 24), t, m.bytes);
      break;
    case 3: {
      std::vector<std::uint8_t> data(rng() % 300);
      for (auto& b : data) b = static_cast<std::uint8_t>(rng());
      m.id = static_cast<std::uint16_t>(4 + rng() % 30000);
      n = applanix::encode_group(m.id, t, data, m.bytes);
      break;
    }
    default: {
      std::vector<std::uint8_t> body(rng() % 200);
      for (auto& b : body) b = static_cast<std::uint8_t>(rng());
      m.id = static_cast<std::uint16_t>(rng() % 100);
      m.is_group = false;
      n = applanix::encode_message(m.id, static_cast<std::uint16_t>(rng()), body, m.bytes);
      break;
    }
  }
  m.bytes.resize(n);
  return m;
}

}  // namespace stac::testing

#include "drivers/velodyne/decoder.hpp"

#include <algorithm>
#include <cmath>
#include <cctype>
#include <numbers>
#include <numeric>
#include <string>

namespace stac::velodyne {
namespace {

constexpr float kTwoPointXAt = 2.4f;     // m, where distance_x is measured
constexpr float kTwoPointYAt = 1.93f;    // m, where distance_y is measured
constexpr float kTwoPointFar = 25.04f;   // m, where dist_correction is measured
constexpr float kFocalScale = 13100.0f;  // cm, intensity formula constant

}  // namespace

std::optional<Model> parse_model(std::string_view text) noexcept {
  std::string s;
  for (char c : text) s.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  for (std::string_view prefix : {"HDL-64E ", "HDL-64E", "HDL64E", "64E_", "64E"}) {
    if (s.rfind(prefix, 0) == 0) {
      s.erase(0, prefix.size());
      break;
    }
  }
  if (s == "S2") return Model::kS2;
  if (s == "S2.1" || s == "S21") return Model::kS2_1;
  if (s == "S3") return Model::kS3;
  return std::nullopt;
}

PacketDecoder::PacketDecoder(const Calibration& calibration, const DecoderConfig& config)
    : traits_(&traits(config.model)),
      config_(config),
      resolution_m_(static_cast<float>(calibration.distance_resolution_m)),
      cos_table_(kRotationUnits),
      sin_table_(kRotationUnits) {
  for (int r = 0; r < kRotationUnits; ++r) {
    const double a = r * (std::numbers::pi / 18000.0);
    cos_table_[static_cast<std::size_t>(r)] = static_cast<float>(std::cos(a));
    sin_table_[static_cast<std::size_t>(r)] = static_cast<float>(std::sin(a));
  }
  // Ring = rank of the vertical correction, lowest beam first.
  std::array<int, kMaxLasers> order{};
  std::iota(order.begin(), order.end(), 0);
  const int n = calibration.num_lasers;
  std::stable_sort(order.begin(), order.begin() + n, [&](int a, int b) {
    return calibration.lasers[static_cast<std::size_t>(a)].vert_correction_rad <
           calibration.lasers[static_cast<std::size_t>(b)].vert_correction_rad;
  });
  for (int rank = 0; rank < kMaxLasers; ++rank) {
    const int id = order[static_cast<std::size_t>(rank)];
    const LaserCalibration& c = calibration.lasers[static_cast<std::size_t>(id)];
    LaserTable& t = lasers_[static_cast<std::size_t>(id)];
    t.cos_vert = static_cast<float>(std::cos(c.vert_correction_rad));
    t.sin_vert = static_cast<float>(std::sin(c.vert_correction_rad));
    t.cos_rot = static_cast<float>(std::cos(c.rot_correction_rad));
    t.sin_rot = static_cast<float>(std::sin(c.rot_correction_rad));
    t.dist = static_cast<float>(c.dist_correction_m);
    t.dist_x = static_cast<float>(c.dist_correction_x_m);
    t.dist_y = static_cast<float>(c.dist_correction_y_m);
    t.vert_offset = static_cast<float>(c.vert_offset_m);
    t.horiz_offset = static_cast<float>(c.horiz_offset_m);
    const float fd = static_cast<float>(c.focal_distance_m * (config.ros_intensity_units ? 1.0 : 100.0));
    const float f = 1.0f - fd / kFocalScale;
    t.focal_offset = 256.0f * f * f;
    t.focal_slope = static_cast<float>(c.focal_slope);
    t.min_intensity = static_cast<float>(c.min_intensity);
    t.max_intensity = static_cast<float>(c.max_intensity);
    t.two_pt = c.two_pt_correction_available;
    t.enabled = c.enabled && id < n;
    t.ring = static_cast<std::uint8_t>(rank);
  }
  for (int dual = 0; dual < 2; ++dual) {
    const int blocks_per_firing = dual ? 4 : 2;
    for (int b = 0; b < kBlocksPerPacket; ++b) {
      for (int j = 0; j < kLasersPerBlock; ++j) {
        const double us = traits_->firing_period_us * (b / blocks_per_firing) +
                          traits_->laser_group_us * (j / 4) +
                          traits_->laser_in_group_us[static_cast<std::size_t>(j % 4)];
        firing_ns_[static_cast<std::size_t>(dual)][static_cast<std::size_t>(b)]
                  [static_cast<std::size_t>(j)] = static_cast<std::int32_t>(std::lround(us * 1000.0));
      }
    }
  }
}

int PacketDecoder::decode_block(const RawBlock& block, int block_index, bool dual_return,
                                std::int64_t packet_offset_ns, Point* out) noexcept {
  if (block.rotation >= kRotationUnits) {  // the assembler drops such packets before this
    ++counters_.invalid_rotation;
    return 0;
  }
  const int bank_origin = block.bank == kLowerBank ? kLasersPerBlock : 0;
  const float cos_r = cos_table_[block.rotation];
  const float sin_r = sin_table_[block.rotation];
  const auto& firing = firing_ns_[dual_return ? 1 : 0][static_cast<std::size_t>(block_index)];
  const std::uint8_t return_type = static_cast<std::uint8_t>(
      dual_return && (block_index % 4) >= 2 ? ReturnType::kLast : ReturnType::kStrongest);
  int written = 0;
  for (int j = 0; j < kLasersPerBlock; ++j) {
    const RawReturn& ret = block.returns[j];
    const int laser = bank_origin + j;
    const LaserTable& c = lasers_[static_cast<std::size_t>(laser)];
    const std::uint16_t raw = ret.distance;
    if (raw == 0) {
      ++counters_.no_return;
      continue;
    }
    if (!c.enabled) {
      ++counters_.disabled;
      continue;
    }
    const float distance = static_cast<float>(raw) * resolution_m_ + c.dist;
    if (distance < config_.min_range_m || distance > config_.max_range_m) {
      ++counters_.out_of_range;
      continue;
    }
    // Azimuth with the laser's rotational correction: cos/sin(rotation - rot_correction).
    const float cos_a = cos_r * c.cos_rot + sin_r * c.sin_rot;
    const float sin_a = sin_r * c.cos_rot - cos_r * c.sin_rot;
    float corr_x = 0.0f;
    float corr_y = 0.0f;
    if (c.two_pt) {
      const float xy = distance * c.cos_vert - c.vert_offset * c.sin_vert;
      const float xx = std::fabs(xy * sin_a - c.horiz_offset * cos_a);
      const float yy = std::fabs(xy * cos_a + c.horiz_offset * sin_a);
      corr_x = (c.dist - c.dist_x) * (xx - kTwoPointXAt) / (kTwoPointFar - kTwoPointXAt) +
               c.dist_x - c.dist;
      corr_y = (c.dist - c.dist_y) * (yy - kTwoPointYAt) / (kTwoPointFar - kTwoPointYAt) +
               c.dist_y - c.dist;
      if (config_.gate_two_point_correction) {
        if (xx > kTwoPointFar) corr_x = 0.0f;
        if (yy > kTwoPointFar) corr_y = 0.0f;
      }
    }
    const float dx = distance + corr_x;
    const float dy = distance + corr_y;
    const float xy_x = dx * c.cos_vert - c.vert_offset * c.sin_vert;
    const float xy_y = dy * c.cos_vert - c.vert_offset * c.sin_vert;
    const float vx = xy_x * sin_a - c.horiz_offset * cos_a;  // Velodyne frame: x right
    const float vy = xy_y * cos_a + c.horiz_offset * sin_a;  // y forward
    const float vz = dy * c.sin_vert + c.vert_offset * c.cos_vert;

    const float r = 1.0f - static_cast<float>(raw) / 65535.0f;
    float intensity = static_cast<float>(ret.intensity) +
                      c.focal_slope * std::fabs(c.focal_offset - 256.0f * r * r);
    intensity = std::clamp(intensity, c.min_intensity, c.max_intensity);

    Point& p = out[written++];
    p.x = vy;  // forward
    p.y = -vx; // left
    p.z = vz;
    p.intensity = intensity;
    p.distance_m = distance;
    p.time_offset_ns = static_cast<std::int32_t>(packet_offset_ns + firing[static_cast<std::size_t>(j)]);
    p.azimuth = block.rotation;
    p.laser = static_cast<std::uint8_t>(laser);
    p.ring = c.ring;
    p.return_type = return_type;
  }
  return written;
}

}  // namespace stac::velodyne

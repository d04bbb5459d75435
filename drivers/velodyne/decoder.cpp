#include "drivers/velodyne/decoder.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
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
  std::string s;  // upper case, without spaces, dashes and underscores
  for (char c : text) {
    if (c == ' ' || c == '-' || c == '_') continue;
    s.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  }
  for (std::string_view prefix : {"HDL64E", "64E"}) {
    if (s.rfind(prefix, 0) == 0) {
      s.erase(0, prefix.size());
      break;
    }
  }
  if (s == "S2") return Model::kS2;
  if (s == "S2.1" || s == "S21") return Model::kS2_1;
  if (s == "S3") return Model::kS3;
  if (s == "HDL32E" || s == "HDL32" || s == "32E") return Model::kHdl32e;
  if (s == "VLP16" || s == "PUCK") return Model::kVlp16;
  if (s == "PUCKLITE" || s == "VLP16LITE") return Model::kPuckLite;
  if (s == "PUCKHIRES" || s == "VLP16HIRES") return Model::kPuckHiRes;
  if (s == "VLP32C" || s == "VLP32" || s == "ULTRAPUCK") return Model::kVlp32c;
  return std::nullopt;
}

std::string_view model_names() noexcept {
  return "S2, S2.1, S3 (HDL-64E), HDL-32E, VLP-16, Puck LITE, Puck Hi-Res or VLP-32C";
}

PacketIdentity identify_packet(std::span<const std::uint8_t> payload) noexcept {
  PacketIdentity id;
  const RawPacket* packet = as_packet(payload);
  if (packet == nullptr) return id;
  bool all_upper = true;
  for (const RawBlock& b : packet->blocks) {
    if (b.bank == kLowerBank) {
      id.kind = PacketIdentity::Kind::kHdl64;
      return id;
    }
    all_upper = all_upper && b.bank == kUpperBank;
  }
  const std::uint8_t mode = packet->trailer[4], product = packet->trailer[5];
  if (!all_upper || mode < kReturnStrongest || mode > kReturnDual) return id;
  id.kind = PacketIdentity::Kind::kFactory;
  id.return_mode = mode;
  id.product_id = product;
  for (Model m : kAllModels) {
    if (traits(m).product_id != 0 && traits(m).product_id == product) {  // 0: an HDL-64E's
      id.model = m;
      break;
    }
  }
  return id;
}

bool identity_matches(const PacketIdentity& id, Model m) noexcept {
  if (id.kind == PacketIdentity::Kind::kUnknown) return true;  // the bytes name no model
  if (is_hdl64(m)) return id.kind == PacketIdentity::Kind::kHdl64;
  return id.kind == PacketIdentity::Kind::kFactory && id.product_id == traits(m).product_id;
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
  const int n = std::min(calibration.num_lasers, traits_->lasers);
  std::stable_sort(order.begin(), order.begin() + n, [&](int a, int b) {
    return calibration.lasers[static_cast<std::size_t>(a)].vert_correction_rad <
           calibration.lasers[static_cast<std::size_t>(b)].vert_correction_rad;
  });
  auto by_laser = std::make_unique<LaserTables>();
  for (int rank = 0; rank < kMaxLasers; ++rank) {
    const int id = order[static_cast<std::size_t>(rank)];
    const LaserCalibration& c = calibration.lasers[static_cast<std::size_t>(id)];
    LaserTables& t = *by_laser;
    t.cos_vert[id] = static_cast<float>(std::cos(c.vert_correction_rad));
    t.sin_vert[id] = static_cast<float>(std::sin(c.vert_correction_rad));
    t.cos_rot[id] = static_cast<float>(std::cos(c.rot_correction_rad));
    t.sin_rot[id] = static_cast<float>(std::sin(c.rot_correction_rad));
    t.dist[id] = static_cast<float>(c.dist_correction_m);
    t.dist_x[id] = static_cast<float>(c.dist_correction_x_m);
    t.dist_y[id] = static_cast<float>(c.dist_correction_y_m);
    t.vert_offset[id] = static_cast<float>(c.vert_offset_m);
    t.horiz_offset[id] = static_cast<float>(c.horiz_offset_m);
    const float fd =
        static_cast<float>(c.focal_distance_m * (config.ros_intensity_units ? 1.0 : 100.0));
    const float f = 1.0f - fd / kFocalScale;
    t.focal_offset[id] = 256.0f * f * f;
    t.focal_slope[id] = static_cast<float>(c.focal_slope);
    t.min_intensity[id] = static_cast<float>(c.min_intensity);
    t.max_intensity[id] = static_cast<float>(c.max_intensity);
    t.two_pt[id] = c.two_pt_correction_available ? 1.0f : 0.0f;
    t.enabled[id] = c.enabled && id < n;
    t.ring[id] = static_cast<std::uint8_t>(rank);
    t.laser[id] = static_cast<std::uint8_t>(id);
    ring_by_laser_[static_cast<std::size_t>(id)] = static_cast<std::uint8_t>(rank);
  }
  if (traits_->layout == Layout::kBankPairs) {
    lasers_ = *by_laser;
  } else {
    for (int slot = 0; slot < kMaxLasers; ++slot) {
      const int from = slot < kLasersPerBlock ? slot % traits_->lasers : 0;
      LaserTables& t = lasers_;
      const LaserTables& f = *by_laser;
      t.cos_vert[slot] = f.cos_vert[from], t.sin_vert[slot] = f.sin_vert[from];
      t.cos_rot[slot] = f.cos_rot[from], t.sin_rot[slot] = f.sin_rot[from];
      t.dist[slot] = f.dist[from], t.dist_x[slot] = f.dist_x[from], t.dist_y[slot] = f.dist_y[from];
      t.vert_offset[slot] = f.vert_offset[from], t.horiz_offset[slot] = f.horiz_offset[from];
      t.two_pt[slot] = f.two_pt[from];
      t.focal_offset[slot] = f.focal_offset[from], t.focal_slope[slot] = f.focal_slope[from];
      t.min_intensity[slot] = f.min_intensity[from], t.max_intensity[slot] = f.max_intensity[from];
      t.enabled[slot] = f.enabled[from] && slot < kLasersPerBlock;
      t.ring[slot] = f.ring[from];
      t.laser[slot] = f.laser[from];
    }
  }
  for (int dual = 0; dual < 2; ++dual) {
    for (int b = 0; b < kBlocksPerPacket; ++b) {
      for (int j = 0; j < kLasersPerBlock; ++j) {
        const auto d = static_cast<std::size_t>(dual);
        const auto bi = static_cast<std::size_t>(b), ji = static_cast<std::size_t>(j);
        firing_ns_[d][bi][ji] = static_cast<std::int32_t>(
            std::lround(firing_time_us(*traits_, b, j, dual != 0) * 1000.0));
        fraction_[d][bi][ji] = static_cast<float>(azimuth_fraction_of(*traits_, j));
        interpolates_ = interpolates_ || fraction_[d][bi][ji] != 0.0f;
      }
    }
  }
}

ReturnType PacketDecoder::return_type(int block_index, bool dual_return) const noexcept {
  if (!dual_return) return ReturnType::kStrongest;
  // HDL-64E: [upper, lower] strongest then [upper, lower] last; the others: a pair of blocks,
  // the last return first (docs/velodyne.md).
  if (traits_->layout == Layout::kBankPairs)
    return block_index % 4 >= 2 ? ReturnType::kLast : ReturnType::kStrongest;
  return block_index % 2 == 0 ? ReturnType::kLast : ReturnType::kStrongest;
}

int PacketDecoder::decode_block(const RawBlock& block, int block_index, bool dual_return,
                                std::int64_t packet_offset_ns, Point* out,
                                int azimuth_step) noexcept {
  if (block.rotation >= kRotationUnits) {  // the assembler drops such packets before this
    ++counters_.invalid_rotation;
    return 0;
  }
  // Slot of channel 0 in the tables: the bank for an HDL-64E; the channels of the others.
  const int base =
      traits_->layout == Layout::kBankPairs && block.bank == kLowerBank ? kLasersPerBlock : 0;
  // The rotation of every channel: the block's, or (VLP-16) interpolated by its firing time.
  alignas(64) std::uint16_t rotation[kLasersPerBlock];
  alignas(64) float cos_r[kLasersPerBlock], sin_r[kLasersPerBlock];
  if (interpolates_ && azimuth_step != 0) {
    const auto& fraction = fraction_[dual_return ? 1 : 0][static_cast<std::size_t>(block_index)];
    for (int j = 0; j < kLasersPerBlock; ++j) {
      rotation[j] = interpolated_rotation(block.rotation, azimuth_step,
                                          fraction[static_cast<std::size_t>(j)]);
      cos_r[j] = cos_table_[rotation[j]];
      sin_r[j] = sin_table_[rotation[j]];
    }
  } else {
    const float c = cos_table_[block.rotation], s = sin_table_[block.rotation];
    for (int j = 0; j < kLasersPerBlock; ++j) {
      rotation[j] = block.rotation;
      cos_r[j] = c;
      sin_r[j] = s;
    }
  }
  constexpr float kInvX = 1.0f / (kTwoPointFar - kTwoPointXAt);
  constexpr float kInvY = 1.0f / (kTwoPointFar - kTwoPointYAt);
  const LaserTables& t = lasers_;

  // Pass 1, branch-free loops over all 32 returns (vectorised): the ROS math of REFERENCE §1.
  alignas(64) float raw[kLasersPerBlock], raw_intensity[kLasersPerBlock];
  for (int j = 0; j < kLasersPerBlock; ++j) {
    raw[j] = static_cast<float>(block.returns[j].distance);
    raw_intensity[j] = static_cast<float>(block.returns[j].intensity);
  }
  alignas(64) float distance[kLasersPerBlock], cos_a[kLasersPerBlock], sin_a[kLasersPerBlock];
  alignas(64) float xx[kLasersPerBlock], yy[kLasersPerBlock];
  alignas(64) float corr_x[kLasersPerBlock], corr_y[kLasersPerBlock];
  for (int j = 0; j < kLasersPerBlock; ++j) {
    const int l = base + j;
    distance[j] = raw[j] * resolution_m_ + t.dist[l];
    // Azimuth with the laser's rotational correction: cos/sin(rotation - rot_correction).
    cos_a[j] = cos_r[j] * t.cos_rot[l] + sin_r[j] * t.sin_rot[l];
    sin_a[j] = sin_r[j] * t.cos_rot[l] - cos_r[j] * t.sin_rot[l];
    const float xy = distance[j] * t.cos_vert[l] - t.vert_offset[l] * t.sin_vert[l];
    xx[j] = std::fabs(xy * sin_a[j] - t.horiz_offset[l] * cos_a[j]);
    yy[j] = std::fabs(xy * cos_a[j] + t.horiz_offset[l] * sin_a[j]);
    corr_x[j] =
        ((t.dist[l] - t.dist_x[l]) * (xx[j] - kTwoPointXAt) * kInvX + t.dist_x[l] - t.dist[l]) *
        t.two_pt[l];
    corr_y[j] =
        ((t.dist[l] - t.dist_y[l]) * (yy[j] - kTwoPointYAt) * kInvY + t.dist_y[l] - t.dist[l]) *
        t.two_pt[l];
  }
  if (config_.gate_two_point_correction) {
    for (int j = 0; j < kLasersPerBlock; ++j) {
      corr_x[j] = xx[j] > kTwoPointFar ? 0.0f : corr_x[j];
      corr_y[j] = yy[j] > kTwoPointFar ? 0.0f : corr_y[j];
    }
  }
  alignas(64) float px[kLasersPerBlock], py[kLasersPerBlock], pz[kLasersPerBlock];
  alignas(64) float pi[kLasersPerBlock];
  for (int j = 0; j < kLasersPerBlock; ++j) {
    const int l = base + j;
    const float cv = t.cos_vert[l], sv = t.sin_vert[l];
    const float vo = t.vert_offset[l], ho = t.horiz_offset[l];
    const float xy_x = (distance[j] + corr_x[j]) * cv - vo * sv;
    const float xy_y = (distance[j] + corr_y[j]) * cv - vo * sv;
    const float vx = xy_x * sin_a[j] - ho * cos_a[j];  // Velodyne frame: x right
    const float vy = xy_y * cos_a[j] + ho * sin_a[j];  // y forward
    px[j] = vy;                                        // sensor frame: x forward
    py[j] = -vx;                                       // y left
    pz[j] = (distance[j] + corr_y[j]) * sv + vo * cv;
    const float r = 1.0f - raw[j] * (1.0f / 65535.0f);
    const float intensity =
        raw_intensity[j] + t.focal_slope[l] * std::fabs(t.focal_offset[l] - 256.0f * r * r);
    pi[j] = std::min(std::max(intensity, t.min_intensity[l]), t.max_intensity[l]);
  }

  // Pass 2: keep the valid returns, counting the others by cause.
  const auto& firing = firing_ns_[dual_return ? 1 : 0][static_cast<std::size_t>(block_index)];
  const auto type = static_cast<std::uint8_t>(return_type(block_index, dual_return));
  int written = 0;
  for (int j = 0; j < kLasersPerBlock; ++j) {
    const int l = base + j;
    if (block.returns[j].distance == 0) {
      ++counters_.no_return;
      continue;
    }
    if (!t.enabled[l]) {
      ++counters_.disabled;
      continue;
    }
    if (distance[j] < config_.min_range_m || distance[j] > config_.max_range_m) {
      ++counters_.out_of_range;
      continue;
    }
    Point& p = out[written++];
    p.x = px[j];
    p.y = py[j];
    p.z = pz[j];
    p.intensity = pi[j];
    p.distance_m = distance[j];
    p.time_offset_ns =
        static_cast<std::int32_t>(packet_offset_ns + firing[static_cast<std::size_t>(j)]);
    p.azimuth = rotation[j];
    p.laser = t.laser[l];
    p.ring = t.ring[l];
    p.return_type = type;
  }
  return written;
}

}  // namespace stac::velodyne

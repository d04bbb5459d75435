#include "sim/lidar.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "drivers/velodyne/beam.hpp"
#include "drivers/velodyne/packet_builder.hpp"

namespace stac::sim {
namespace {

constexpr double kWindowS = 0.02;  // candidate bins are rebuilt every 20 ms of sensor time

std::uint64_t mix(std::uint64_t x) {  // splitmix64
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}
double uniform(std::uint64_t h) {
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}
double normal(std::uint64_t h) {  // Box-Muller from two hashes
  const double u1 = std::max(uniform(mix(h)), 1e-300), u2 = uniform(mix(h ^ 0xABCDEF));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

// Sensor frame -> world: rotation by roll, pitch, yaw (Z-Y-X), then translation.
struct Frame {
  double r[3][3];
  V3 t;
  V3 apply(V3 p) const { return rotate(p) + t; }
  V3 rotate(V3 p) const {
    return {r[0][0] * p.x + r[0][1] * p.y + r[0][2] * p.z,
            r[1][0] * p.x + r[1][1] * p.y + r[1][2] * p.z,
            r[2][0] * p.x + r[2][1] * p.y + r[2][2] * p.z};
  }
};

Frame sensor_frame(const EgoState& e, double mount_height) {
  const double cr = std::cos(e.roll), sr = std::sin(e.roll), cp = std::cos(e.pitch),
               sp = std::sin(e.pitch), cy = std::cos(e.yaw), sy = std::sin(e.yaw);
  Frame f{};
  f.r[0][0] = cy * cp;
  f.r[0][1] = cy * sp * sr - sy * cr;
  f.r[0][2] = cy * sp * cr + sy * sr;
  f.r[1][0] = sy * cp;
  f.r[1][1] = sy * sp * sr + cy * cr;
  f.r[1][2] = sy * sp * cr - cy * sr;
  f.r[2][0] = -sp;
  f.r[2][1] = cp * sr;
  f.r[2][2] = cp * cr;
  f.t = V3{e.x, e.y, e.z} + f.rotate(V3{0, 0, mount_height});
  return f;
}

// Intensity of a return as the decoder reports it after its focal correction (0..255; see
// docs/simulator.md "Intensity"): brighter with reflectivity (saturating: rho / (rho + 0.17),
// fitted to KITTI's histogram), mildly with incidence, falling off slowly with range, with
// multiplicative noise; a part of the returns off dark surfaces at a slant come back at 0 (-1 here:
// a raw byte of 0).
double intensity_of(double reflectivity, double incidence, double range, std::uint64_t h) {
  const double rho = std::clamp(reflectivity, 0.0, 1.0);
  const double p_zero = 0.03 + 0.2 * (1.0 - incidence) * std::max(0.0, 0.45 - rho);
  if (uniform(mix(h ^ 0x31)) < p_zero) return -1.0;
  return 255.0 * 0.78 * rho / (rho + 0.17) * (0.7 + 0.3 * incidence) / (1.0 + range / 90.0) *
         std::exp(0.18 * normal(mix(h ^ 0x33)));
}

// The raw byte the sensor sends for a corrected intensity: the decoder adds
// focal_slope * |256 (1 - focal_distance / 13100 cm)^2 - 256 (1 - raw_distance / 65535)^2|
// (drivers/velodyne/decoder.cpp), so the sensor's raw value is the corrected one minus that.
std::uint8_t raw_intensity(double corrected, const velodyne::LaserCalibration& l,
                           double raw_distance) {
  if (corrected < 0.0) return 0;
  const double f = 1.0 - l.focal_distance_m * 100.0 / 13100.0;
  const double r = 1.0 - raw_distance / 65535.0;
  const double correction = l.focal_slope * std::abs(256.0 * f * f - 256.0 * r * r);
  return static_cast<std::uint8_t>(std::clamp(std::lround(corrected - correction), 0L, 255L));
}

}  // namespace

bool LidarSim::hits_body(const velodyne::BeamLine& line) const {
  const EgoBody& b = config_.body;
  if (!b.enabled || line.direction[2] >= 0.0) return false;
  const V3 o{line.origin[0], line.origin[1], line.origin[2]};
  V3 d{line.direction[0], line.direction[1], line.direction[2]};
  d = d * (1.0 / norm(d));
  const Ray r{o, d};
  const double ground = -config_.mount_height_m;  // ego frame z = 0, in the sensor frame
  if (hit_box(r, {-b.length_m / 2, -b.width_m / 2, ground + b.bottom_m},
              {b.length_m / 2, b.width_m / 2, ground + b.bonnet_height_m})
          .t < kNoHit) {
    return true;
  }
  return hit_box(r, {-b.roof_back_m, -b.roof_half_width_m, ground + b.bonnet_height_m - 0.01},
                 {b.roof_front_m, b.roof_half_width_m, -b.roof_below_sensor_m})
             .t < kNoHit;
}

LidarSim::LidarSim(const velodyne::Calibration& calibration, const LidarConfig& config,
                   const World& world, EgoFn ego)
    : calibration_(calibration),
      beams_(calibration, false),
      config_(config),
      world_(world),
      ego_(std::move(ego)) {
  const velodyne::ModelTraits& m = velodyne::traits(config.model);
  for (int b = 0; b < 12; ++b) {
    for (int j = 0; j < 32; ++j) {
      firing_offset_s_[static_cast<std::size_t>(b)][static_cast<std::size_t>(j)] =
          1e-6 * velodyne::firing_time_us(m, b, j, config.dual_return);
    }
  }
}

double LidarSim::packets_per_second() const noexcept {
  const velodyne::ModelTraits& m = velodyne::traits(config_.model);
  return config_.dual_return ? m.packets_per_second_dual : m.packets_per_second_single;
}

std::uint16_t LidarSim::rotation_at(double t) const noexcept {
  const double deg = std::fmod(config_.start_azimuth_deg + config_.rpm * 6.0 * t, 360.0);
  return static_cast<std::uint16_t>(std::lround(deg * 100.0) % 36000);
}

void LidarSim::refresh_candidates(double t) {
  window_start_ = t;
  window_end_ = t + kWindowS;
  for (auto& b : bins_) b.clear();
  const double tm = t + kWindowS / 2;
  const EgoState e = ego_(tm);
  // The sensor moves during the window, and beams leave a few centimetres off its axis.
  const double ego_travel = std::abs(e.speed) * kWindowS + 0.1;
  for (std::size_t i = 0; i < world_.actors().size(); ++i) {
    const Pose p = world_.actor_pose(i, tm);
    const V3 v = world_.actors()[i].path.velocity_at(tm);
    const double r = world_.actor_radius(i) + std::hypot(v.x, v.y) * kWindowS + ego_travel;
    const double dx = p.x - e.x, dy = p.y - e.y;
    const double dist = std::hypot(dx, dy);
    if (dist - r > config_.max_range_m + 10.0) continue;
    if (dist <= r + 1.0) {  // around the sensor: every direction
      for (auto& b : bins_) b.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
    const double centre = std::atan2(dy, dx) * 180.0 / std::numbers::pi;
    const double half = std::asin(std::min(1.0, r / dist)) * 180.0 / std::numbers::pi + 0.5;
    for (int d = static_cast<int>(std::floor(centre - half));
         d <= static_cast<int>(std::ceil(centre + half)); ++d) {
      bins_[static_cast<std::size_t>(((d % 360) + 360) % 360)].push_back(
          static_cast<std::uint32_t>(i));
    }
  }
}

// What the firings of one packet share.
struct LidarSim::PacketContext {
  std::uint32_t k;  // the packet
  double t0;        // its first firing (s)
  bool dual, banks;
  int per_firing;  // blocks per firing
  const velodyne::ModelTraits& model;
  velodyne::PacketBuilder& builder;
  const std::function<void(const BeamRecord&)>& record;
};

// One beam: a laser of a firing, the blocks it is written to, and the ego about it.
struct LidarSim::Beam {
  int strongest_block = 0, last_block = 0;
  int j = 0;  // its channel within the block
  int laser = 0;
  std::uint16_t rotation = 0;  // 0.01 deg
  double tf = 0.0;             // the firing's time (s): the actors are cast where they are then
  std::uint64_t h = 0;         // the hash its random draws come from
  Frame f;                     // sensor -> world as the beam leaves
};

// An echo of a beam, traced along the decoder's beam line.
struct LidarSim::Echo {
  WorldHit hit;
  double d = 0.0;
  velodyne::Vec3 sensor_hit{};
  V3 origin, dir;
  bool through = false;  // went through foliage
};

void LidarSim::make_packet(std::uint32_t k, std::array<std::uint8_t, velodyne::kPacketSize>& bytes,
                           double& first_firing_s,
                           const std::function<void(const BeamRecord&)>& record) {
  using namespace velodyne;
  const double t0 = k / packets_per_second();
  first_firing_s = t0;
  PacketBuilder builder;
  const bool dual = config_.dual_return;
  const ModelTraits& model = traits(config_.model);
  const bool banks = model.layout == Layout::kBankPairs;
  const int per_firing = (banks ? 2 : 1) * (dual ? 2 : 1);
  const int firings = kBlocksPerPacket / per_firing;
  const PacketContext p{k, t0, dual, banks, per_firing, model, builder, record};
  std::array<std::uint16_t, kBlocksPerPacket> firing_rotation{};
  std::array<int, kBlocksPerPacket> azimuth_step{};
  firing_rotations(p, firings, firing_rotation, azimuth_step);
  for (int firing = 0; firing < firings; ++firing) {
    const auto fi = static_cast<std::size_t>(firing);
    fire(p, firing, firing_rotation[fi], azimuth_step[fi]);
  }
  std::copy(builder.bytes().begin(), builder.bytes().end(), bytes.begin());
}

// Every firing's rotation and the azimuth step to the next, as the scan assembler takes them
// from the packet (the last firing keeps the step before it).
void LidarSim::firing_rotations(const PacketContext& p, int firings,
                                std::array<std::uint16_t, velodyne::kBlocksPerPacket>& rotation,
                                std::array<int, velodyne::kBlocksPerPacket>& step) const noexcept {
  for (int f = 0; f < firings; ++f) {
    rotation[static_cast<std::size_t>(f)] = rotation_at(
        p.t0 +
        firing_offset_s_[static_cast<std::size_t>(f) * static_cast<std::size_t>(p.per_firing)][0]);
  }
  for (int f = 0; f < firings; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    if (f + 1 < firings) {
      int d = (rotation[fi + 1] - rotation[fi] + 36000) % 36000;
      if (d > 18000) d -= 36000;
      step[fi] = d;
    } else {
      step[fi] = f > 0 ? step[fi - 1] : 0;
    }
  }
}

// One firing: its blocks' headers and every beam of it.
void LidarSim::fire(const PacketContext& p, int firing, std::uint16_t block_rotation,
                    int azimuth_step) {
  using namespace velodyne;
  const int first_block = firing * p.per_firing;
  const double tf = p.t0 + firing_offset_s_[static_cast<std::size_t>(first_block)][0];
  // The ego at the firing and 50 us later (or the firing's end): every beam of the firing
  // leaves in between, its origin interpolated linearly (the attitude changes by < 1e-4 deg).
  const double span =
      p.banks ? 50e-6
              : std::max(
                    50e-6,
                    firing_offset_s_[static_cast<std::size_t>(first_block + p.per_firing - 1)][31] -
                        firing_offset_s_[static_cast<std::size_t>(first_block)][0] + 1e-6);
  const Frame f0 = sensor_frame(ego_(tf), config_.mount_height_m);
  const Frame f1 = sensor_frame(ego_(tf + span), config_.mount_height_m);
  // The blocks with the strongest (or only) return, and in dual return the block of the
  // last return beside each: HDL-64E [upper, lower] then [upper, lower] again; the others
  // [last, strongest] (PacketDecoder::return_type).
  const int primaries = p.banks ? 2 : 1;
  for (int bank = 0; bank < primaries; ++bank) {
    const int strongest_block = p.banks ? first_block + bank : first_block + (p.dual ? 1 : 0);
    const int last_block = p.banks ? strongest_block + 2 : first_block;
    const std::uint16_t bank_id = bank == 0 ? kUpperBank : kLowerBank;
    p.builder.set_block(strongest_block, bank_id, block_rotation);
    if (p.dual) p.builder.set_block(last_block, bank_id, block_rotation);
    for (int j = 0; j < 32; ++j) {
      const int laser = p.banks ? bank * 32 + j : j % p.model.lasers;
      const std::uint16_t rotation = interpolated_rotation(
          block_rotation, azimuth_step, static_cast<float>(azimuth_fraction_of(p.model, j)));
      const double t =
          p.t0 +
          firing_offset_s_[static_cast<std::size_t>(strongest_block)][static_cast<std::size_t>(j)];
      if (t >= window_end_ || t < window_start_) refresh_candidates(t);
      const std::uint64_t h =
          mix(config_.seed ^
              mix((static_cast<std::uint64_t>(p.k) << 16) |
                  static_cast<std::uint64_t>(strongest_block * 64 + (p.banks ? laser : j))));
      Frame f = f0;
      f.t = f0.t + (f1.t - f0.t) * ((t - tf) / span);
      BeamRecord rec{p.k,
                     static_cast<std::uint8_t>(strongest_block),
                     static_cast<std::uint8_t>(laser),
                     rotation,
                     static_cast<std::uint8_t>(j),
                     block_rotation,
                     -2,
                     t,
                     {0, 0, 0},
                     {0, 0, 0},
                     false};
      const Beam b{strongest_block, last_block, j, laser, rotation, tf, h, f};
      if (!hits_body(beams_.line(laser, rotation, 1.0))) {  // the ego's own car: no return
        cast(p, b, rec);
      }
      if (p.record) p.record(rec);
    }
  }
}

// Cast along the decoder's beam line; re-linearise at the solution until exact.
// `through`: 0 stop at foliage, 1 go through it, 2 go through at random (45 %).
// `yaw_offset`: a ray beside the beam's axis (rad about the world vertical), for the edge
// of the beam's footprint.
LidarSim::Echo LidarSim::trace(const Beam& b, int through, double yaw_offset) {
  Echo e;
  double d = 20.0;
  for (int it = 0; it < 4; ++it) {
    const velodyne::BeamLine line = beams_.line(b.laser, b.rotation, d);
    const V3 o{line.origin[0], line.origin[1], line.origin[2]};
    const V3 dir{line.direction[0], line.direction[1], line.direction[2]};
    const double line_scale = norm(dir);
    const V3 ow = b.f.apply(o);
    V3 uw = b.f.rotate(dir * (1.0 / line_scale));
    if (yaw_offset != 0.0) {
      const double c = std::cos(yaw_offset), sn = std::sin(yaw_offset);
      uw = V3{c * uw.x - sn * uw.y, sn * uw.x + c * uw.y, uw.z};
    }
    e.origin = ow;
    e.dir = uw;
    const double az = std::atan2(uw.y, uw.x) * 180.0 / std::numbers::pi;
    const auto bin =
        static_cast<std::size_t>(((static_cast<int>(std::floor(az)) % 360) + 360) % 360);
    e.hit = world_.cast(Ray{ow, uw}, b.tf, bins_[bin], poses_);
    if (e.hit.t == kNoHit) break;
    const bool pass = through == 1 || (through == 2 && uniform(mix(b.h ^ 0x77)) < 0.45);
    e.through = false;
    if (e.hit.translucent && pass) {
      // Foliage: a part of the beam goes through to what lies behind.
      const double step = e.hit.t + 0.6 + 0.6 * uniform(mix(b.h ^ 0x78));
      const WorldHit behind = world_.cast(Ray{ow + uw * step, uw}, b.tf, bins_[bin], poses_);
      if (behind.t < kNoHit) {
        e.hit = behind;
        e.hit.t += step;
        e.through = true;
      }
    }
    const double d_new = e.hit.t / line_scale;
    const velodyne::Vec3 exact = beams_.point(b.laser, b.rotation, d_new);
    const V3 on_line = o + dir * d_new;
    e.sensor_hit = exact;
    const double err = norm(V3{exact[0], exact[1], exact[2]} - on_line);
    d = d_new;
    e.d = d;
    if (err < 1e-5 || yaw_offset != 0.0) break;
  }
  return e;
}

// The beam's main echo into the record and, unless lost, its return(s) into the packet.
void LidarSim::cast(const PacketContext& p, const Beam& b, BeamRecord& rec) {
  const Echo main = trace(b, 2, 0.0);
  const WorldHit& hit = main.hit;
  if (!(hit.t < kNoHit)) return;
  const velodyne::LaserCalibration& l = calibration_.lasers[static_cast<std::size_t>(b.laser)];
  rec.actor = hit.actor;
  for (int i = 0; i < 3; ++i) rec.sensor_xyz[i] = main.sensor_hit[static_cast<std::size_t>(i)];
  const V3 w = b.f.apply(V3{main.sensor_hit[0], main.sensor_hit[1], main.sensor_hit[2]});
  rec.world_xyz[0] = w.x;
  rec.world_xyz[1] = w.y;
  rec.world_xyz[2] = w.z;
  // Returns: lost when too far for the target's brightness, grazing, or at random.
  const double range = hit.t;
  const double incidence = std::abs(dot(hit.normal, main.dir));
  const double reach = config_.max_range_m * std::sqrt(std::clamp(hit.reflectivity, 0.02, 1.0));
  const bool lost = range > reach || range < 0.5 || incidence < 0.06 ||
                    uniform(mix(b.h ^ 0x99)) < config_.dropout;
  if (lost) return;
  const double noisy = main.d + config_.range_noise_m * normal(mix(b.h ^ 0x55));
  const double raw = std::round((noisy - l.dist_correction_m) / calibration_.distance_resolution_m);
  if (!(raw >= 1.0 && raw <= 65535.0)) return;
  const std::uint8_t intensity =
      raw_intensity(intensity_of(hit.reflectivity, incidence, range, b.h), l, raw);
  p.builder.set_return(b.strongest_block, b.j, static_cast<std::uint16_t>(raw), intensity);
  rec.returned = true;
  if (p.dual) cast_second(p, b, main, raw, intensity, rec);
}

// Dual return: the other echo where there is one (the foliage and what lies behind it, or the
// far side of an edge the beam's footprint straddles), at most as bright as the main one; else
// the same return in both blocks (one echo only).
void LidarSim::cast_second(const PacketContext& p, const Beam& b, const Echo& main, double raw,
                           std::uint8_t intensity, BeamRecord& rec) {
  const velodyne::LaserCalibration& l = calibration_.lasers[static_cast<std::size_t>(b.laser)];
  const WorldHit& hit = main.hit;
  std::uint16_t raw2 = static_cast<std::uint16_t>(raw);
  std::uint8_t intensity2 = intensity;
  Echo other;
  if (main.through) {
    other = trace(b, 0, 0.0);
  } else if (hit.translucent) {
    other = trace(b, 1, 0.0);
    if (!other.through) other.hit.t = kNoHit;
  } else {
    other = trace(b, 0, uniform(mix(b.h ^ 0x44)) < 0.5 ? 1.0e-3 : -1.0e-3);
    if (std::abs(other.hit.t - hit.t) < 1.0) other.hit.t = kNoHit;
  }
  if (other.hit.t < kNoHit && other.hit.t > 0.5 &&
      other.hit.t <
          config_.max_range_m * std::sqrt(std::clamp(other.hit.reflectivity, 0.02, 1.0))) {
    const double noisy2 = other.d + config_.range_noise_m * normal(mix(b.h ^ 0x56));
    const double r2 =
        std::round((noisy2 - l.dist_correction_m) / calibration_.distance_resolution_m);
    if (r2 >= 1.0 && r2 <= 65535.0) {
      raw2 = static_cast<std::uint16_t>(r2);
      const double inc2 = std::abs(dot(other.hit.normal, other.dir));
      const double full = intensity_of(other.hit.reflectivity, inc2, other.hit.t, b.h ^ 0x5A5A);
      intensity2 = std::min(raw_intensity(0.5 * full, l, r2), intensity);
    }
  }
  // The manuals' dual mode: the last block holds the farthest echo; the strongest
  // block the strongest one, or the second strongest when that is the last. With
  // two echoes the nearer one is in the strongest block either way (foliage before
  // a brighter wall: the foliage there, the wall as the last return).
  if (raw2 < static_cast<std::uint16_t>(raw)) {
    p.builder.set_return(b.strongest_block, b.j, raw2, intensity2);
    p.builder.set_return(b.last_block, b.j, static_cast<std::uint16_t>(raw), intensity);
    rec.block = static_cast<std::uint8_t>(b.last_block);  // where the main echo went
  } else {
    p.builder.set_return(b.last_block, b.j, raw2, intensity2);
  }
}

}  // namespace stac::sim

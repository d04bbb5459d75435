#include "drivers/velodyne/scan_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace stac::velodyne {
namespace {

constexpr int kHalfTurn = kRotationUnits / 2;
constexpr double kGapFactor = 1.5;  // an azimuth step this many times the usual one is a gap
// Between two blocks of one packet the rotation advances by at most kMaxBlockStep (0.01 deg:
// 3 deg, ten times a firing's step at 1200 rpm) and goes back by at most kMaxBlockBack (jitter).
constexpr int kMaxBlockStep = 300, kMaxBlockBack = 5;
constexpr std::size_t kPointsPerPacket =
    static_cast<std::size_t>(kBlocksPerPacket) * static_cast<std::size_t>(kLasersPerBlock);

int forward(int from, int to) noexcept {
  return (to - from + kRotationUnits) % kRotationUnits;
}

std::uint64_t payload_hash(std::span<const std::uint8_t> payload) noexcept {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  std::size_t i = 0;
  for (; i + 8 <= payload.size(); i += 8) {
    std::uint64_t w;
    std::memcpy(&w, payload.data() + i, 8);
    h = (h ^ w) * 0x9E3779B97F4A7C15ULL;
    h ^= h >> 29;
  }
  for (; i < payload.size(); ++i) h = (h ^ payload[i]) * 0x100000001B3ULL;
  return h;
}

}  // namespace

std::size_t scan_capacity(const ScanAssemblerConfig& config) noexcept {
  const ModelTraits& t = traits(config.decoder.model);
  const double packets_per_s =
      t.supports_dual_return ? t.packets_per_second_dual : t.packets_per_second_single;
  const double packets_per_turn = packets_per_s * 60.0 / std::max(config.min_rpm, 1.0);
  return static_cast<std::size_t>(std::ceil(packets_per_turn * 1.1)) * kPointsPerPacket;
}

ScanAssembler::ScanAssembler(const Calibration& calibration, const ScanAssemblerConfig& config)
    : config_(config),
      decoder_(calibration, config.decoder),
      status_(config.decoder.model),
      max_gap_ns_(static_cast<std::int64_t>(config.max_gap_s * 1e9)),
      max_duration_ns_(static_cast<std::int64_t>(config.max_scan_duration_s * 1e9)),
      carry_points_(kPointsPerPacket) {
  carry_.header = &carry_header_;
  carry_.points = &carry_points_;
}

void ScanAssembler::begin(Scan& scan) noexcept {
  scan_ = &scan;
  scan.points.clear();
  current_.header = &scan.header;
  current_.points = &scan.points;
  current_.open = carry_.open;
  current_.epoch = carry_.epoch;
  scan.header = carry_.open ? carry_header_ : ScanHeader{};
  for (const Point& p : carry_points_) {
    if (!scan.points.push_back(p)) ++scan.header.points_dropped;
  }
  carry_points_.clear();
  carry_.open = false;
  target_ = &current_;
}

void ScanAssembler::open(Target& t, std::int64_t stamp_ns, std::uint16_t rotation, bool at_cut,
                         std::uint32_t device_usec, std::int32_t firing_in_packet_ns,
                         bool dual) noexcept {
  *t.header = ScanHeader{};
  t.points->clear();
  t.header->stamp_ns = stamp_ns;
  t.header->end_stamp_ns = stamp_ns;
  t.header->first_azimuth = rotation;
  t.header->last_azimuth = rotation;
  t.header->starts_at_cut = at_cut;
  t.header->device_usec_first = device_usec;
  t.header->first_firing_in_packet_ns = firing_in_packet_ns;
  const auto packet_utc = utc_time_ns(status_.sensor(), device_usec);
  t.header->device_utc_ns = packet_utc ? *packet_utc + firing_in_packet_ns : 0;
  t.header->gps = status_.sensor().valid ? status_.sensor().gps : GpsState::kUnknown;
  t.header->dual_return = dual;
  t.open = true;
  t.epoch = ++epochs_;
}

void ScanAssembler::close(bool at_cut) noexcept {
  ScanHeader& h = *current_.header;
  h.ends_at_cut = at_cut;
  h.below_completeness = h.completeness() < config_.min_completeness;
  counters_.below_completeness += h.below_completeness ? 1 : 0;
  h.sequence = next_sequence_++;
  counters_.points_dropped += h.points_dropped;
  ++counters_.scans;
  current_.open = false;
  target_ = &carry_;
}

bool ScanAssembler::is_duplicate(std::span<const std::uint8_t> payload) noexcept {
  const std::uint64_t h = payload_hash(payload);
  if (std::find(recent_.begin(), recent_.end(), h) != recent_.end()) return true;
  recent_[recent_next_] = h;
  recent_next_ = (recent_next_ + 1) % recent_.size();
  return false;
}

bool ScanAssembler::add_packet(std::span<const std::uint8_t> payload,
                               std::int64_t stamp_ns) noexcept {
  ++counters_.packets;
  const RawPacket* packet = as_packet(payload);
  if (packet == nullptr) {
    ++counters_.wrong_size;
    return false;
  }
  if (!accept(*packet, payload)) return false;
  if (scan_ == nullptr) return false;     // begin() was never called: nothing to write into
  if (target_ == &carry_) begin(*scan_);  // the caller did not take the closed scan: reuse it
  const std::uint32_t device_usec = read_trailer(*packet);
  const bool had_prev = have_prev_;
  bool completed = close_stale(stamp_ns);
  const bool restarted = !had_prev || completed;
  const bool dual = decoder_.dual_return(*packet);
  estimate_loss(packet->blocks[0].rotation);
  if (write_firings(*packet, stamp_ns, device_usec, dual)) completed = true;
  prev_stamp_ns_ = restarted ? stamp_ns : std::max(prev_stamp_ns_, stamp_ns);
  return completed;
}

// Invalid blocks, rotations that jump, duplicates and (when so configured) other models' packets
// are counted and refused.
bool ScanAssembler::accept(const RawPacket& packet,
                           std::span<const std::uint8_t> payload) noexcept {
  const bool banks = decoder_.model().layout == Layout::kBankPairs;  // HDL-64E: upper and lower
  for (const RawBlock& b : packet.blocks) {
    if ((b.bank != kUpperBank && (!banks || b.bank != kLowerBank)) ||
        b.rotation >= kRotationUnits) {
      ++counters_.invalid_block;
      return false;
    }
  }
  // The blocks of one packet are fired within about 0.3 ms: their rotations advance by a few
  // hundredths of a degree (equal within a firing). Rotations that jump (a corrupted packet whose
  // bank ids hold) would cross the cut angle and split a scan: the packet is dropped.
  for (int b = 1; b < kBlocksPerPacket; ++b) {
    const int step = forward(packet.blocks[b - 1].rotation, packet.blocks[b].rotation);
    if (step > kMaxBlockStep && step < kRotationUnits - kMaxBlockBack) {
      ++counters_.invalid_block;
      return false;
    }
  }
  if (is_duplicate(payload)) {
    ++counters_.duplicates;
    return false;
  }
  if (const PacketIdentity id = identify_packet(payload);
      !identity_matches(id, decoder_.model_id())) {
    ++counters_.model_mismatch;
    last_identity_ = id;
    if (config_.drop_other_models &&
        (id.kind == PacketIdentity::Kind::kHdl64 || id.model.has_value())) {
      ++counters_.other_model_dropped;
      return false;
    }
  }
  return true;
}

// The trailer kept, its status byte pair decoded; returns the device's microseconds (0 for a
// spin-count trailer).
std::uint32_t ScanAssembler::read_trailer(const RawPacket& packet) noexcept {
  const ModelTraits& model = decoder_.model();
  std::memcpy(last_trailer_.data(), packet.trailer, last_trailer_.size());
  if (model.trailer == TrailerKind::kGpsStatus) status_.add(packet.trailer[4], packet.trailer[5]);
  return model.trailer == TrailerKind::kSpinCount ? 0 : load_u32(packet.trailer);
}

// Silence, a clock jump or a scan that never ends closes the scan in progress: returns true
// when it did.
bool ScanAssembler::close_stale(std::int64_t stamp_ns) noexcept {
  if (!(have_prev_ && current_.open)) return false;
  const bool gap =
      stamp_ns - prev_stamp_ns_ > max_gap_ns_ || prev_stamp_ns_ - stamp_ns > max_gap_ns_;
  const bool timeout = stamp_ns - current_.header->stamp_ns > max_duration_ns_;
  if (!(gap || timeout)) return false;
  ++(gap ? counters_.time_gaps : counters_.timeouts);
  close(false);
  have_prev_ = false;
  step_ema_ = 0.0;
  return true;
}

// Loss estimate: an azimuth step between packets much larger than the usual one.
void ScanAssembler::estimate_loss(std::uint16_t r0) noexcept {
  if (!have_prev_) {
    prev_packet_rotation_ = r0;
    return;
  }
  const int step = forward(prev_packet_rotation_, r0);
  if (step > 0 && step < kHalfTurn) {
    if (step_ema_ == 0.0) {
      step_ema_ = step;
    } else if (step > kGapFactor * step_ema_) {
      const auto lost = static_cast<std::uint32_t>(std::lround(step / step_ema_) - 1);
      counters_.packets_lost += lost;
      target_->header->packets_lost += lost;
      gap_ = {prev_packet_rotation_, r0, lost, target_, target_->epoch};
    } else {
      step_ema_ = 0.95 * step_ema_ + 0.05 * step;
    }
    prev_packet_rotation_ = r0;
  } else if (step >= kHalfTurn && gap_.open > 0 && forward(gap_.from, r0) > 0 &&
             forward(gap_.from, r0) < forward(gap_.from, gap_.to)) {
    // A packet behind the newest one, inside the last gap: it was reordered, not lost. The
    // scan that counted the gap is corrected while it is still open.
    --gap_.open;
    --counters_.packets_lost;
    if (gap_.target == target_ && gap_.epoch == target_->epoch &&
        target_->header->packets_lost > 0) {
      --target_->header->packets_lost;
    }
  }
}

// Every firing of the packet into the scan it belongs to; returns true when a scan was closed
// at the cut angle.
bool ScanAssembler::write_firings(const RawPacket& packet, std::int64_t stamp_ns,
                                  std::uint32_t device_usec, bool dual) noexcept {
  const int group = decoder_.blocks_per_firing(dual);
  bool completed = false;
  bool wrote_current = false;
  bool wrote_carry = false;
  int azimuth_step = 0;  // to the next firing; the last firing of the packet keeps the one before
  for (int first = 0; first < kBlocksPerPacket; first += group) {
    const std::uint16_t r = packet.blocks[first].rotation;
    if (first + group < kBlocksPerPacket) {
      azimuth_step = forward(r, packet.blocks[first + group].rotation);
      if (azimuth_step > kHalfTurn) azimuth_step -= kRotationUnits;  // jitter backwards
    }
    const std::int32_t firing = decoder_.firing_offset_ns(first, 0, dual);
    if (!frame_firing(stamp_ns + firing, r, device_usec, firing, dual, completed)) continue;
    decode_firing(packet, first, group, stamp_ns, dual, azimuth_step);
    (target_ == &current_ ? wrote_current : wrote_carry) = true;
  }
  if (wrote_current) ++current_.header->packets;
  if (wrote_carry) ++carry_header_.packets;
  return completed;
}

// Cut-angle framing of one firing at time t and rotation r: closes the scan when the firing
// crosses the cut (completed set) and opens the target it goes to. False for a late firing
// (reordered behind the cut, counted): it is dropped.
bool ScanAssembler::frame_firing(std::int64_t t, std::uint16_t r, std::uint32_t device_usec,
                                 std::int32_t firing, bool dual, bool& completed) noexcept {
  if (!have_prev_) {
    have_prev_ = true;
    prev_rotation_ = r;
    if (!target_->open) open(*target_, t, r, false, device_usec, firing, dual);
    return true;
  }
  const int d = forward(prev_rotation_, r);
  if (d != 0 && d < kHalfTurn) {
    const int to_cut = forward(prev_rotation_, config_.cut_angle);
    if (to_cut > 0 && to_cut <= d) {
      if (target_ == &current_ && current_.open) {
        close(true);
        completed = true;
      }
      open(*target_, t, r, true, device_usec, firing, dual);
    }
    prev_rotation_ = r;
  } else if (d >= kHalfTurn) {
    // Backwards: a reordered firing. If the cut lies between it and the newest firing,
    // it belongs to a scan already closed.
    if (forward(config_.cut_angle, prev_rotation_) < kRotationUnits - d) {
      counters_.late_firings += 1;
      target_->header->late_firings += 1;
      return false;
    }
  }
  if (!target_->open) open(*target_, t, r, false, device_usec, firing, dual);
  return true;
}

// The firing's blocks [first, first + group) decoded into the target's points (over its
// capacity: counted as dropped), its end time and last azimuth.
void ScanAssembler::decode_firing(const RawPacket& packet, int first, int group,
                                  std::int64_t stamp_ns, bool dual, int azimuth_step) noexcept {
  const std::uint16_t r = packet.blocks[first].rotation;
  ScanHeader& h = *target_->header;
  rt::FixedVector<Point>& pts = *target_->points;
  const std::int64_t offset = stamp_ns - h.stamp_ns;
  for (int b = first; b < first + group; ++b) {
    const std::size_t size = pts.size();
    if (pts.capacity() - size < static_cast<std::size_t>(kLasersPerBlock)) {
      Point spill[kLasersPerBlock];
      const int n = decoder_.decode_block(packet.blocks[b], b, dual, offset, spill, azimuth_step);
      for (int i = 0; i < n; ++i) {
        if (!pts.push_back(spill[i])) ++h.points_dropped;
      }
      continue;
    }
    const int n =
        decoder_.decode_block(packet.blocks[b], b, dual, offset, pts.data() + size, azimuth_step);
    (void)pts.resize(size + static_cast<std::size_t>(n));
  }
  h.end_stamp_ns =
      std::max(h.end_stamp_ns,
               stamp_ns + decoder_.firing_offset_ns(first + group - 1, kLasersPerBlock - 1, dual));
  if (forward(h.first_azimuth, r) >= forward(h.first_azimuth, h.last_azimuth)) h.last_azimuth = r;
}

bool ScanAssembler::flush() noexcept {
  if (target_ != &current_ || !current_.open || current_.points->empty()) return false;
  close(false);
  return true;
}

}  // namespace stac::velodyne

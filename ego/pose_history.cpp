#include "ego/pose_history.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

namespace stac::ego {
namespace {

constexpr int kAttempts = 8;  // reads raced by the writer are retried this often

bool finite(const PoseSample& s) noexcept {
  return s.position_m.allFinite() && s.attitude.coeffs().allFinite() &&
         s.velocity_mps.allFinite() && s.angular_rate_rps.allFinite() && s.attitude.norm() > 0.5;
}

}  // namespace

const char* to_string(PoseStatus s) noexcept {
  switch (s) {
    case PoseStatus::kInterpolated:
      return "interpolated";
    case PoseStatus::kExtrapolated:
      return "extrapolated";
    case PoseStatus::kTooOld:
      return "too old";
    case PoseStatus::kTooNew:
      return "too new";
    case PoseStatus::kGap:
      return "gap";
    case PoseStatus::kEmpty:
      break;
  }
  return "empty";
}

PoseHistory::PoseHistory(const PoseHistoryConfig& config)
    : config_(config), slots_(std::make_unique<Slot[]>(config.capacity < 2 ? 2 : config.capacity)) {
  if (config_.capacity < 2) config_.capacity = 2;
}

bool PoseHistory::push(const PoseSample& sample) noexcept {
  const std::uint64_t i = head_.load(std::memory_order_relaxed);
  if (!finite(sample) ||
      (i > first_.load(std::memory_order_relaxed) && sample.stamp_ns <= last_stamp_ns_)) {
    rejected_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  const Eigen::Quaterniond q = sample.attitude.normalized();
  const double v[kFields] = {sample.position_m.x(),
                             sample.position_m.y(),
                             sample.position_m.z(),
                             q.w(),
                             q.x(),
                             q.y(),
                             q.z(),
                             sample.velocity_mps.x(),
                             sample.velocity_mps.y(),
                             sample.velocity_mps.z(),
                             sample.angular_rate_rps.x(),
                             sample.angular_rate_rps.y(),
                             sample.angular_rate_rps.z(),
                             0.0,
                             0.0,
                             0.0};
  // Seqlock without fences (which ThreadSanitizer cannot follow): every field is stored with
  // release, so a reader that sees any new field also sees the odd sequence stored before it.
  Slot& slot = slots_[i % config_.capacity];
  slot.sequence.store(2 * i + 1, std::memory_order_relaxed);
  slot.stamp_ns.store(sample.stamp_ns, std::memory_order_release);
  for (int k = 0; k < kFields; ++k)
    slot.v[static_cast<std::size_t>(k)].store(v[k], std::memory_order_release);
  slot.sequence.store(2 * i + 2, std::memory_order_release);
  head_.store(i + 1, std::memory_order_release);
  last_stamp_ns_ = sample.stamp_ns;
  return true;
}

bool PoseHistory::restart(const PoseSample& sample) noexcept {
  if (!finite(sample)) {
    rejected_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  const std::uint64_t i = head_.load(std::memory_order_relaxed);
  // Before the sample and head_: a reader that sees the new head sees the new timeline's start.
  first_.store(i, std::memory_order_release);
  last_stamp_ns_ = std::numeric_limits<std::int64_t>::min();
  return push(sample);
}

bool PoseHistory::read_stamp(std::uint64_t index, std::int64_t& out) const noexcept {
  const Slot& slot = slots_[index % config_.capacity];
  const std::uint64_t s1 = slot.sequence.load(std::memory_order_acquire);
  if (s1 != 2 * index + 2) return false;                // being written, or already another sample
  out = slot.stamp_ns.load(std::memory_order_acquire);  // acquire: the check below stays after it
  return slot.sequence.load(std::memory_order_relaxed) == s1;
}

bool PoseHistory::read(std::uint64_t index, PoseSample& out) const noexcept {
  const Slot& slot = slots_[index % config_.capacity];
  const std::uint64_t s1 = slot.sequence.load(std::memory_order_acquire);
  if (s1 != 2 * index + 2) return false;
  double v[kFields];
  out.stamp_ns = slot.stamp_ns.load(std::memory_order_acquire);
  for (int k = 0; k < kFields; ++k)
    v[k] = slot.v[static_cast<std::size_t>(k)].load(std::memory_order_acquire);
  if (slot.sequence.load(std::memory_order_relaxed) != s1) return false;
  out.position_m = {v[0], v[1], v[2]};
  out.attitude = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
  out.velocity_mps = {v[7], v[8], v[9]};
  out.angular_rate_rps = {v[10], v[11], v[12]};
  return true;
}

std::int64_t PoseHistory::newest_stamp_ns() const noexcept {
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    const std::uint64_t n = head_.load(std::memory_order_acquire);
    if (n == 0) return INT64_MIN;
    std::int64_t t = 0;
    if (read_stamp(n - 1, t)) return t;
  }
  return INT64_MIN;
}

PoseLookup PoseHistory::at(std::int64_t stamp_ns) const noexcept {
  PoseLookup out;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    const std::uint64_t n = head_.load(std::memory_order_acquire);
    if (n == 0) return out;  // kEmpty
    const std::uint64_t first = first_.load(std::memory_order_acquire);
    if (first >= n) continue;  // a new timeline's first sample is being written
    PoseSample newest;
    if (!read(n - 1, newest)) continue;
    if (stamp_ns >= newest.stamp_ns) {
      const std::int64_t ahead = stamp_ns - newest.stamp_ns;
      out.pose = extrapolate(newest, stamp_ns);
      out.status = ahead == 0                              ? PoseStatus::kInterpolated
                   : ahead <= config_.max_extrapolation_ns ? PoseStatus::kExtrapolated
                                                           : PoseStatus::kTooNew;
      return out;
    }
    // The oldest slot may be overwritten at any moment: keep one slot of margin.
    std::uint64_t lo = n > config_.capacity ? n - config_.capacity + 1 : 0;
    lo = std::max(lo, first);  // the samples of an earlier timeline are not this one's
    std::uint64_t hi = n - 1;  // stamp(hi) > stamp_ns
    std::int64_t t_lo = 0;
    if (!read_stamp(lo, t_lo)) continue;
    if (t_lo > stamp_ns) {
      out.status = PoseStatus::kTooOld;
      return out;
    }
    bool raced = false;
    while (hi - lo > 1) {  // invariant: stamp(lo) <= stamp_ns < stamp(hi)
      const std::uint64_t mid = lo + (hi - lo) / 2;
      std::int64_t t_mid = 0;
      if (!read_stamp(mid, t_mid)) {
        raced = true;
        break;
      }
      (t_mid <= stamp_ns ? lo : hi) = mid;
    }
    PoseSample a, b;
    if (raced || !read(lo, a) || !read(hi, b)) continue;
    out.pose = interpolate(a, b, stamp_ns);
    out.status =
        b.stamp_ns - a.stamp_ns > config_.max_gap_ns ? PoseStatus::kGap : PoseStatus::kInterpolated;
    return out;
  }
  out.status = PoseStatus::kTooOld;  // the writer kept overwriting what we read
  return out;
}

PoseSample interpolate(const PoseSample& a, const PoseSample& b, std::int64_t stamp_ns) noexcept {
  const double span = static_cast<double>(b.stamp_ns - a.stamp_ns);
  double f = span > 0 ? static_cast<double>(stamp_ns - a.stamp_ns) / span : 0.0;
  f = f < 0 ? 0 : (f > 1 ? 1 : f);
  PoseSample p;
  p.stamp_ns = stamp_ns;
  p.position_m = a.position_m + f * (b.position_m - a.position_m);
  p.attitude = a.attitude.slerp(f, b.attitude);
  p.velocity_mps = a.velocity_mps + f * (b.velocity_mps - a.velocity_mps);
  p.angular_rate_rps = a.angular_rate_rps + f * (b.angular_rate_rps - a.angular_rate_rps);
  return p;
}

PoseSample extrapolate(const PoseSample& p, std::int64_t stamp_ns) noexcept {
  const double dt = static_cast<double>(stamp_ns - p.stamp_ns) * 1e-9;
  PoseSample out = p;
  out.stamp_ns = stamp_ns;
  out.position_m += p.velocity_mps * dt;
  const double angle = p.angular_rate_rps.norm() * dt;
  if (angle > 0) {
    out.attitude =
        (p.attitude * Eigen::AngleAxisd(angle, p.angular_rate_rps.normalized())).normalized();
  }
  return out;
}

}  // namespace stac::ego

// Where the vehicle is, from the INS when it is alive and from CAN odometry when it is not:
// Applanix Group 1 fixes become poses on the UTC pose clock in the local frame; when no fix came
// for `ins_timeout_ns`, speed and yaw rate are integrated from the last INS pose (height, roll
// and pitch held) and pushed as dead-reckoned poses, until the INS returns. One thread (the
// pose thread) calls it; the PoseHistory it writes is read lock-free by perception.
#pragma once

#include <cstdint>

#include "drivers/applanix/stream_parser.hpp"
#include "drivers/can/odometry.hpp"
#include "ego/local_frame.hpp"
#include "ego/pose_history.hpp"

namespace stac::ego {

// GPS time (ns since 1980-01-06) -> UTC (ns since 1970), GPS - UTC being `gps_utc_offset_s`.
std::int64_t gps_to_utc_ns(std::int64_t gps_ns, double gps_utc_offset_s) noexcept;

// An Applanix Group 1 navigation solution as the INS fix of time `stamp_ns` (pose clock).
InsFix ins_fix(const applanix::Group1& g, std::int64_t stamp_ns) noexcept;

enum class EgoSource : std::uint8_t {
  kNone,           // nothing received yet
  kIns,            // the last pose came from the INS
  kDeadReckoning,  // the INS is silent; poses come from CAN odometry
  kLost,           // the INS is silent and odometry is stale or absent
};
const char* to_string(EgoSource s) noexcept;

struct EgoEstimatorConfig {
  std::int64_t ins_timeout_ns = 100'000'000;  // no fix for this long: the INS counts as lost
  int max_alignment_status = 2;               // Group 1 worse than this (0 full navigation,
                                              // 1 fine, 2 GC/coarse..., 8 none) is not used
  std::int64_t dead_reckoning_period_ns = 5'000'000;  // pose rate while dead reckoning (200 Hz)
  can::DeadReckoningConfig odometry;
};

struct EgoCounters {
  std::uint64_t ins_fixes = 0;         // Group 1 turned into poses
  std::uint64_t no_absolute_time = 0;  // Group 1 before a Group 3 gave the GPS week: skipped
  std::uint64_t not_aligned = 0;       // alignment status above the limit: skipped
  std::uint64_t impossible = 0;        // a value no vehicle has (NaN, |lat| > 90, |lon| > 360, alt
                                       // outside -1..20 km, speed over 200 m/s): skipped, never
                                       // the origin
  std::uint64_t dead_reckoned = 0;     // poses pushed from odometry
  std::uint64_t rejected = 0;          // poses the history refused (out of order)
  // A fix over 1 s after or before the last that no fix within 0.1 s followed: a corrupted time,
  // dropped. One the next fix confirms is taken: ahead, the INS back after an outage; back, a
  // new timeline (a looping replay, the clock corrected after bad fixes), counted here.
  std::uint64_t time_jumps = 0;
  std::uint64_t backward_jumps = 0;
};

class EgoEstimator {
 public:
  EgoEstimator(const EgoEstimatorConfig& config, LocalFrame& frame, PoseHistory& history) noexcept;

  // One parsed Applanix message; `parser` gives the GPS-UTC offset of its last Group 3.
  void add_ins(const applanix::Parsed& message, const applanix::StreamParser& parser) noexcept;
  // One navigation solution already on the pose clock, from another INS (a KITTI raw drive's
  // OXTS records); the same checks of time jumps as add_ins.
  void add_fix(const InsFix& fix) noexcept;
  // One decoded CAN frame with speed and/or yaw rate.
  void add_odometry(const can::OdometryUpdate& update) noexcept;

  // What the poses come from at `now_ns` (pose clock), for health.
  [[nodiscard]] EgoSource source(std::int64_t now_ns) const noexcept;
  const EgoCounters& counters() const noexcept { return counters_; }
  // The stamp of the newest fix that became a pose (pose clock, UTC ns); 0 before the first.
  [[nodiscard]] std::int64_t last_fix_ns() const noexcept {
    return have_ins_ ? last_ins_.stamp_ns : 0;
  }

 private:
  EgoEstimatorConfig config_;
  LocalFrame& frame_;
  PoseHistory& history_;
  can::DeadReckoning odometry_;
  void accept(const PoseSample& pose) noexcept;
  void commit(const PoseSample& pose) noexcept;  // a fix the history took

  PoseSample last_ins_;
  bool have_ins_ = false;
  // A fix that jumped ahead of the last accepted one, held until the next one confirms it.
  PoseSample after_jump_;
  bool have_after_jump_ = false;
  std::int64_t last_pushed_ns_ = 0;
  EgoCounters counters_;
};

}  // namespace stac::ego

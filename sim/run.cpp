#include "sim/run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rt/json_number.hpp"

namespace stac::sim {
namespace {

int forward(int from, int to) {
  return (to - from + 36000) % 36000;
}

}  // namespace

std::string to_json(const TruthScan& s, const double* origin) {
  std::string out;
  char buf[1024];
  if (origin != nullptr) {
    std::snprintf(buf, sizeof(buf), "{\"origin\":[%s,%s,%s],",
                  rt::json_number(origin[0], 10).c_str(), rt::json_number(origin[1], 10).c_str(),
                  rt::json_number(origin[2], 4).c_str());
    out += buf;
  }
  const auto num = [](double v, int decimals) { return rt::json_number(v, decimals); };
  std::snprintf(buf, sizeof(buf),
                "%s\"scan\":%llu,\"time\":%lld.%09lld,\"end_time\":%lld.%09lld,\"points\":%u,"
                "\"ground_points\":%u,\"ego\":{\"x\":%s,\"y\":%s,\"z\":%s,\"roll\":%s,"
                "\"pitch\":%s,\"yaw\":%s,\"speed\":%s,\"yaw_rate\":%s},\"objects\":[",
                origin != nullptr ? "" : "{", static_cast<unsigned long long>(s.scan),
                static_cast<long long>(s.start_ns / 1'000'000'000),
                static_cast<long long>(s.start_ns % 1'000'000'000),
                static_cast<long long>(s.end_ns / 1'000'000'000),
                static_cast<long long>(s.end_ns % 1'000'000'000), s.points, s.ground_points,
                num(s.ego.x, 4).c_str(), num(s.ego.y, 4).c_str(), num(s.ego.z, 4).c_str(),
                num(s.ego.roll, 6).c_str(), num(s.ego.pitch, 6).c_str(), num(s.ego.yaw, 6).c_str(),
                num(s.ego.speed, 4).c_str(), num(s.ego.yaw_rate, 6).c_str());
  out += buf;
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    const TruthObject& o = s.objects[i];
    std::snprintf(buf, sizeof(buf),
                  "%s{\"id\":%u,\"class\":\"%s\",\"box\":{\"x\":%s,\"y\":%s,\"z\":%s,"
                  "\"length\":%s,\"width\":%s,\"height\":%s,\"yaw\":%s},"
                  "\"velocity\":{\"x\":%s,\"y\":%s},\"points\":%u,\"time\":%s}",
                  i == 0 ? "" : ",", o.id, std::string(class_name(o.cls)).c_str(),
                  num(o.x, 4).c_str(), num(o.y, 4).c_str(), num(o.z, 4).c_str(),
                  num(o.length, 3).c_str(), num(o.width, 3).c_str(), num(o.height, 3).c_str(),
                  num(o.yaw, 5).c_str(), num(o.vx, 4).c_str(), num(o.vy, 4).c_str(), o.points,
                  num(o.time_s, 6).c_str());
    out += buf;
  }
  out += "]}";
  return out;
}

rt::Result<std::unique_ptr<SimRun>> SimRun::create(const velodyne::Calibration& calibration,
                                                   const RunConfig& config) {
  if (!(config.duration_s > 0)) return rt::make_error("--duration must be positive");
  if (config.lidar.dual_return && !velodyne::traits(config.lidar.model).supports_dual_return) {
    return rt::make_error(std::string("dual return needs a model that has it (S3, HDL-32E, VLP-16, "
                                      "VLP-32C), not the ") +
                          std::string(velodyne::traits(config.lidar.model).name));
  }
  if (calibration.num_lasers < velodyne::traits(config.lidar.model).lasers) {
    return rt::make_error(calibration.source + ": too few lasers for a " +
                          std::string(velodyne::traits(config.lidar.model).name));
  }
  auto scenario = make_scenario(config.scenario, config.seed, config.duration_s);
  if (!scenario) return rt::Unexpected<rt::Error>{scenario.error()};
  std::erase_if(scenario->actors, [&](const Actor& a) {
    return std::find(config.without.begin(), config.without.end(), a.cls) != config.without.end();
  });
  std::unique_ptr<SimRun> run(new SimRun());
  run->config_ = config;
  run->scenario_ = std::move(*scenario);
  run->world_ = std::make_unique<World>(run->scenario_.ground, run->scenario_.actors);
  SimRun* self = run.get();
  run->lidar_ = std::make_unique<LidarSim>(calibration, config.lidar, *run->world_,
                                           [self](double t) { return self->ego(t); });
  run->hits_.assign(run->world_->actors().size(), 0);
  run->hit_time_sum_.assign(run->world_->actors().size(), 0.0);
  return run;
}

std::uint32_t SimRun::packet_count() const noexcept {
  return static_cast<std::uint32_t>(config_.duration_s * lidar_->packets_per_second());
}

void SimRun::close_scan(const std::function<void(const TruthScan&)>& on_scan) {
  const double t_start = static_cast<double>(current_.start_ns - config_.start_ns) * 1e-9;
  const double t_end = static_cast<double>(current_.end_ns - config_.start_ns) * 1e-9;
  const auto& actors = world_->actors();
  for (std::size_t i = 0; i < actors.size(); ++i) {
    const Actor& a = actors[i];
    double t = 0.5 * (t_start + t_end);
    if (hits_[i] > 0) {
      t = hit_time_sum_[i] / hits_[i];
    } else {
      if (!is_foreground(a.cls)) continue;
      const Pose p = world_->actor_pose(i, t);
      if (std::hypot(p.x - current_.ego.x, p.y - current_.ego.y) > 100.0) continue;
    }
    const Pose p = world_->actor_pose(i, t);
    const V3 v = a.path.velocity_at(t);
    current_.objects.push_back({a.id, a.cls, p.x, p.y, p.z + a.size.z / 2, a.size.x, a.size.y,
                                a.size.z, p.yaw, v.x, v.y, hits_[i], t});
    hits_[i] = 0;
    hit_time_sum_[i] = 0.0;
  }
  current_.scan = next_scan_++;
  if (on_scan) on_scan(current_);
  current_ = TruthScan{};
  open_ = false;
}

void SimRun::packet(std::uint32_t k, std::array<std::uint8_t, velodyne::kPacketSize>& bytes,
                    std::int64_t& first_firing_ns,
                    const std::function<void(const TruthScan&)>& on_scan,
                    const std::function<void(const BeamRecord&)>& on_beam) {
  double t0 = 0;
  lidar_->make_packet(k, bytes, t0, [&](const BeamRecord& b) {
    // Framing: a new scan at the first firing whose rotation crosses the cut angle.
    if (b.channel == 0) {  // a block's first beam: the block's rotation frames the scans
      if (have_prev_ && b.block_rotation != prev_rotation_) {
        const int d = forward(prev_rotation_, b.block_rotation);
        const int to_cut = forward(prev_rotation_, config_.cut_angle);
        if (d < 18000 && to_cut > 0 && to_cut <= d && open_) close_scan(on_scan);
      }
      if (!have_prev_ || forward(prev_rotation_, b.block_rotation) < 18000)
        prev_rotation_ = b.block_rotation;
      have_prev_ = true;
    }
    const std::int64_t t_ns = config_.start_ns + std::llround(b.time_s * 1e9);
    if (!open_) {
      open_ = true;
      current_.start_ns = t_ns;
      current_.ego = ego(b.time_s);
    }
    current_.end_ns = std::max(current_.end_ns, t_ns);
    if (b.returned) {
      ++current_.points;
      if (b.actor == -1) ++current_.ground_points;
      if (b.actor >= 0) {
        ++hits_[static_cast<std::size_t>(b.actor)];
        hit_time_sum_[static_cast<std::size_t>(b.actor)] += b.time_s;
      }
    }
    if (on_beam) on_beam(b);
  });
  first_firing_ns = config_.start_ns + std::llround(t0 * 1e9);
}

bool SimRun::finish(const std::function<void(const TruthScan&)>& on_scan) {
  if (!open_) return false;
  close_scan(on_scan);
  return true;
}

}  // namespace stac::sim

// The `run:` section of config/stac.yaml: the live process's threads, deadline and inputs
// (docs/run.md). Every key is required; errors name `run.<key>`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "rt/deadline_monitor.hpp"
#include "rt/expected.hpp"
#include "rt/scheduling.hpp"

namespace stac::settings {

enum class InsTransport : std::uint8_t { kTcp, kUdp, kNone };

struct RunSettings {
  rt::DeadlineConfig deadline;   // budget and histogram range
  std::size_t result_slots = 4;  // perception -> publisher results in flight
  bool lock_memory = true;       // mlockall at start-up
  int cpu_wake_latency_us =
      -1;  // >= 0: a PM QoS request held while running (rt::CpuLatencyRequest)
  // Published tracks are classified before their scan is published until it is this old (from
  // its last firing); the others, and the accumulated clouds, after it (docs/run.md).
  std::int64_t classify_budget_ns = 8'000'000;
  rt::ThreadSchedule receiver, perception, publisher, pose;
  InsTransport ins = InsTransport::kTcp;
  std::string ins_address;  // tcp: the POS computer (IPv4); port: ego.ins_port
  bool can = false;  // read the vehicle CAN bus (section can:, socketcan, gs_usb or cannelloni)
  std::int64_t velodyne_timeout_ns = 200'000'000;  // watchdog: lidar silent this long = stale
};

rt::Result<RunSettings> load_run_settings(const std::filesystem::path& config_file);
rt::Result<InsTransport> parse_ins_transport(const std::string& text);

}  // namespace stac::settings

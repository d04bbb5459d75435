#include "settings/run_settings.hpp"

#include <arpa/inet.h>

#include <cmath>

#include "settings/config_section.hpp"

namespace stac::settings {
namespace {

rt::Status read_schedule(const ConfigSection& s, const char* priority_key, const char* cpu_key,
                         rt::ThreadSchedule& out) {
  STAC_CONFIG_GET(s, int, priority_key, out.fifo_priority);
  STAC_CONFIG_GET(s, int, cpu_key, out.cpu);
  if (out.fifo_priority < 0 || out.fifo_priority > 99)
    return s.error(priority_key, "must be 0..99 (0: no SCHED_FIFO)");
  if (out.cpu < -1 || out.cpu > 1023)
    return s.error(cpu_key, "must be -1 (any CPU) or a CPU index 0..1023");
  return {};
}

}  // namespace

rt::Result<InsTransport> parse_ins_transport(const std::string& text) {
  if (text == "tcp") return InsTransport::kTcp;
  if (text == "udp") return InsTransport::kUdp;
  if (text == "none") return InsTransport::kNone;
  return rt::make_error("'" + text + "' is not tcp, udp or none");
}

rt::Result<RunSettings> load_run_settings(const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "run");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& r = *section;
  RunSettings s;
  double deadline_ms = 0, histogram_ms = 0, velodyne_timeout_s = 0, classify_budget_ms = 0;
  int slots = 0;
  std::string ins;
  STAC_CONFIG_GET(r, double, "deadline_ms", deadline_ms);
  STAC_CONFIG_GET(r, double, "latency_histogram_max_ms", histogram_ms);
  STAC_CONFIG_GET(r, int, "result_slots", slots);
  STAC_CONFIG_GET(r, bool, "lock_memory", s.lock_memory);
  STAC_CONFIG_GET(r, int, "cpu_wake_latency_us", s.cpu_wake_latency_us);
  STAC_CONFIG_GET(r, double, "classify_budget_ms", classify_budget_ms);
  STAC_CONFIG_GET(r, std::string, "ins", ins);
  STAC_CONFIG_GET(r, std::string, "ins_address", s.ins_address);
  STAC_CONFIG_GET(r, bool, "can", s.can);
  STAC_CONFIG_GET(r, double, "velodyne_timeout_s", velodyne_timeout_s);
  for (auto [p, c, t] : {std::tuple{"receiver_priority", "receiver_cpu", &s.receiver},
                         std::tuple{"perception_priority", "perception_cpu", &s.perception},
                         std::tuple{"publisher_priority", "publisher_cpu", &s.publisher},
                         std::tuple{"pose_priority", "pose_cpu", &s.pose}}) {
    if (auto ok = read_schedule(r, p, c, *t); !ok) return rt::Unexpected<rt::Error>{ok.error()};
  }
  if (!(deadline_ms > 0 && deadline_ms <= 10'000))
    return r.error("deadline_ms", "must be in (0, 10000] ms");
  if (!(histogram_ms >= deadline_ms && histogram_ms <= 60'000)) {
    return r.error("latency_histogram_max_ms",
                   "must be at least run.deadline_ms and at most 60000 ms");
  }
  if (slots < 2 || slots > 64) return r.error("result_slots", "must be 2..64");
  if (!(classify_budget_ms >= 0 && classify_budget_ms <= deadline_ms)) {
    return r.error("classify_budget_ms",
                   "must be in [0, run.deadline_ms] ms (0: every class after publication)");
  }
  if (s.cpu_wake_latency_us < -1 || s.cpu_wake_latency_us > 1'000'000)
    return r.error("cpu_wake_latency_us", "must be -1 (no request) or 0..1000000 us");
  if (!(velodyne_timeout_s > 0 && velodyne_timeout_s <= 10))
    return r.error("velodyne_timeout_s", "must be in (0, 10] s");
  auto transport = parse_ins_transport(ins);
  if (!transport) return r.error("ins", transport.error().message);
  s.ins = *transport;
  in_addr a{};
  if (s.ins == InsTransport::kTcp && inet_pton(AF_INET, s.ins_address.c_str(), &a) != 1) {
    return r.error("ins_address",
                   "'" + s.ins_address + "' is not an IPv4 address (needed with run.ins: tcp)");
  }
  s.deadline.budget_ns = std::llround(deadline_ms * 1e6);
  s.deadline.histogram_max_ns = std::llround(histogram_ms * 1e6);
  s.deadline.histogram_bins =
      static_cast<std::size_t>(std::ceil(histogram_ms / 0.1));  // 0.1 ms bins
  s.result_slots = static_cast<std::size_t>(slots);
  s.classify_budget_ns = std::llround(classify_budget_ms * 1e6);
  s.velodyne_timeout_ns = std::llround(velodyne_timeout_s * 1e9);
  return s;
}

}  // namespace stac::settings

// stac echo TOPIC: subscribes to one of STAC's DDS topics and prints a one-line summary per
// sample; exits after --count samples (0) or at --timeout with a message saying what arrived (1).
#include <cstdio>
#include <string>

#include "dds/idl_types.hpp"
#include "dds/topics.hpp"
#include "rt/deadline_monitor.hpp"
#include "tools/commands.hpp"
#include "tools/dds_settings.hpp"
#include "tools/settings.hpp"

namespace stac::tools {
namespace {

struct EchoOptions {
  std::string topic, config;
  int count = 0;
  double timeout_s = 10;
  int domain = -1;
  bool latency = false;
};

template <class Time>
double seconds(const Time& t) {
  return static_cast<double>(t.sec) + 1e-9 * static_cast<double>(t.nanosec);
}

const char* label_name(unsigned label) {
  static const char* const names[] = {"unknown", "car", "pedestrian", "bicyclist", "background"};
  return label < 5 ? names[label] : "?";
}

template <class S>
void print_tracked(const S& s) {
  std::printf("tracked_objects scan %llu t=%.6f objects=%u", static_cast<unsigned long long>(s.scan_index),
              seconds(s.stamp), s.objects._length);
  for (std::uint32_t i = 0; i < s.objects._length && i < 5; ++i) {
    const auto& o = s.objects._buffer[i];
    const unsigned label = o.classification._length > 0 ? o.classification._buffer[0].label : 0;
    std::printf(" | #%llu %s x=%.2f y=%.2f v=(%.2f,%.2f) age=%u", static_cast<unsigned long long>(o.object_id),
                label_name(label), o.kinematics.position.x, o.kinematics.position.y, o.kinematics.velocity.x,
                o.kinematics.velocity.y, o.age);
  }
  std::printf("%s\n", s.objects._length > 5 ? " | ..." : "");
}

template <class S>
void print_segments(const S& s) {
  std::printf("segments scan %llu t=%.6f segments=%u\n", static_cast<unsigned long long>(s.scan_index),
              seconds(s.stamp), s.segments._length);
}

template <class S>
void print_pose(const S& s) {
  std::printf("ego_pose t=%.6f x=%.3f y=%.3f z=%.3f v=(%.2f,%.2f) yaw_rate=%.3f source=%u\n", seconds(s.stamp),
              s.position.x, s.position.y, s.position.z, s.velocity.x, s.velocity.y,
              static_cast<double>(s.yaw_rate), static_cast<unsigned>(s.source));
}

template <class S>
void print_health(const S& s) {
  std::printf("health scan %llu t=%.6f e2e=%uus misses=%llu", static_cast<unsigned long long>(s.scan_index),
              seconds(s.stamp), s.end_to_end_latency_us, static_cast<unsigned long long>(s.deadline_misses));
  for (std::uint32_t i = 0; i < s.stages._length; ++i)
    std::printf(" %s=%uus", s.stages._buffer[i].stage, s.stages._buffer[i].latency_us);
  for (std::uint32_t i = 0; i < s.drops._length; ++i)
    std::printf(" drop:%s=%llu", s.drops._buffer[i].cause, static_cast<unsigned long long>(s.drops._buffer[i].count));
  for (std::uint32_t i = 0; i < s.sensors._length; ++i)
    std::printf(" %s:%u", s.sensors._buffer[i].name, static_cast<unsigned>(s.sensors._buffer[i].status));
  std::printf("\n");
}

template <bool Ros2>
void print_sample(dds::Topic t, const void* sample) {
  using T = dds::IdlTypes<Ros2>;
  switch (t) {
    case dds::Topic::kTrackedObjects: print_tracked(*static_cast<const typename T::TrackedObjects*>(sample)); break;
    case dds::Topic::kSegments: print_segments(*static_cast<const typename T::ScanSegments*>(sample)); break;
    case dds::Topic::kEgoPose: print_pose(*static_cast<const typename T::EgoPose*>(sample)); break;
    case dds::Topic::kHealth: print_health(*static_cast<const typename T::Health*>(sample)); break;
  }
}

template <bool Ros2>
const dds_topic_descriptor_t* descriptor(dds::Topic t) {
  using T = dds::IdlTypes<Ros2>;
  switch (t) {
    case dds::Topic::kTrackedObjects: return T::tracked_objects();
    case dds::Topic::kSegments: return T::segments();
    case dds::Topic::kEgoPose: return T::ego_pose();
    case dds::Topic::kHealth: return T::health();
  }
  return nullptr;
}

int run_echo(const EchoOptions& o) {
  auto topic = dds::topic_from_suffix(o.topic);
  if (!topic) return fail(topic.error().message);
  auto settings = load_dds_settings(config_path(o.config));
  if (!settings) return fail(settings.error().message);
  dds::PublisherConfig c = *settings;
  if (o.domain >= 0) c.domain_id = static_cast<std::uint32_t>(o.domain);
  if (c.domain_id > 230) return fail("--domain must be 0..230");
  if (!c.config_uri.empty()) {
    const dds_entity_t domain = dds_create_domain(c.domain_id, c.config_uri.c_str());
    if (domain < 0) return fail("creating DDS domain with " + c.config_uri + ": " + dds_strretcode(domain));
  }
  const dds_entity_t participant = dds_create_participant(c.domain_id, nullptr, nullptr);
  if (participant < 0) return fail(std::string("creating a DDS participant: ") + dds_strretcode(participant));
  const std::string name = dds::topic_name(*topic, c.topic_prefix, c.ros2_names);
  const dds_topic_descriptor_t* type = c.ros2_names ? descriptor<true>(*topic) : descriptor<false>(*topic);
  const dds_entity_t t = dds_create_topic(participant, type, name.c_str(), nullptr, nullptr);
  if (t < 0) return fail("creating DDS topic " + name + ": " + dds_strretcode(t));
  // The topic's QoS with a deeper history: a diagnostic shows every sample, not only the latest.
  dds::QosPtr qos = dds::reader_qos(*topic);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 64);
  const dds_entity_t reader = dds_create_reader(participant, t, qos.get(), nullptr);
  if (reader < 0) return fail("creating a DDS reader of " + name + ": " + dds_strretcode(reader));
  std::fprintf(stderr, "stac echo: listening on %s (domain %u)\n", name.c_str(), c.domain_id);

  // Woken by a read condition (no polling), so the receive time is when the sample arrived.
  const dds_entity_t waitset = dds_create_waitset(participant);
  const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
  if (waitset < 0 || condition < 0 || dds_waitset_attach(waitset, condition, reader) < 0) {
    return fail("creating a DDS waitset for " + name);
  }
  rt::LatencyHistogram latency(1'000'000'000, 100'000);  // publish -> receive, 10 us bins over 1 s
  int received = 0;
  const dds_time_t end = dds_time() + static_cast<dds_duration_t>(o.timeout_s * 1e9);
  while ((o.count == 0 || received < o.count) && dds_time() < end) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info{};
    const dds_return_t n = dds_take(reader, samples, &info, 1, 1);
    if (n < 0) return fail(std::string("reading DDS: ") + dds_strretcode(n));
    if (n == 0) {
      (void)dds_waitset_wait_until(waitset, nullptr, 0, end);
      continue;
    }
    const dds_time_t now = dds_time();
    if (info.valid_data) {
      latency.add(now - info.source_timestamp);
      c.ros2_names ? print_sample<true>(*topic, samples[0]) : print_sample<false>(*topic, samples[0]);
      std::fflush(stdout);
      ++received;
    }
    dds_return_loan(reader, samples, n);
  }
  if (o.latency && latency.count() > 0) {
    const auto us = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-3; };
    std::fprintf(
        stderr,
        "stac echo: publish -> receive latency over %llu samples: p50 %.0f us, p99 %.0f us, "
        "max %.0f us (writer's source timestamp to this reader's take, one host clock)\n",
        static_cast<unsigned long long>(latency.count()), us(latency.percentile(0.5)),
        us(latency.percentile(0.99)), us(latency.max_ns()));
  }
  dds_delete(participant);
  if (o.count > 0 && received < o.count) {
    std::fprintf(stderr, "stac echo: timed out after %.1f s with %d of %d samples on %s (is a publisher running "
                 "on domain %u with the same dds config?)\n", o.timeout_s, received, o.count, name.c_str(), c.domain_id);
    return 1;
  }
  if (received == 0) {
    std::fprintf(stderr, "stac echo: no sample on %s within %.1f s (is a publisher running on domain %u with "
                 "the same dds config?)\n", name.c_str(), o.timeout_s, c.domain_id);
    return 1;
  }
  std::fprintf(stderr, "stac echo: %d samples on %s\n", received, name.c_str());
  return 0;
}

}  // namespace

void add_echo_command(CLI::App& app) {
  auto o = std::make_shared<EchoOptions>();
  auto* cmd = app.add_subcommand("echo", "Print the samples arriving on one of STAC's DDS topics");
  cmd->add_option("topic", o->topic, "tracked_objects, segments, ego_pose or health")->required();
  cmd->add_option("--count", o->count, "exit after this many samples (0: run until the timeout)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--timeout", o->timeout_s, "give up after this many seconds")->check(CLI::PositiveNumber);
  cmd->add_option("--domain", o->domain, "DDS domain id (default: dds.domain_id of the config)");
  cmd->add_option("--config", o->config, "configuration file (default: $STAC_CONFIG or config/stac.yaml)");
  cmd->add_flag("--latency", o->latency,
                "at the end, print the publish -> receive latency (p50, p99, max) of the samples");
  cmd->callback([o] {
    if (const int rc = run_echo(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace stac::tools

// stac echo TOPIC: subscribes to one of STAC's DDS topics and prints a one-line summary per
// sample; exits after --count samples (0) or at --timeout with a message saying what arrived (1).
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <string>

#include "dds/idl_types.hpp"
#include "dds/reading.hpp"
#include "dds/topics.hpp"
#include "rt/deadline_monitor.hpp"
#include "settings/dds_settings.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"

namespace stac::tools {

using namespace stac::settings;
namespace {

struct EchoOptions {
  std::string topic, config, dds_config;
  int count = 0;
  double timeout_s = 10;
  int domain = -1;
  bool latency = false;
};

template <class S>
void print_tracked(const S& s) {
  std::printf("tracked_objects scan %llu t=%.6f objects=%u",
              static_cast<unsigned long long>(s.scan_index), dds::seconds(s.stamp),
              s.objects._length);
  for (std::uint32_t i = 0; i < s.objects._length && i < 5; ++i) {
    const auto& o = s.objects._buffer[i];
    std::printf(" | #%llu %s x=%.2f y=%.2f v=(%.2f,%.2f) age=%u",
                static_cast<unsigned long long>(o.object_id), dds::shown_class(o).name,
                o.kinematics.position.x, o.kinematics.position.y, o.kinematics.velocity.x,
                o.kinematics.velocity.y, o.age);
  }
  std::printf("%s\n", s.objects._length > 5 ? " | ..." : "");
}

template <class S>
void print_segments(const S& s) {
  std::printf("segments scan %llu t=%.6f segments=%u\n",
              static_cast<unsigned long long>(s.scan_index), dds::seconds(s.stamp),
              s.segments._length);
}

template <class S>
void print_pose(const S& s) {
  std::printf("ego_pose t=%.6f x=%.3f y=%.3f z=%.3f v=(%.2f,%.2f) yaw_rate=%.3f source=%u\n",
              dds::seconds(s.stamp), s.position.x, s.position.y, s.position.z, s.velocity.x,
              s.velocity.y, static_cast<double>(s.yaw_rate), static_cast<unsigned>(s.source));
}

template <class S>
void print_health(const S& s) {
  std::printf("health scan %llu t=%.6f e2e=%uus misses=%llu model=%016llx reloads=%u",
              static_cast<unsigned long long>(s.scan_index), dds::seconds(s.stamp),
              s.end_to_end_latency_us, static_cast<unsigned long long>(s.deadline_misses),
              static_cast<unsigned long long>(s.model_hash), s.model_reloads);
  for (std::uint32_t i = 0; i < s.stages._length; ++i)
    std::printf(" %s=%uus", s.stages._buffer[i].stage, s.stages._buffer[i].latency_us);
  for (std::uint32_t i = 0; i < s.drops._length; ++i)
    std::printf(" drop:%s=%llu", s.drops._buffer[i].cause,
                static_cast<unsigned long long>(s.drops._buffer[i].count));
  for (std::uint32_t i = 0; i < s.sensors._length; ++i)
    std::printf(" %s:%u", s.sensors._buffer[i].name,
                static_cast<unsigned>(s.sensors._buffer[i].status));
  std::printf("\n");
}

// The cloud's size and its points per label: none (0, no object), then labels 1..the largest
// present (a model of K classes: 1..K its classes, K + 1 background, K + 2 unclassified; the
// default model: car, pedestrian, bicyclist, background, unclassified). The cloud carries no
// class names (tracked_objects does).
template <class S>
void print_cloud(const S& s) {
  unsigned by_label[256] = {};
  unsigned top = 0;
  for (std::uint32_t i = 0; i < s.points._length; ++i) {
    const unsigned label = s.points._buffer[i].label;
    ++by_label[label];
    top = std::max(top, label);
  }
  std::printf(
      "point_cloud scan %llu t=%.6f points=%u origin=(%.2f,%.2f,%.2f) resolution=%.3f none=%u "
      "labels=[",
      static_cast<unsigned long long>(s.scan_index), dds::seconds(s.stamp), s.points._length,
      s.origin.x, s.origin.y, s.origin.z, static_cast<double>(s.resolution), by_label[0]);
  for (unsigned label = 1; label <= top; ++label)
    std::printf("%s%u", label == 1 ? "" : ",", by_label[label]);
  std::printf("]\n");
}

// One sample of any topic (native or ROS 2 names), told apart by its fields.
template <class S>
void print_sample(const S& s) {
  if constexpr (requires { s.objects; }) {
    print_tracked(s);
  } else if constexpr (requires { s.segments; }) {
    print_segments(s);
  } else if constexpr (requires { s.points; }) {
    print_cloud(s);
  } else if constexpr (requires { s.stages; }) {
    print_health(s);
  } else {
    print_pose(s);
  }
}

int run_echo(const EchoOptions& o) {
  auto topic = dds::topic_from_suffix(o.topic);
  if (!topic) return fail(topic.error().message);
  auto settings = load_dds_settings(config_path(o.config));
  if (!settings) return fail(settings.error().message);
  dds::PublisherConfig c = *settings;
  override_dds(c, o.domain, o.dds_config);
  auto readers = dds::TopicReaders::create(c);
  if (!readers) return fail(readers.error().message);
  const std::string name = (*readers)->topic_name(*topic);

  // Samples are taken and printed on Cyclone's receive thread as they arrive; this thread waits.
  rt::LatencyHistogram latency(1'000'000'000, 100'000);  // publish -> receive, 10 us bins over 1 s
  std::atomic<int> received = 0;
  const auto on_sample = [&](const auto& sample, dds_time_t now, const dds_sample_info_t& info) {
    if (o.count > 0 && received.load(std::memory_order_relaxed) >= o.count) return;
    latency.add(now - info.source_timestamp);
    print_sample(sample);
    std::fflush(stdout);
    received.fetch_add(1, std::memory_order_release);
  };
  // The topic's QoS with a deeper history: a diagnostic shows every sample, not only the latest.
  auto reader = c.ros2_names ? dds::listen_topic<true>(**readers, *topic, 64, on_sample)
                             : dds::listen_topic<false>(**readers, *topic, 64, on_sample);
  if (!reader) return fail(reader.error().message);
  std::fprintf(stderr, "stac echo: listening on %s (domain %u)\n", name.c_str(), c.domain_id);
  const dds_time_t end = dds_time() + static_cast<dds_duration_t>(o.timeout_s * 1e9);
  while ((o.count == 0 || received.load(std::memory_order_acquire) < o.count) && dds_time() < end)
    dds_sleepfor(DDS_MSECS(10));
  readers->reset();  // no callback runs after this
  if (o.latency && latency.count() > 0) {
    const auto us = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-3; };
    std::fprintf(
        stderr,
        "stac echo: publish -> receive latency over %llu samples: p50 %.0f us, p99 %.0f us, "
        "max %.0f us (writer's source timestamp to this reader's take on arrival, one host "
        "clock)\n",
        static_cast<unsigned long long>(latency.count()), us(latency.percentile(0.5)),
        us(latency.percentile(0.99)), us(latency.max_ns()));
  }
  if (o.count > 0 && received < o.count) {
    std::fprintf(
        stderr,
        "stac echo: timed out after %.1f s with %d of %d samples on %s (is a publisher running "
        "on domain %u with the same dds config?)\n",
        o.timeout_s, received.load(), o.count, name.c_str(), c.domain_id);
    return 1;
  }
  if (received == 0) {
    std::fprintf(
        stderr,
        "stac echo: no sample on %s within %.1f s (is a publisher running on domain %u with "
        "the same dds config?)\n",
        name.c_str(), o.timeout_s, c.domain_id);
    return 1;
  }
  std::fprintf(stderr, "stac echo: %d samples on %s\n", received.load(), name.c_str());
  return 0;
}

}  // namespace

void add_echo_command(CLI::App& app) {
  auto o = std::make_shared<EchoOptions>();
  auto* cmd = app.add_subcommand("echo", "Print the samples arriving on one of STAC's DDS topics");
  cmd->add_option("topic", o->topic, "tracked_objects, segments, ego_pose, health or point_cloud")
      ->required();
  cmd->add_option("--count", o->count, "exit after this many samples (0: run until the timeout)")
      ->check(finite_range(0, 1e12));
  cmd->add_option("--timeout", o->timeout_s, "give up after this many seconds")
      ->check(finite_range(0.001, 1e6));
  cmd->add_option("--domain", o->domain, "DDS domain id (default: dds.domain_id of the config)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->add_option("--dds-config", o->dds_config, "Cyclone DDS XML (default: dds.config_file)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--latency", o->latency,
                "at the end, print the publish -> receive latency (p50, p99, max) of the samples");
  cmd->callback([o] {
    if (const int rc = run_echo(*o); rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace stac::tools

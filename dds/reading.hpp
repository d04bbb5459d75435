// Reading STAC's DDS topics at the edge, shared by `stac echo` and `stac demo`: one participant on
// the configured domain, readers whose samples are taken on Cyclone's receive thread as they
// arrive (a data-available listener: no other thread has to wake up between the sample's arrival
// and its take, which on a loaded machine is where the latency tail was; docs/benchmarks.md), and
// how a tracked object's class is shown.
#pragma once

#include <dds/dds.h>

#include <functional>
#include <list>
#include <memory>
#include <string>

#include "dds/idl_types.hpp"
#include "dds/publisher.hpp"
#include "dds/topics.hpp"
#include "rt/expected.hpp"

namespace stac::dds {

class TopicReaders {
 public:
  // Creates the domain (with config.config_uri when given) and a participant on it. When this
  // process made that domain already, the participant joins it (with the config it was made
  // with), and the TopicReaders that made it must be destroyed last.
  static rt::Result<std::unique_ptr<TopicReaders>> create(const dds::PublisherConfig& config);
  // Deletes the participant and its readers (waits for running callbacks), and the domain when
  // create() made it: its threads must be gone before the process's exit handlers run (with DDS
  // Security, OpenSSL's exit-time cleanup would pull the ground from under them).
  ~TopicReaders();
  TopicReaders(const TopicReaders&) = delete;
  TopicReaders& operator=(const TopicReaders&) = delete;

  // A reader of `t` with the topic's reader QoS (dds::reader_qos) but keep-last `depth`. Each
  // sample is taken as it arrives and passed, as T, to on_sample(const T&, dds_time_t
  // receive_time, const dds_sample_info_t&) on Cyclone's receive thread (one call at a time per
  // reader; until this object is destroyed). Errors name the topic.
  template <class T, class F>
  rt::Result<dds_entity_t> listen(dds::Topic t, int depth, F on_sample);

  // The matched writers of `reader` (0 on error).
  [[nodiscard]] static std::uint32_t matched(dds_entity_t reader) noexcept;
  [[nodiscard]] std::string topic_name(dds::Topic t) const;
  [[nodiscard]] const dds::PublisherConfig& config() const noexcept { return config_; }

 private:
  TopicReaders(const dds::PublisherConfig& config, dds_entity_t domain, dds_entity_t participant)
      : config_(config), domain_(domain), participant_(participant) {}
  // Creates the reader with a data-available listener calling take(reader).
  rt::Result<dds_entity_t> add(dds::Topic t, int depth, std::function<void(dds_entity_t)> take);
  // Takes what `reader` holds now, calling f(sample, receive_time, info) for each valid sample.
  template <class T, class F>
  static void take(dds_entity_t reader, F& f);

  dds::PublisherConfig config_;
  dds_entity_t domain_;  // 0: Cyclone's default domain (no config_uri)
  dds_entity_t participant_;
  std::list<std::function<void(dds_entity_t)>> takers_;  // the listeners' arguments (stable)
};

template <class T, class F>
rt::Result<dds_entity_t> TopicReaders::listen(dds::Topic t, int depth, F on_sample) {
  return add(t, depth,
             [f = std::move(on_sample)](dds_entity_t reader) mutable { take<T>(reader, f); });
}

template <class T, class F>
void TopicReaders::take(dds_entity_t reader, F& f) {
  for (;;) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info{};
    const dds_return_t got = dds_take(reader, samples, &info, 1, 1);
    if (got <= 0) return;  // nothing more (an error here leaves the data for the next call)
    const dds_time_t now = dds_time();
    if (info.valid_data) f(*static_cast<const T*>(samples[0]), now, info);
    dds_return_loan(reader, samples, got);
  }
}

// A reader of topic `t` with the topic's sample type (dds::IdlTypes<Ros2>), each sample passed to
// f as TopicReaders::listen does (`stac echo`, `stac view`).
template <bool Ros2, class F>
rt::Result<dds_entity_t> listen_topic(TopicReaders& readers, Topic t, int depth, F f) {
  using T = IdlTypes<Ros2>;
  switch (t) {  // NOLINT(bugprone-branch-clone): the branches differ in the sample type only
    case Topic::kTrackedObjects:
      return readers.listen<typename T::TrackedObjects>(t, depth, f);
    case Topic::kSegments:
      return readers.listen<typename T::ScanSegments>(t, depth, f);
    case Topic::kEgoPose:
      return readers.listen<typename T::EgoPose>(t, depth, f);
    case Topic::kHealth:
      return readers.listen<typename T::Health>(t, depth, f);
    case Topic::kPointCloud:
      return readers.listen<typename T::LabeledPointCloud>(t, depth, f);
  }
  return rt::make_error("unknown topic");
}

// How a tracked object's class is shown: the name of the first (most probable) entry of its
// classification (the publisher's model's class name, or "background"), or "unknown" when no
// class is more likely than not (probability <= 0.5: log odds all <= 0, as before a classifier
// has seen the track). `name` points into the sample: copy it to keep it.
struct ShownClass {
  const char* name;
  float probability;
};
template <class Object>
ShownClass shown_class(const Object& o) noexcept {
  if (o.classification._length == 0) return {"unknown", 0.0f};
  const auto& c = o.classification._buffer[0];
  return {c.probability > 0.5f ? c.name : "unknown", c.probability};
}

// A ROS time {sec, nanosec} in seconds.
template <class Time>
double seconds(const Time& t) noexcept {
  return static_cast<double>(t.sec) + 1e-9 * static_cast<double>(t.nanosec);
}

}  // namespace stac::dds

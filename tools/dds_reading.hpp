// Reading STAC's DDS topics at the edge, shared by `stac echo` and `stac demo`: one participant on
// the configured domain, readers woken by read conditions on one waitset (no polling, so a
// sample's receive time is when it arrived), and how a tracked object's class is shown.
#pragma once

#include <dds/dds.h>

#include <memory>
#include <string>

#include "dds/publisher.hpp"
#include "dds/topics.hpp"
#include "rt/expected.hpp"

namespace stac::tools {

class TopicReaders {
 public:
  // Creates the domain (with config.config_uri when given) and a participant on it.
  static rt::Result<std::unique_ptr<TopicReaders>> create(const dds::PublisherConfig& config);
  ~TopicReaders();  // deletes the participant and everything in it
  TopicReaders(const TopicReaders&) = delete;
  TopicReaders& operator=(const TopicReaders&) = delete;

  // A reader of `t` with the topic's reader QoS (dds::reader_qos) but keep-last `depth`, attached
  // to the waitset. Errors name the topic.
  rt::Result<dds_entity_t> add(dds::Topic t, int depth);
  // Blocks until a reader has data or `until` (dds_time() clock) has passed.
  void wait_until(dds_time_t until) const;
  // Takes the samples `reader` holds now, calling f(const T& sample, dds_time_t receive_time,
  // const dds_sample_info_t&) for each valid one; returns how many or a Cyclone error.
  template <class T, class F>
  rt::Result<int> take(dds_entity_t reader, F&& f) const;

  // The matched writers of `reader` (0 on error).
  [[nodiscard]] static std::uint32_t matched(dds_entity_t reader) noexcept;
  [[nodiscard]] std::string topic_name(dds::Topic t) const;
  [[nodiscard]] const dds::PublisherConfig& config() const noexcept { return config_; }

 private:
  TopicReaders(const dds::PublisherConfig& config, dds_entity_t participant, dds_entity_t waitset)
      : config_(config), participant_(participant), waitset_(waitset) {}
  dds::PublisherConfig config_;
  dds_entity_t participant_, waitset_;
};

template <class T, class F>
rt::Result<int> TopicReaders::take(dds_entity_t reader, F&& f) const {
  int n = 0;
  for (;;) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info{};
    const dds_return_t got = dds_take(reader, samples, &info, 1, 1);
    if (got < 0) return dds::dds_error("reading DDS", got);
    if (got == 0) return n;
    const dds_time_t now = dds_time();
    if (info.valid_data) {
      f(*static_cast<const T*>(samples[0]), now, info);
      ++n;
    }
    dds_return_loan(reader, samples, got);
  }
}

// A class name: "unknown", "car", "pedestrian", "bicyclist", "background" (IDL labels 0..4).
const char* label_name(unsigned label) noexcept;

// How a tracked object's class is shown: the first (most probable) entry of its classification,
// or "unknown" when no class is more likely than not (probability <= 0.5: log odds all <= 0, as
// before a classifier has seen the track).
struct ShownClass {
  const char* name;
  float probability;
};
template <class Object>
ShownClass shown_class(const Object& o) noexcept {
  if (o.classification._length == 0) return {label_name(0), 0.0f};
  const auto& c = o.classification._buffer[0];
  return {c.probability > 0.5f ? label_name(c.label) : label_name(0), c.probability};
}

// A ROS time {sec, nanosec} in seconds.
template <class Time>
double seconds(const Time& t) noexcept {
  return static_cast<double>(t.sec) + 1e-9 * static_cast<double>(t.nanosec);
}

}  // namespace stac::tools

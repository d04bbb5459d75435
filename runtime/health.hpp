// The health sample of the live component (idl/stac.idl Health; docs/run.md "Health"): drops by
// cause, the inputs' status, the model in use and, for a published scan, where its time went.
// Assembled by the publisher thread into storage of its own (no allocation).
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "dds/idl_types.hpp"
#include "dds/publisher.hpp"
#include "runtime/live.hpp"

namespace stac::runtime {

// The counters of the last published scan's frame (health without a scan repeats them).
struct FrameDrops {
  std::uint64_t segment_overflow = 0, without_pose = 0;
  std::uint64_t pool_overflow = 0, dropped_detections = 0, classes_late = 0;
};

class HealthAssembly {
 public:
  explicit HealthAssembly(Component::Live& live) noexcept : live_(live) {}

  // The last published scan's frame counters.
  void set_frame(const Frame& f) noexcept;
  // Health now: drops by cause and the inputs' status, with this scan's stages (none when no
  // scan is published: the samples of a silent or dead sensor). Valid until the next call.
  [[nodiscard]] dds::HealthIn sample(std::int64_t stamp_ns, std::uint64_t index,
                                     std::span<const dds::StageLatencyIn> stages,
                                     std::int64_t end_to_end_ns) noexcept;

 private:
  Component::Live& live_;
  FrameDrops frame_;
  std::array<dds::DropCountIn, 30> drops_{};
  static_assert(std::tuple_size_v<decltype(drops_)> <= dds::kMaxDrops, "idl/stac.idl's bound");
  std::array<dds::SensorStatusIn, 3> sensors_{};
};

// Microseconds, clamped to the IDL's uint32.
std::uint32_t to_us(std::int64_t ns) noexcept;

}  // namespace stac::runtime

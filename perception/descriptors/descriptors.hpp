// Segment descriptors of STAC chapter 1 (the thesis's 29 descriptor spaces, with the settings of
// the original implementation; docs/descriptors.md): a segment's points are put in a canonical
// frame (PCA of the XY footprint, z kept up), then the oriented bounding box size, 4 whitened
// spin images about the vertical axis and 24 randomly projected HOG descriptors of virtual
// orthographic intensity images (front, side, top) are written into one fixed-size vector.
// Everything is allocated at construction; compute() allocates nothing, never throws.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string_view>

namespace stac::descriptors {

// One segment's points, read in place: point i's x, y, z, intensity are four consecutive floats
// at xyzi + i * stride_bytes (KITTI float4: stride 16; the driver's 32-byte Point: stride 32).
// Sensor frame, metres, z up. The segment is xyzi[indices[k]] when `indices` is non-empty
// (Segments::indices(s) of the Segmenter), else the first `count` records. The caller
// guarantees every index is readable.
struct SegmentView {
  const float* xyzi = nullptr;
  std::size_t stride_bytes = 4 * sizeof(float);
  std::span<const std::uint32_t> indices;
  std::size_t count = 0;  // used only when indices is empty

  [[nodiscard]] std::size_t size() const noexcept {
    return indices.empty() ? count : indices.size();
  }
  void read(std::size_t k, float (&p)[4]) const noexcept {
    const std::size_t i = indices.empty() ? k : indices[k];
    std::memcpy(p, reinterpret_cast<const unsigned char*>(xyzi) + i * stride_bytes, sizeof(p));
  }
  // A hint that point k is read soon (no effect on results).
  void prefetch(std::size_t k) const noexcept {
    const std::size_t i = indices.empty() ? k : indices[k];
    __builtin_prefetch(reinterpret_cast<const unsigned char*>(xyzi) + i * stride_bytes);
  }
};

// The layout is fixed (the thesis's spaces); only capacities and scales are configurable.
struct DescriptorConfig {
  std::size_t max_points = 30000;       // points per segment; beyond: counted, ignored
  std::size_t max_image_px = 256;       // intensity image side capacity (px); larger views are
                                        // cropped about their centre and the lost points counted
  std::size_t min_image_px = 30;        // images are at least this many px on a side (thesis: 30)
  double image_px_per_m = 15.0;         // orthographic intensity image resolution (thesis: 15)
  double intensity_full_scale = 255.0;  // return intensity meaning "full" (driver: 255,
                                        // KITTI reflectance: 1); clamped to [0, 1] of it
  std::uint64_t projection_seed = 20110509;  // seed of the fixed HOG random projections
};

// Empty when the configuration is usable, else what is wrong (start-up checks).
const char* validate(const DescriptorConfig& config) noexcept;

// One named descriptor space: values [offset, offset + size) of Descriptors::values.
struct Space {
  std::string_view name;
  std::size_t offset = 0;
  std::size_t size = 0;
};

inline constexpr std::size_t kSpaceCount = 29;
inline constexpr std::size_t kDimensions = 3 + (100 + 98 + 200 + 50) + 24 * 20;  // 931
inline constexpr std::size_t kHogProjectedDim = 20;

// The 29 spaces in output order (names are stable: models refer to them).
const std::array<Space, kSpaceCount>& spaces() noexcept;  // NOLINT(bugprone-exception-escape)

enum class Status : std::uint8_t {
  kOk,
  kEmpty,  // no finite point: every value is 0
};

struct Descriptors {
  std::array<float, kDimensions> values{};
  Status status = Status::kEmpty;
  std::uint32_t points_used = 0;
  std::uint32_t points_invalid = 0;        // NaN or infinite x, y, z or intensity: skipped
  std::uint32_t points_over_capacity = 0;  // beyond max_points: skipped
  std::uint32_t pixels_cropped = 0;        // point projections outside the image capacity

  [[nodiscard]] std::span<const float> space(std::size_t k) const noexcept {
    return {values.data() + spaces()[k].offset, spaces()[k].size};
  }
};

class DescriptorPipeline {
 public:
  // Throws std::invalid_argument when validate() fails (start-up only).
  explicit DescriptorPipeline(const DescriptorConfig& config);
  DescriptorPipeline(const DescriptorPipeline&) = delete;
  DescriptorPipeline& operator=(const DescriptorPipeline&) = delete;
  DescriptorPipeline(DescriptorPipeline&&) noexcept;
  DescriptorPipeline& operator=(DescriptorPipeline&&) noexcept;
  ~DescriptorPipeline();

  // Overwrites `out` with the descriptors of one segment. No allocation, exception or I/O.
  // NOLINTNEXTLINE(bugprone-exception-escape): see spaces()
  void compute(const SegmentView& segment, Descriptors& out) noexcept;

  // Intermediate results of the last compute() (tests, visualisation). Canonical frame: origin
  // at the centroid, x along the major XY axis, z up; image rows top (max) to bottom.
  struct Image {
    // Row-major, `width` floats a row; 0 where no return. Only the pixels within 1 px of the
    // HOG windows are computed (a large view is mostly outside every window); the others hold
    // whatever an earlier segment left.
    const float* pixels = nullptr;
    std::size_t width = 0, height = 0;
  };
  enum class View : std::uint8_t { kFront = 0, kSide = 1, kTop = 2 };  // along x, y, z
  [[nodiscard]] Image image(View view) const noexcept;
  [[nodiscard]] float yaw() const noexcept;  // of the canonical x axis in the sensor frame (rad)

  [[nodiscard]] const DescriptorConfig& config() const noexcept { return config_; }

 private:
  struct State;
  DescriptorConfig config_;
  std::unique_ptr<State> state_;
};

}  // namespace stac::descriptors

// What differs between HDL-64E models, as data (STYLE rule 6): firing timing, trailer kind and
// whether dual return exists. The decoder reads these once at start-up into its tables.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace stac::velodyne {

enum class Model : std::uint8_t { kS2, kS2_1, kS3 };
enum class TrailerKind : std::uint8_t {
  kSpinCount,  // early S2 firmware: u16 spin count + 4 bytes temperature or "vXXX"
  kGpsStatus,  // S2.1 / S3: u32 microseconds past the hour + status type + status value
};

struct ModelTraits {
  std::string_view name;
  double firing_period_us;                  // between successive firings (block pairs)
  double laser_group_us;                    // between groups of 4 lasers within a firing
  std::array<double, 4> laser_in_group_us;  // offset of laser j%4 within its group
  TrailerKind trailer;
  bool supports_dual_return;
  double packets_per_second_single;  // independent of RPM
  double packets_per_second_dual;
};

// Timing: valgur/velodyne_decoder (REFERENCE §1). The packet stamp marks the FIRST firing of
// the packet: time(point) = stamp + firing*firing_period + group*laser_group + in_group.
inline constexpr ModelTraits kS2Traits{
    "S2", 48.0, 6.0, {0.0, 1.26, 2.46, 3.66}, TrailerKind::kSpinCount, false, 3472.17, 3472.17};
inline constexpr ModelTraits kS21Traits{
    "S2.1", 48.0, 6.0, {0.0, 1.26, 2.46, 3.66}, TrailerKind::kGpsStatus, false, 3472.17, 3472.17};
inline constexpr ModelTraits kS3Traits{
    "S3", 57.6, 7.2, {0.0, 1.3, 2.5, 3.7}, TrailerKind::kGpsStatus, true, 3472.17, 5787.0};

constexpr const ModelTraits& traits(Model m) noexcept {
  switch (m) {
    case Model::kS2:
      return kS2Traits;
    case Model::kS2_1:
      return kS21Traits;
    case Model::kS3:
      break;
  }
  return kS3Traits;
}

// Accepts "S2", "S2.1", "S3" (case-insensitive, "HDL-64E " prefix allowed).
std::optional<Model> parse_model(std::string_view text) noexcept;

// Return type of a point: single return or the strongest of a dual pair, or the last return.
enum class ReturnType : std::uint8_t { kStrongest = 0, kLast = 1 };

}  // namespace stac::velodyne

// What differs between Velodyne models, as data (STYLE rule 6): how a packet's 12 blocks and 32
// channels map to lasers and firing times, the trailer, dual return and the packet rate. The
// decoder, the scan assembler and the simulator read these once at start-up into their tables.
// Formulas and sources: docs/velodyne.md.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace stac::velodyne {

enum class Model : std::uint8_t {
  kS2,    // HDL-64E S2 (early firmware: spin-count trailer)
  kS2_1,  // HDL-64E S2.1
  kS3,    // HDL-64E S3
  kHdl32e,
  kVlp16,
  kPuckLite,   // VLP-16 layout, lighter housing
  kPuckHiRes,  // VLP-16 layout, +-10 deg field of view
  kVlp32c,
};
inline constexpr std::array<Model, 8> kAllModels{Model::kS2,        Model::kS2_1,  Model::kS3,
                                                 Model::kHdl32e,    Model::kVlp16, Model::kPuckLite,
                                                 Model::kPuckHiRes, Model::kVlp32c};

enum class TrailerKind : std::uint8_t {
  kSpinCount,  // early S2 firmware: u16 spin count + 4 bytes temperature or "vXXX"
  kGpsStatus,  // S2.1 / S3: u32 microseconds past the hour + status type + status value
  kFactory,    // HDL-32E, VLP-16, VLP-32C: u32 microseconds past the hour + return mode + product
};

// How the 12 blocks x 32 channels of a packet are fired.
enum class Layout : std::uint8_t {
  kBankPairs,     // HDL-64E: upper (0xEEFF, lasers 0-31) and lower (0xDDFF, 32-63) block of one
                  // firing share a rotation; dual return: 4 blocks per firing
  kOneSequence,   // HDL-32E, VLP-32C: a block is one firing sequence of 32 channels
  kTwoSequences,  // VLP-16: a block is two firing sequences of the 16 lasers (channels 0-15,
                  // 16-31); the second's azimuth is interpolated
};

struct ModelTraits {
  std::string_view name;
  Layout layout;
  int lasers;  // 64, 32 or 16
  // HDL-64E timing (valgur/velodyne_decoder): firing = a pair of blocks.
  double firing_period_us;                  // between successive firings (block pairs)
  double laser_group_us;                    // between groups of 4 lasers within a firing
  std::array<double, 4> laser_in_group_us;  // offset of laser j%4 within its group
  // HDL-32E / VLP timing (the manuals' tables): a firing sequence, and one firing within it.
  double sequence_us;       // between firing sequences
  double channel_us;        // between successive firings of a sequence
  int channels_per_firing;  // lasers fired at once (VLP-32C: 2)
  TrailerKind trailer;
  bool supports_dual_return;
  double packets_per_second_single;  // independent of RPM
  double packets_per_second_dual;
  std::uint8_t product_id;       // byte 1205 of a kFactory packet; 0 = none
  double distance_resolution_m;  // raw distance unit when the calibration does not say
};

// HDL-64E timing: valgur/velodyne_decoder (REFERENCE §1). The packet stamp marks the FIRST firing
// of the packet: time(point) = stamp + firing*firing_period + group*laser_group + in_group.
// An HDL-64E: 2 blocks a firing (4 in dual return), 6 firings a packet.
constexpr ModelTraits hdl64_traits(std::string_view name, double firing_us, double group_us,
                                   std::array<double, 4> in_group_us, TrailerKind trailer,
                                   bool dual, double dual_packets_per_s) {
  return {.name = name,
          .layout = Layout::kBankPairs,
          .lasers = 64,
          .firing_period_us = firing_us,
          .laser_group_us = group_us,
          .laser_in_group_us = in_group_us,
          .sequence_us = 0,
          .channel_us = 0,
          .channels_per_firing = 1,
          .trailer = trailer,
          .supports_dual_return = dual,
          .packets_per_second_single = 3472.17,
          .packets_per_second_dual = dual_packets_per_s,
          .product_id = 0,
          .distance_resolution_m = 0.002};
}
// An HDL-32E / VLP: `sequences` firing sequences of `sequence_us` a packet (single return; dual
// return sends each twice), `channel_us` between firings of `per_firing` lasers.
constexpr ModelTraits factory_traits(std::string_view name, Layout layout, int lasers,
                                     double sequence_us, double channel_us, int per_firing,
                                     int sequences, std::uint8_t product, double resolution_m) {
  return {.name = name,
          .layout = layout,
          .lasers = lasers,
          .firing_period_us = 0,
          .laser_group_us = 0,
          .laser_in_group_us = {},
          .sequence_us = sequence_us,
          .channel_us = channel_us,
          .channels_per_firing = per_firing,
          .trailer = TrailerKind::kFactory,
          .supports_dual_return = true,
          .packets_per_second_single = 1e6 / (sequences * sequence_us),
          .packets_per_second_dual = 2e6 / (sequences * sequence_us),
          .product_id = product,
          .distance_resolution_m = resolution_m};
}

inline constexpr ModelTraits kS2Traits = hdl64_traits(
    "HDL-64E S2", 48.0, 6.0, {0.0, 1.26, 2.46, 3.66}, TrailerKind::kSpinCount, false, 3472.17);
inline constexpr ModelTraits kS21Traits = hdl64_traits(
    "HDL-64E S2.1", 48.0, 6.0, {0.0, 1.26, 2.46, 3.66}, TrailerKind::kGpsStatus, false, 3472.17);
inline constexpr ModelTraits kS3Traits = hdl64_traits("HDL-64E S3", 57.6, 7.2, {0.0, 1.3, 2.5, 3.7},
                                                      TrailerKind::kGpsStatus, true, 5787.0);
// HDL-32E manual: 32 firings 1.152 us apart, a sequence every 46.08 us; 12 sequences a packet.
inline constexpr ModelTraits kHdl32eTraits =
    factory_traits("HDL-32E", Layout::kOneSequence, 32, 46.08, 1.152, 1, 12, 0x21, 0.002);
// VLP-16 manual: 16 firings 2.304 us apart, a sequence every 55.296 us; 24 sequences a packet.
// The Puck LITE shares its product id; the Puck Hi-Res differs in its calibration only.
inline constexpr ModelTraits kVlp16Traits =
    factory_traits("VLP-16", Layout::kTwoSequences, 16, 55.296, 2.304, 1, 24, 0x22, 0.002);
inline constexpr ModelTraits kPuckLiteTraits =
    factory_traits("Puck LITE", Layout::kTwoSequences, 16, 55.296, 2.304, 1, 24, 0x22, 0.002);
inline constexpr ModelTraits kPuckHiResTraits =
    factory_traits("Puck Hi-Res", Layout::kTwoSequences, 16, 55.296, 2.304, 1, 24, 0x24, 0.002);
// VLP-32C manual: lasers fire in pairs 2.304 us apart, a sequence every 55.296 us; 4 mm units.
inline constexpr ModelTraits kVlp32cTraits =
    factory_traits("VLP-32C", Layout::kOneSequence, 32, 55.296, 2.304, 2, 12, 0x28, 0.004);

constexpr const ModelTraits& traits(Model m) noexcept {
  switch (m) {
    case Model::kS2:
      return kS2Traits;
    case Model::kS2_1:
      return kS21Traits;
    case Model::kS3:
      return kS3Traits;
    case Model::kHdl32e:
      return kHdl32eTraits;
    case Model::kVlp16:
      return kVlp16Traits;
    case Model::kPuckLite:
      return kPuckLiteTraits;
    case Model::kPuckHiRes:
      return kPuckHiResTraits;
    case Model::kVlp32c:
      break;
  }
  return kVlp32cTraits;
}

constexpr bool is_hdl64(Model m) noexcept {
  return traits(m).layout == Layout::kBankPairs;
}

// Accepts "S2", "S2.1", "S3" (case-insensitive, "HDL-64E " prefix allowed), "HDL-32E",
// "VLP-16", "Puck LITE", "Puck Hi-Res", "VLP-32C" (with or without dashes and spaces).
std::optional<Model> parse_model(std::string_view text) noexcept;
// The names parse_model accepts, for messages: "S2, S2.1, S3, HDL-32E, VLP-16, ...".
std::string_view model_names() noexcept;

// Firing time (us) of channel j of block b relative to the packet's first firing.
constexpr double firing_time_us(const ModelTraits& t, int b, int j, bool dual) noexcept {
  switch (t.layout) {
    case Layout::kBankPairs: {
      const int firing = b / (dual ? 4 : 2), group = j / 4;  // whole firings and laser groups
      return t.firing_period_us * firing + t.laser_group_us * group +
             t.laser_in_group_us[static_cast<std::size_t>(j % 4)];
    }
    case Layout::kOneSequence: {
      const int sequence = dual ? b / 2 : b, firing = j / t.channels_per_firing;  // whole ones
      return t.sequence_us * sequence + t.channel_us * firing;
    }
    case Layout::kTwoSequences:
      break;
  }
  const int sequence = (dual ? b / 2 : b) * 2 + j / 16;  // two whole sequences a block
  return t.sequence_us * sequence + t.channel_us * (j % 16);
}

// Where between a block's rotation and the next firing's channel j is fired, as a fraction of
// that step: ros-drivers' unpack_vlp16 places every VLP-16 return by its firing time; the other
// layouts give every return of a block the block's rotation.
constexpr double azimuth_fraction_of(const ModelTraits& t, int j) noexcept {
  if (t.layout != Layout::kTwoSequences) return 0.0;
  const int sequence = j / 16;  // the block's first or second
  return (t.sequence_us * sequence + t.channel_us * (j % 16)) / (2.0 * t.sequence_us);
}

// The rotation (0.01 deg) of a channel fired `fraction` of the way from its block's rotation
// to the next firing's, `step` ahead: the same float arithmetic in the decoder and simulator.
inline std::uint16_t interpolated_rotation(std::uint16_t rotation, int step,
                                           float fraction) noexcept {
  const long shifted = rotation + std::lround(static_cast<float>(step) * fraction);
  return static_cast<std::uint16_t>(((shifted % 36000) + 36000) % 36000);
}

// Return type of a point: single return or the strongest of a dual pair, or the last return.
enum class ReturnType : std::uint8_t { kStrongest = 0, kLast = 1 };

// Return-mode byte (1204) of a kFactory packet.
inline constexpr std::uint8_t kReturnStrongest = 0x37, kReturnLast = 0x38, kReturnDual = 0x39;

// What a data packet's bytes say about the sensor that sent it (without trusting them):
//  - the factory bytes (return mode, product id) of an HDL-32E / VLP packet, when every block
//    is an upper-bank block and the return mode is one of the three;
//  - an HDL-64E when any block is a lower-bank (0xDDFF) block (which S2/S2.1/S3 is not told).
struct PacketIdentity {
  enum class Kind : std::uint8_t { kUnknown, kHdl64, kFactory } kind = Kind::kUnknown;
  std::optional<Model> model;  // kFactory with a known product id
  std::uint8_t product_id = 0, return_mode = 0;
};
PacketIdentity identify_packet(std::span<const std::uint8_t> payload) noexcept;

// Whether a packet's identity bytes agree with model `m`: false only when they name another
// model (lower-bank blocks for a 16/32-laser model; for an HDL-64E, or another product id, a
// factory packet); bytes that name nothing (HDL-32E firmware before 2.2.20: zeros) agree.
bool identity_matches(const PacketIdentity& id, Model m) noexcept;

}  // namespace stac::velodyne

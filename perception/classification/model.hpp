// A trained track classifier (segment and holistic grid classifiers, ADBF parameters) and its
// byte format (docs/classification.md, "Model format"). Reading and writing files is the
// caller's (tools/); this library only turns a model into bytes and back. Loading checks the
// magic, version, size, checksum, class count and names (check_class_names) and the descriptor
// layouts the model was trained for, and fails with a message, never undefined behaviour, on
// any bad buffer.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "perception/classification/grid_classifier.hpp"
#include "perception/classification/track_filter.hpp"
#include "rt/expected.hpp"

namespace stac::classification {

struct TrackClassifierModel {
  GridClassifier segment;   // on descriptors::Descriptors::values (segment_layout())
  GridClassifier holistic;  // on HolisticDescriptor (holistic_layout())
  AdbfParams adbf;
  ClassNames classes = default_class_names();  // K names; both classifiers have K classes
};

// The per-scan use of a model (noexcept, no allocation). One segment of a track: its log odds
// H_S into `out`, and the track's evidence updated; false (evidence unchanged) on a wrong size.
[[nodiscard]] bool add_segment(const TrackClassifierModel& model, std::span<const float> segment,
                               TrackEvidence& evidence, LogOdds& out) noexcept;
// A track's log odds by the augmented filter from its evidence and holistic descriptor; false
// (out = the filter without holistic evidence) on a wrong size.
[[nodiscard]] bool track_log_odds(const TrackClassifierModel& model, const TrackEvidence& evidence,
                                  std::span<const float> holistic, LogOdds& out) noexcept;

// The same from the holistic log odds H_H(w) already computed (e.g. from parts, partial()).
[[nodiscard]] LogOdds track_log_odds(const TrackClassifierModel& model,
                                     const TrackEvidence& evidence,
                                     const LogOdds& holistic) noexcept;

// FNV-1a 64 of serialize(model): what health reports as the model in use. Allocates (start-up
// and model loading only).
std::uint64_t model_hash(const TrackClassifierModel& model);

inline constexpr std::uint32_t kModelFormatVersion = 1;
inline constexpr char kModelMagic[8] = {'S', 'T', 'A', 'C', 'C', 'L', 'S', '\0'};

// The layouts a loaded model must have been trained for.
struct ExpectedLayouts {
  Layout segment;
  Layout holistic;
};
ExpectedLayouts build_layouts();  // this build's segment_layout() and holistic_layout()

// `model.classes.size()` must be both classifiers' classes() (else deserialize refuses the bytes).
std::vector<std::uint8_t> serialize(const TrackClassifierModel& model);
rt::Result<TrackClassifierModel> deserialize(std::span<const std::uint8_t> bytes,
                                             const ExpectedLayouts& expected);
inline rt::Result<TrackClassifierModel> deserialize(std::span<const std::uint8_t> bytes) {
  return deserialize(bytes, build_layouts());
}

}  // namespace stac::classification

#include "view/foxglove_messages.hpp"

namespace stac::view {

// The schemas describe the fields these messages fill, with Foxglove's names and types (checked
// against @foxglove/schemas by tests/web/foxglove_view.mjs).
#define STAC_TIME \
  R"({"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}})"
#define STAC_VEC3 \
  R"({"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}})"
#define STAC_QUAT                                                                                        \
  R"({"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},)" \
  R"("w":{"type":"number"}}})"
#define STAC_POSE \
  R"({"type":"object","properties":{"position":)" STAC_VEC3 R"(,"orientation":)" STAC_QUAT "}}"
#define STAC_COLOR                                                                                       \
  R"({"type":"object","properties":{"r":{"type":"number"},"g":{"type":"number"},"b":{"type":"number"},)" \
  R"("a":{"type":"number"}}})"

const char* const kPointCloudSchema =
    R"({"title":"foxglove.PointCloud","type":"object","properties":{"timestamp":)" STAC_TIME
    R"(,"frame_id":{"type":"string"},"pose":)" STAC_POSE
    R"(,"point_stride":{"type":"integer"},"fields":{"type":"array","items":{"type":"object",)"
    R"("properties":{"name":{"type":"string"},"offset":{"type":"integer"},"type":{"type":"integer"}}}},)"
    R"("data":{"type":"string","contentEncoding":"base64"},"scan_index":{"type":"integer"}}})";

const char* const kSceneUpdateSchema =
    R"({"title":"foxglove.SceneUpdate","type":"object","properties":{"deletions":{"type":"array",)"
    R"("items":{"type":"object","properties":{"timestamp":)" STAC_TIME
    R"(,"type":{"type":"integer"},"id":{"type":"string"}}}},"entities":{"type":"array","items":)"
    R"({"type":"object","properties":{"timestamp":)" STAC_TIME
    R"(,"frame_id":{"type":"string"},"id":{"type":"string"},"lifetime":)" STAC_TIME
    R"(,"frame_locked":{"type":"boolean"},"metadata":{"type":"array","items":{"type":"object",)"
    R"("properties":{"key":{"type":"string"},"value":{"type":"string"}}}},)"
    R"("arrows":{"type":"array","items":{"type":"object","properties":{"pose":)" STAC_POSE
    R"(,"shaft_length":{"type":"number"},"shaft_diameter":{"type":"number"},)"
    R"("head_length":{"type":"number"},"head_diameter":{"type":"number"},"color":)" STAC_COLOR
    R"(}}},"cubes":{"type":"array","items":{"type":"object","properties":{"pose":)" STAC_POSE
    R"(,"size":)" STAC_VEC3 R"(,"color":)" STAC_COLOR
    R"(}}},"spheres":{"type":"array"},"cylinders":{"type":"array"},)"
    R"("lines":{"type":"array","items":{"type":"object","properties":{"type":{"type":"integer"},)"
    R"("pose":)" STAC_POSE
    R"(,"thickness":{"type":"number"},"scale_invariant":{"type":"boolean"},"points":{"type":"array",)"
    R"("items":)" STAC_VEC3 R"(},"color":)" STAC_COLOR
    R"(,"colors":{"type":"array"},"indices":{"type":"array"}}}},"triangles":{"type":"array"},)"
    R"("texts":{"type":"array","items":{"type":"object","properties":{"pose":)" STAC_POSE
    R"(,"billboard":{"type":"boolean"},"font_size":{"type":"number"},)"
    R"("scale_invariant":{"type":"boolean"},"color":)" STAC_COLOR
    R"(,"text":{"type":"string"}}}},"models":{"type":"array"}}}}}})";

const char* const kFrameTransformSchema =
    R"({"title":"foxglove.FrameTransform","type":"object","properties":{"timestamp":)" STAC_TIME
    R"(,"parent_frame_id":{"type":"string"},"child_frame_id":{"type":"string"},"translation":)" STAC_VEC3
    R"(,"rotation":)" STAC_QUAT "}}";

const char* const kHealthSchema =
    R"({"title":"stac.Health","type":"object","properties":{"timestamp":)" STAC_TIME
    R"(,"scan_index":{"type":"integer"},"end_to_end_latency_us":{"type":"integer"},)"
    R"("deadline_misses":{"type":"integer"},)"
    R"("stages_us":{"type":"object","additionalProperties":{"type":"integer"}},)"
    R"("drops":{"type":"object","additionalProperties":{"type":"integer"}},)"
    R"("sensors":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},)"
    R"("status":{"type":"integer"},"age_s":{"type":"number"}}}},"model_hash":{"type":"string"},)"
    R"("model_reloads":{"type":"integer"}}})";

#undef STAC_TIME
#undef STAC_VEC3
#undef STAC_QUAT
#undef STAC_POSE
#undef STAC_COLOR

std::string base64(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const auto n = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16 |
                   static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8 |
                   static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[n >> 18];
    out += kAlphabet[(n >> 12) & 63];
    out += kAlphabet[(n >> 6) & 63];
    out += kAlphabet[n & 63];
  }
  if (const std::size_t rest = bytes.size() - i; rest > 0) {
    std::uint32_t n = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16;
    if (rest == 2) n |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8;
    out += kAlphabet[n >> 18];
    out += kAlphabet[(n >> 12) & 63];
    out += rest == 2 ? kAlphabet[(n >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

Rgba class_color(std::string_view name) noexcept {
  if (name == "car") return {0.25, 0.55, 1.0, 1.0};
  if (name == "pedestrian") return {1.0, 0.3, 0.3, 1.0};
  if (name == "bicyclist") return {0.3, 0.9, 0.4, 1.0};
  if (name == "background") return {0.6, 0.6, 0.6, 1.0};
  if (name == "unknown") return {1.0, 1.0, 1.0, 1.0};
  return {1.0, 0.85, 0.2, 1.0};
}

Rgba segment_color(std::uint16_t segment) noexcept {
  if (segment == dds::kNoSegment) return {0.35, 0.35, 0.4, 1.0};  // ground, or in no kept segment
  static constexpr Rgba kPalette[12] = {
      {0.90, 0.30, 0.30, 1}, {0.30, 0.70, 0.95, 1}, {0.95, 0.75, 0.20, 1}, {0.45, 0.85, 0.40, 1},
      {0.80, 0.45, 0.90, 1}, {0.95, 0.55, 0.25, 1}, {0.30, 0.85, 0.75, 1}, {0.95, 0.45, 0.70, 1},
      {0.60, 0.60, 0.95, 1}, {0.75, 0.90, 0.30, 1}, {0.55, 0.40, 0.30, 1}, {0.85, 0.85, 0.85, 1}};
  return kPalette[(segment * 5U) % 12U];
}

}  // namespace stac::view

#include "perception/classification/model.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "perception/classification/holistic.hpp"

namespace stac::classification {
namespace {

// Header: magic (8), version (u32), payload size (u32); then the payload; then its FNV-1a 64.
constexpr std::size_t kHeaderBytes = 16;
constexpr std::size_t kTrailerBytes = 8;
constexpr const char* kRetrain = "; retrain the model for this build (stac train)";
static_assert(kMaxClasses == 8, "kRemakeClasses names the maximum");
constexpr const char* kRemakeClasses =
    "; a model holds 1..8 classes with unique printable names: remake it with stac train from a "
    "dataset whose classes are such (stac dataset --class NAME adds a class)";

class Writer {
 public:
  void u8(std::uint8_t v) { bytes_.push_back(v); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
  void floats(std::span<const float> v) {
    u32(static_cast<std::uint32_t>(v.size()));
    for (const float x : v) f32(x);
  }
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  std::vector<std::uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
};

// Bounded reads: past the end, ok() turns false and every read returns 0.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> b) : b_(b) {}
  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] std::size_t left() const { return ok_ ? b_.size() - at_ : 0; }
  std::uint32_t u32() { return static_cast<std::uint32_t>(take(4)); }
  std::uint64_t u64() { return take(8); }
  float f32() { return std::bit_cast<float>(u32()); }
  // A count of items of `item_bytes` each, refused when the rest of the buffer cannot hold them.
  std::uint32_t count(std::size_t item_bytes) {
    const std::uint32_t n = u32();
    if (ok_ && n > left() / item_bytes) ok_ = false;
    return ok_ ? n : 0;
  }
  std::vector<float> floats() {
    std::vector<float> v(count(4));
    for (auto& x : v) x = f32();
    return v;
  }
  std::string str() {
    const std::uint32_t n = count(1);
    std::string s(reinterpret_cast<const char*>(b_.data()) + (ok_ ? at_ : 0), n);
    at_ += n;
    return s;
  }

 private:
  std::uint64_t take(int n) {
    if (!ok_ || left() < static_cast<std::size_t>(n)) {
      ok_ = false;
      return 0;
    }
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= std::uint64_t{b_[at_ + i]} << (8 * i);
    at_ += static_cast<std::size_t>(n);
    return v;
  }
  std::span<const std::uint8_t> b_;
  std::size_t at_ = 0;
  bool ok_ = true;
};

void write_grid(Writer& w, const GridClassifier& c) {
  const GridModel& m = c.model();
  w.u32(static_cast<std::uint32_t>(m.layout.size()));
  for (const auto& s : m.layout) {
    w.str(s.name);
    w.u32(s.size);
  }
  w.u64(layout_hash(m.layout));
  w.u32(static_cast<std::uint32_t>(m.resolutions.size()));
  for (const auto r : m.resolutions) w.u32(r);
  for (std::size_t k = 0; k < m.classes; ++k) w.f32(m.prior[k]);
  w.floats(m.lower);
  w.floats(m.scale);
  w.floats(m.table);
}

std::string describe(const Layout& l) {
  return std::to_string(l.size()) + " spaces, " + std::to_string(layout_dimensions(l)) +
         " elements";
}

rt::Result<GridClassifier> read_grid(Reader& r, std::size_t classes, const Layout& expected,
                                     const char* which) {
  const std::string what = std::string("model's ") + which + " classifier: ";
  GridModel m;
  m.classes = classes;
  m.layout.resize(r.count(8));
  for (auto& s : m.layout) {
    s.name = r.str();
    s.size = r.u32();
  }
  const std::uint64_t hash = r.u64();
  m.resolutions.resize(r.count(4));
  for (auto& x : m.resolutions) x = r.u32();
  for (std::size_t k = 0; k < classes; ++k) m.prior[k] = r.f32();
  m.lower = r.floats();
  m.scale = r.floats();
  m.table = r.floats();
  if (!r.ok()) return rt::make_error(what + "ends early (corrupt model)");
  if (hash != layout_hash(m.layout))
    return rt::make_error(what + "layout hash does not match its space list (corrupt model)");
  if (m.layout != expected) {
    std::string diff;
    for (std::size_t i = 0; i < m.layout.size() && i < expected.size() && diff.empty(); ++i)
      if (!(m.layout[i] == expected[i]))
        diff = "; space " + std::to_string(i) + " is '" + m.layout[i].name + "' (" +
               std::to_string(m.layout[i].size) + ") in the model, '" + expected[i].name + "' (" +
               std::to_string(expected[i].size) + ") here";
    return rt::make_error(what + "trained for a descriptor layout of " + describe(m.layout) +
                          ", this build computes " + describe(expected) + diff + kRetrain);
  }
  auto c = GridClassifier::create(std::move(m));
  if (!c) return rt::make_error(what + c.error().message + " (corrupt model)");
  return c;
}

}  // namespace

bool add_segment(const TrackClassifierModel& model, std::span<const float> segment,
                 TrackEvidence& evidence, LogOdds& out) noexcept {
  if (!model.segment.classify(segment, out)) return false;
  evidence.add_segment(out, model.segment.model().prior);
  return true;
}

bool track_log_odds(const TrackClassifierModel& model, const TrackEvidence& evidence,
                    std::span<const float> holistic, LogOdds& out) noexcept {
  LogOdds hh{};
  const bool ok = model.holistic.classify(holistic, hh);  // hh = L0_H when not ok
  out = augmented_dbf(evidence, model.holistic.model().prior, hh, model.adbf);
  return ok;
}

LogOdds track_log_odds(const TrackClassifierModel& model, const TrackEvidence& evidence,
                       const LogOdds& holistic) noexcept {
  return augmented_dbf(evidence, model.holistic.model().prior, holistic, model.adbf);
}

ExpectedLayouts build_layouts() {
  return {segment_layout(), holistic_layout()};
}

std::uint64_t model_hash(const TrackClassifierModel& model) {
  return fnv1a64(serialize(model));
}

std::vector<std::uint8_t> serialize(const TrackClassifierModel& model) {
  Writer payload;
  const std::size_t classes = model.classes.size();
  payload.u32(static_cast<std::uint32_t>(classes));
  for (const std::string& name : model.classes) payload.str(name);
  write_grid(payload, model.segment);
  write_grid(payload, model.holistic);
  for (const LogOdds* v : {&model.adbf.alpha, &model.adbf.beta, &model.adbf.gamma})
    for (std::size_t k = 0; k < classes; ++k) payload.f32((*v)[k]);

  Writer out;
  for (const char c : kModelMagic) out.u8(static_cast<std::uint8_t>(c));
  out.u32(kModelFormatVersion);
  out.u32(static_cast<std::uint32_t>(payload.bytes().size()));
  auto& bytes = out.bytes();
  bytes.insert(bytes.end(), payload.bytes().begin(), payload.bytes().end());
  out.u64(fnv1a64(payload.bytes()));
  return std::move(bytes);
}

rt::Result<TrackClassifierModel> deserialize(std::span<const std::uint8_t> bytes,
                                             const ExpectedLayouts& expected) {
  if (bytes.size() < kHeaderBytes + kTrailerBytes)
    return rt::make_error("model is " + std::to_string(bytes.size()) +
                          " bytes, too short for a STAC classifier model (truncated file?)");
  if (std::memcmp(bytes.data(), kModelMagic, sizeof(kModelMagic)) != 0)
    return rt::make_error(
        "not a STAC classifier model (bad magic); give a file written by "
        "stac train");
  Reader header(bytes.subspan(8, 8));
  const std::uint32_t version = header.u32();
  const std::uint32_t payload_size = header.u32();
  if (version != kModelFormatVersion)
    return rt::make_error("model format version " + std::to_string(version) +
                          ", this build reads version " + std::to_string(kModelFormatVersion) +
                          kRetrain);
  const std::size_t expected_size = kHeaderBytes + std::size_t{payload_size} + kTrailerBytes;
  if (bytes.size() != expected_size)
    return rt::make_error("model is " + std::to_string(bytes.size()) + " bytes, its header says " +
                          std::to_string(expected_size) +
                          " (truncated or padded file); copy the model again");
  const auto payload = bytes.subspan(kHeaderBytes, payload_size);
  Reader trailer(bytes.subspan(kHeaderBytes + payload_size));
  if (trailer.u64() != fnv1a64(payload))
    return rt::make_error("model checksum mismatch (corrupt file); copy the model again");

  Reader r(payload);
  TrackClassifierModel model;
  const std::uint32_t class_count = r.u32();
  if (r.ok() && (class_count == 0 || class_count > kMaxClasses))
    return rt::make_error("model has " + std::to_string(class_count) +
                          " classes, this build reads 1.." + std::to_string(kMaxClasses) +
                          kRemakeClasses);
  model.classes.resize(class_count);
  for (std::string& name : model.classes) name = r.str();
  if (!r.ok()) return rt::make_error("model ends early in its class names (corrupt model)");
  if (const std::string bad = check_class_names(model.classes); !bad.empty())
    return rt::make_error("model has " + bad + kRemakeClasses);
  const std::size_t classes = model.classes.size();
  auto segment = read_grid(r, classes, expected.segment, "segment");
  if (!segment) return rt::make_error(segment.error().message);
  auto holistic = read_grid(r, classes, expected.holistic, "holistic");
  if (!holistic) return rt::make_error(holistic.error().message);
  model.segment = std::move(segment).value();
  model.holistic = std::move(holistic).value();
  for (LogOdds* v : {&model.adbf.alpha, &model.adbf.beta, &model.adbf.gamma})
    for (std::size_t k = 0; k < classes; ++k) (*v)[k] = r.f32();  // past K: AdbfParams' 1
  if (!r.ok()) return rt::make_error("model ends early in its filter parameters (corrupt model)");
  if (r.left() != 0)
    return rt::make_error("model has " + std::to_string(r.left()) +
                          " unexpected bytes after its filter parameters (corrupt model)");
  for (const LogOdds* v : {&model.adbf.alpha, &model.adbf.beta, &model.adbf.gamma})
    for (const float x : *v)
      if (!(std::fabs(x) <= 1e4f))
        return rt::make_error(
            "model filter parameter " + std::to_string(x) +
            " is not finite or over 1e4 in magnitude (no fitted filter has one; corrupt?)");
  return model;
}

}  // namespace stac::classification

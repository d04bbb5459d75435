#include "formats/induction_state.hpp"

#include <bit>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "perception/classification/holistic.hpp"
#include "perception/descriptors/descriptors.hpp"

namespace stac::formats {
namespace {

static_assert(std::endian::native == std::endian::little, "the state format is little-endian");
constexpr char kMagic[8] = {'S', 'T', 'A', 'C', 'I', 'N', 'D', '\0'};
constexpr std::size_t kMaxString = 4096;
constexpr std::uint64_t kMaxCount = 100'000'000;

struct Writer {
  std::vector<std::uint8_t> b;
  void bytes(const void* p, std::size_t n) {
    const std::size_t at = b.size();
    b.resize(at + n);
    if (n != 0) std::memcpy(b.data() + at, p, n);
  }
  template <class T>
  void put(const T& v) {
    bytes(&v, sizeof(T));
  }
  void string(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    bytes(s.data(), s.size());
  }
  void floats(const std::vector<float>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    bytes(v.data(), v.size() * sizeof(float));
  }
};

struct Reader {
  std::span<const std::uint8_t> b;
  std::size_t at = 0;
  bool ok = true;
  template <class T>
  T get() {
    T v{};
    if (!ok || b.size() - at < sizeof(T)) {
      ok = false;
      return v;
    }
    std::memcpy(&v, b.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  std::string string() {
    const auto n = get<std::uint32_t>();
    if (!ok || n > kMaxString || b.size() - at < n) {
      ok = false;
      return {};
    }
    std::string s(reinterpret_cast<const char*>(b.data() + at), n);
    at += n;
    return s;
  }
  std::vector<float> floats() {
    const auto n = get<std::uint64_t>();
    if (!ok || n > kMaxCount || (b.size() - at) / sizeof(float) < n) {
      ok = false;
      return {};
    }
    std::vector<float> v(n);
    // An empty vector's data() may be null, which memcpy must not be given even for 0 bytes
    // (found by induction_state_fuzz).
    if (n != 0) std::memcpy(v.data(), b.data() + at, n * sizeof(float));
    at += n * sizeof(float);
    return v;
  }
  // A count of records each at least `min_bytes` long: more than the bytes left can hold is
  // refused before anything is allocated for them (a damaged count with a valid checksum had
  // sized 1.6 GB of records from a 114-byte file).
  std::uint64_t count(std::size_t min_bytes) {
    const auto n = get<std::uint64_t>();
    if (n > kMaxCount || (ok && n > (b.size() - at) / min_bytes)) ok = false;
    return ok ? n : 0;
  }
};

}  // namespace

rt::Status write_induction_state(const std::filesystem::path& dir, const InductionState& s) {
  Writer w;
  w.bytes(kMagic, sizeof(kMagic));
  w.put(kInductionStateVersion);
  w.put(static_cast<std::uint32_t>(descriptors::kDimensions));
  w.put(static_cast<std::uint32_t>(classification::kHolisticDimensions));
  w.put(static_cast<std::uint32_t>(s.classes.size()));
  for (const std::string& c : s.classes) w.string(c);
  w.put(static_cast<std::uint64_t>(s.induction.max_group_size));
  w.put(static_cast<std::uint8_t>(s.induction.dual ? 1 : 0));
  w.put(s.induction.eps_max);
  w.put(static_cast<std::uint64_t>(s.induction.buffer_groups));
  w.put(s.rounds);
  w.put(static_cast<std::uint8_t>(s.reset_pending ? 1 : 0));
  w.put(s.kept_classes);
  w.put(s.answers_applied);
  w.put(static_cast<std::uint64_t>(s.sources.size()));
  for (const InductionSource& src : s.sources) {
    w.string(src.path);
    w.put(static_cast<std::uint8_t>(src.role));
    w.put(static_cast<std::uint8_t>(src.stage));
    w.put(src.dataset_checksum);
  }
  w.put(static_cast<std::uint64_t>(s.labels.size()));
  for (const LabelledTrack& t : s.labels) {
    w.put(t.source);
    w.put(t.track);
    w.put(t.label);
    w.floats(t.segments);
    w.floats(t.holistic);
  }
  w.put(static_cast<std::uint64_t>(s.buffer.size()));
  for (const learning::Group& g : s.buffer) {
    w.put(g.source);
    w.put(g.track);
    w.put(g.first);
    w.put(g.label);
    w.put(g.usefulness);
    w.put(g.margin);
    w.floats(g.segments);
    w.floats(g.holistic);
  }
  w.put(static_cast<std::uint64_t>(s.seen.size()));
  for (const auto& [source, track] : s.seen) w.put(source), w.put(track);
  w.put(static_cast<std::uint8_t>(s.has_model ? 1 : 0));
  if (s.has_model) {
    const std::vector<std::uint8_t> model = classification::serialize(s.model);
    w.put(static_cast<std::uint64_t>(model.size()));
    w.bytes(model.data(), model.size());
  }
  w.put(classification::fnv1a64(w.b));
  return write_file_durably(dir / "state.bin", w.b);
}

rt::Result<InductionState> read_induction_state(const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / "state.bin";
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    return rt::make_error(name + ": missing; start a state with `stac induct --state " +
                          dir.string() + " --classes ...` or `--model FILE`");
  std::ifstream in(file, std::ios::binary);
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                        std::istreambuf_iterator<char>()};
  return parse_induction_state(bytes, name);
}

rt::Result<InductionState> parse_induction_state(std::span<const std::uint8_t> bytes,
                                                 const std::string& name) {
  const auto bad = [&](const std::string& what) {
    return rt::make_error(name + ": " + what +
                          "; the state is damaged: restore the folder from a backup, or start a "
                          "new one (the answers in labels.jsonl can be given again)");
  };
  if (bytes.size() < sizeof(kMagic) + 8 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    return bad("not a stac induction state (bad magic or too short)");
  std::uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  const auto body = std::span(bytes).first(bytes.size() - 8);
  if (classification::fnv1a64(body) != stored)
    return bad("checksum mismatch (truncated or corrupt)");
  Reader r{body, sizeof(kMagic)};
  InductionState s;
  const auto version = r.get<std::uint32_t>();
  if (version < 1 || version > kInductionStateVersion)
    return bad("format version " + std::to_string(version) + ", this build reads 1 to " +
               std::to_string(kInductionStateVersion));
  if (r.get<std::uint32_t>() != descriptors::kDimensions ||
      r.get<std::uint32_t>() != classification::kHolisticDimensions)
    return bad("descriptor dimensions differ from this build's");
  const auto nclasses = r.get<std::uint32_t>();
  if (nclasses > classification::kMaxClasses) return bad("bad class count");
  s.classes.resize(nclasses);
  for (std::string& c : s.classes) c = r.string();
  s.induction.max_group_size = r.get<std::uint64_t>();
  s.induction.dual = r.get<std::uint8_t>() != 0;
  s.induction.eps_max = r.get<double>();
  s.induction.buffer_groups = r.get<std::uint64_t>();
  s.rounds = r.get<std::uint32_t>();
  s.reset_pending = r.get<std::uint8_t>() != 0;
  if (version >= 2) s.kept_classes = r.get<std::uint32_t>();
  s.answers_applied = r.get<std::uint64_t>();
  using Label = classification::ClassIndex;
  constexpr std::size_t kSourceMin = sizeof(std::uint32_t) + 2;  // path length, role, stage
  constexpr std::size_t kLabelMin = sizeof(std::uint32_t) + sizeof(std::uint64_t) + sizeof(Label) +
                                    2 * sizeof(std::uint64_t);  // ..., two float counts
  constexpr std::size_t kGroupMin = 2 * sizeof(std::uint32_t) + sizeof(std::uint64_t) +
                                    sizeof(Label) + 2 * sizeof(double) + 2 * sizeof(std::uint64_t);
  constexpr std::size_t kSeenMin = sizeof(std::uint32_t) + sizeof(std::uint64_t);
  s.sources.resize(r.count(kSourceMin));
  for (InductionSource& src : s.sources) {
    src.path = r.string();
    const auto role = r.get<std::uint8_t>();
    const auto stage = r.get<std::uint8_t>();
    if (role > 2 || stage > 2) r.ok = false;
    src.role = static_cast<SourceRole>(role);
    src.stage = static_cast<ChunkStage>(stage);
    if (version >= 3) src.dataset_checksum = r.get<std::uint64_t>();
  }
  const auto source_ok = [&s](std::uint32_t i) { return i < s.sources.size(); };
  s.labels.resize(r.count(kLabelMin));
  for (LabelledTrack& t : s.labels) {
    t.source = r.get<std::uint32_t>();
    t.track = r.get<std::uint64_t>();
    t.label = r.get<classification::ClassIndex>();
    t.segments = r.floats();
    t.holistic = r.floats();
    if (!source_ok(t.source) ||
        (t.label != classification::kBackground && t.label >= s.classes.size()))
      r.ok = false;
  }
  s.buffer.resize(r.count(kGroupMin));
  for (learning::Group& g : s.buffer) {
    g.source = r.get<std::uint32_t>();
    g.track = r.get<std::uint64_t>();
    g.first = r.get<std::uint32_t>();
    g.label = r.get<classification::ClassIndex>();
    g.usefulness = r.get<double>();
    g.margin = r.get<double>();
    g.segments = r.floats();
    g.holistic = r.floats();
    if (!source_ok(g.source) || (g.label != classification::kBackground &&
                                 g.label != learning::kUninducted && g.label >= s.classes.size()))
      r.ok = false;
  }
  s.seen.resize(r.count(kSeenMin));
  for (auto& [source, track] : s.seen)
    source = r.get<std::uint32_t>(), track = r.get<std::uint64_t>();
  s.has_model = r.get<std::uint8_t>() != 0;
  if (!r.ok) return bad("truncated or inconsistent records");
  if (const std::string wrong = classification::check_class_names(s.classes); !wrong.empty())
    return bad("bad classes: " + wrong);
  if (s.kept_classes >> s.classes.size() != 0 || s.kept_classes == (1u << s.classes.size()) - 1u)
    return bad("bad kept classes (none may be past the classes, and one at least is taught)");
  if (const std::string wrong = learning::validate(s.induction); !wrong.empty())
    return bad("bad settings: " + wrong);
  if (s.has_model) {
    const auto n = r.count(1);
    if (!r.ok || r.b.size() - r.at < n) return bad("truncated model");
    auto model = classification::deserialize(r.b.subspan(r.at, n));
    if (!model) return bad("its model: " + model.error().message);
    if (model->classes != s.classes) return bad("its model's classes differ from the state's");
    s.model = std::move(model).value();
    r.at += n;
  }
  if (r.at != r.b.size()) return bad("trailing bytes");
  return s;
}

bool is_answer_line(const std::string& line) {
  const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
  return !j.is_discarded() && j.is_object() && j.contains("source") && j["source"].is_string() &&
         j.contains("track") && j["track"].is_number_unsigned() && j.contains("label") &&
         j["label"].is_string();
}

bool is_json_line(const std::string& line) {
  return nlohmann::json::accept(line);
}

rt::Status bind_source_dataset(std::vector<InductionSource>& sources, const std::string& path,
                               std::uint64_t checksum) {
  for (InductionSource& src : sources) {
    if (src.path != path) continue;
    if (src.dataset_checksum == 0) {
      src.dataset_checksum = checksum;
    } else if (src.dataset_checksum != checksum) {
      char had[17], has[17];
      std::snprintf(had, sizeof had, "%016llx",
                    static_cast<unsigned long long>(src.dataset_checksum));
      std::snprintf(has, sizeof has, "%016llx", static_cast<unsigned long long>(checksum));
      return rt::make_error(
          path + ": not the dataset this state read there (its tracks.bin's checksum is " + has +
          ", the state read " + had +
          "): it was remade, and the questions and answers, which name its tracks by number, "
          "would fall on other tracks. Give the dataset the state read (restore it), or start a "
          "new state for the new one");
    }
  }
  return {};
}

}  // namespace stac::formats

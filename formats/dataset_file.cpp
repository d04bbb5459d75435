#include "formats/dataset_file.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>

#include "formats/durable_file.hpp"
#include "perception/classification/holistic.hpp"

namespace stac::formats {
namespace {

static_assert(std::endian::native == std::endian::little, "the dataset format is little-endian");

constexpr char kMagic[8] = {'S', 'T', 'A', 'C', 'D', 'S', 'E', 'T'};
constexpr std::size_t kHeaderBytes = 8 + 4 * 4 + 8 * 3;

using classification::ClassIndex;
constexpr std::uint32_t kVersion2 = 2;  // the default classes, labels 0..3 (3: background)
constexpr std::uint32_t kVersion2Background = 3;
constexpr std::uint32_t kVersion3 = 3;           // class names, always labelled
constexpr std::uint32_t kVersion4 = 4;           // labelled or not; no paths or snapshots
constexpr std::size_t kMaxStoredSnapshots = 16;  // what a reader accepts
constexpr std::size_t kMaxStoredSnapshotPoints = 4096;

std::size_t segment_dims() {
  return descriptors::kDimensions;
}
std::size_t holistic_dims() {
  return classification::kHolisticDimensions;
}

void put_bytes(std::vector<std::uint8_t>& b, const void* p, std::size_t n) {
  const std::size_t at = b.size();
  b.resize(at + n);
  if (n != 0) std::memcpy(b.data() + at, p, n);
}
template <class T>
void put(std::vector<std::uint8_t>& b, const T& v) {
  put_bytes(b, &v, sizeof(T));
}
void put_floats(std::vector<std::uint8_t>& b, const std::vector<float>& v) {
  put_bytes(b, v.data(), v.size() * sizeof(float));
}

struct Reader {
  std::span<const std::uint8_t> bytes;
  std::size_t at = 0;
  template <class T>
  bool get(T& v) {
    if (bytes.size() - at < sizeof(T)) return false;
    std::memcpy(&v, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return true;
  }
  bool get_floats(std::vector<float>& v, std::size_t n) {
    if ((bytes.size() - at) / sizeof(float) < n) return false;
    v.resize(n);
    // An empty vector's data() may be null, and memcpy to null is UB even for 0 bytes (fuzzing).
    if (n == 0) return true;
    std::memcpy(v.data(), bytes.data() + at, n * sizeof(float));
    at += n * sizeof(float);
    return true;
  }
};

}  // namespace

std::string source_of(const std::string& capture, const std::string& truth) {
  if (truth.empty()) return capture;
  std::string source = capture;
  source.push_back('\0');
  return source + truth;
}

SourceFiles source_files(const std::string& source) {
  const std::size_t nul = source.find('\0');
  if (nul == std::string::npos) return {source, {}};
  return {source.substr(0, nul), source.substr(nul + 1)};
}

rt::Status write_dataset(const std::filesystem::path& dir, const Dataset& data) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return rt::make_error(dir.string() + ": cannot create the dataset folder (" + ec.message() +
                          ")");
  std::vector<std::uint8_t> b;
  put_bytes(b, kMagic, sizeof(kMagic));
  put(b, kDatasetFormatVersion);
  put(b, static_cast<std::uint32_t>(segment_dims()));
  put(b, static_cast<std::uint32_t>(holistic_dims()));
  put(b, static_cast<std::uint32_t>(data.sources.size()));
  put(b, classification::layout_hash(classification::segment_layout()));
  put(b, classification::layout_hash(classification::holistic_layout()));
  put(b, static_cast<std::uint64_t>(data.tracks.size()));
  const auto put_string = [&b](const std::string& s) {
    put(b, static_cast<std::uint32_t>(s.size()));
    put_bytes(b, s.data(), s.size());
  };
  put(b, static_cast<std::uint32_t>(data.classes.size()));
  for (const std::string& c : data.classes) put_string(c);
  put(b, static_cast<std::uint8_t>(data.labelled ? 1 : 0));
  for (const std::string& s : data.sources) put_string(s);
  nlohmann::json classes = nlohmann::json::object(), segments = nlohmann::json::object(),
                 inconsistent = nlohmann::json::object();
  for (std::size_t c = 0; c <= data.classes.size(); ++c) {
    const char* name = classification::class_name(data.classes, c < data.classes.size()
                                                                    ? static_cast<ClassIndex>(c)
                                                                    : classification::kBackground);
    classes[name] = 0;
    segments[name] = 0;
    inconsistent[name] = 0;
  }
  std::uint64_t total_segments = 0;
  for (const DatasetTrack& t : data.tracks) {
    put(b, t.id);
    put(b, t.source);
    put(b, static_cast<std::uint32_t>(t.label));
    put(b, t.segments);
    put(b, t.off_label_segments);
    put_floats(b, t.segment_rows);
    put_floats(b, t.holistic_rows);
    put(b, static_cast<std::uint32_t>(t.path.size() / 2));
    put_floats(b, t.path);
    put(b, static_cast<std::uint32_t>(t.snapshots.size()));
    for (const TrackSnapshot& snap : t.snapshots) {
      put(b, snap.segment);
      put(b, static_cast<std::uint32_t>(snap.points.size() / 4));
      put_floats(b, snap.points);
    }
    const char* name = classification::class_name(data.classes, t.label);
    classes[name] = classes[name].get<std::uint64_t>() + 1;
    if (!consistent(t)) inconsistent[name] = inconsistent[name].get<std::uint64_t>() + 1;
    segments[name] = segments[name].get<std::uint64_t>() + t.segments;
    total_segments += t.segments;
  }
  const std::uint64_t checksum = classification::fnv1a64(b);
  put(b, checksum);
  // Each file through FILE.tmp, fsynced and renamed (durable_file.hpp): a kill leaves the old
  // dataset or the new one, never a cut tracks.bin. The manifest names the tracks.bin it
  // describes by its checksum (a kill between the two renames leaves it naming the old one).
  if (auto w = write_file_durably(dir / "tracks.bin", b); !w) return w;
  char checksum_hex[17];
  std::snprintf(checksum_hex, sizeof(checksum_hex), "%016llx",
                static_cast<unsigned long long>(checksum));
  // Each source's files by name: {"capture": ..., "truth": ...} (no truth: unlabeled, or a
  // source of an older dataset whose two paths were joined by a space).
  nlohmann::json sources = nlohmann::json::array();
  for (const std::string& source : data.sources) {
    const SourceFiles files = source_files(source);
    nlohmann::json entry = {{"capture", files.capture}};
    if (!files.truth.empty()) entry["truth"] = files.truth;
    sources.push_back(std::move(entry));
  }
  const nlohmann::json manifest = {{"format", "stac-dataset"},
                                   {"tracks_bin_checksum_fnv1a64", checksum_hex},
                                   {"version", kDatasetFormatVersion},
                                   {"labelled", data.labelled},
                                   {"classes", data.classes},
                                   {"sources", sources},
                                   {"tracks", data.tracks.size()},
                                   {"segments", total_segments},
                                   {"tracks_per_class", classes},
                                   {"segments_per_class", segments},
                                   {"inconsistent_tracks_per_class", inconsistent},
                                   {"segment_dimensions", segment_dims()},
                                   {"holistic_dimensions", holistic_dims()}};
  const std::string text = manifest.dump(2) + "\n";
  return write_file_durably(
      dir / "manifest.json",
      std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

rt::Result<Dataset> read_dataset(const std::filesystem::path& dir) {
  const std::filesystem::path bin = dir / "tracks.bin";
  const std::string name = bin.string();
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    // A capture (or a drive's file) where a dataset folder was meant: its dataset goes elsewhere.
    return rt::make_error(dir.string() +
                          ": a file, not a dataset folder; if it is a capture, make its dataset "
                          "with `stac dataset --in " +
                          dir.string() + " --out FOLDER` and give FOLDER here");
  }
  if (!std::filesystem::is_regular_file(bin, ec)) {
    return rt::make_error(name +
                          ": missing; make the dataset with `stac dataset --in RUN.pcap "
                          "--truth RUN.truth.jsonl --out " +
                          dir.string() + "`");
  }
  std::ifstream in(bin, std::ios::binary);
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                        std::istreambuf_iterator<char>()};
  return parse_dataset(bytes, name);
}

rt::Result<Dataset> parse_dataset(std::span<const std::uint8_t> bytes, const std::string& name) {
  const auto bad = [&](const std::string& what) {
    return rt::make_error(name + ": " + what + "; remake it with this build's `stac dataset`");
  };
  if (bytes.size() < kHeaderBytes + 8 || std::memcmp(bytes.data(), kMagic, 8) != 0) {
    return bad("not a stac dataset (bad magic or too short)");
  }
  std::uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  Reader r{std::span(bytes).first(bytes.size() - 8), 8};
  std::uint32_t version = 0, sd = 0, hd = 0, nsources = 0;
  std::uint64_t sh = 0, hh = 0, ntracks = 0;
  r.get(version);
  if (version != kDatasetFormatVersion && version != kVersion2 && version != kVersion3 &&
      version != kVersion4) {
    return bad("format version " + std::to_string(version) + ", this build reads " +
               std::to_string(kVersion2) + " to " + std::to_string(kDatasetFormatVersion));
  }
  if (classification::fnv1a64(r.bytes) != stored)
    return bad("checksum mismatch (truncated or corrupt)");
  r.get(sd), r.get(hd), r.get(nsources), r.get(sh), r.get(hh), r.get(ntracks);
  if (sd != segment_dims() || hd != holistic_dims() ||
      sh != classification::layout_hash(classification::segment_layout()) ||
      hh != classification::layout_hash(classification::holistic_layout())) {
    return bad("descriptor layout differs from this build's");
  }
  Dataset d;
  d.checksum = stored;
  const auto get_string = [&r](std::string& s) {
    std::uint32_t n = 0;
    if (!r.get(n) || r.bytes.size() - r.at < n) return false;
    s.assign(reinterpret_cast<const char*>(r.bytes.data() + r.at), n);
    r.at += n;
    return true;
  };
  if (version != kVersion2) {
    std::uint32_t nclasses = 0;
    if (!r.get(nclasses) || nclasses > classification::kMaxClasses)
      return bad("truncated class list or more than " +
                 std::to_string(classification::kMaxClasses) + " classes");
    d.classes.resize(nclasses);
    for (std::string& c : d.classes)
      if (!get_string(c)) return bad("truncated class list");
    if (const std::string wrong = classification::check_class_names(d.classes); !wrong.empty())
      return bad("bad classes: " + wrong);
  }
  if (version >= kVersion4) {
    std::uint8_t labelled = 0;
    if (!r.get(labelled) || labelled > 1) return bad("truncated or bad header");
    d.labelled = labelled == 1;
  }
  if (nsources > (r.bytes.size() - r.at) / 4) return bad("truncated source list");  // u32 each
  d.sources.resize(nsources);
  for (std::string& s : d.sources)
    if (!get_string(s)) return bad("truncated source list");
  for (std::uint64_t i = 0; i < ntracks; ++i) {
    DatasetTrack t;
    std::uint32_t label = 0;
    if (!r.get(t.id) || !r.get(t.source) || !r.get(label) || !r.get(t.segments) ||
        !r.get(t.off_label_segments))
      return bad("truncated track");
    if (version == kVersion2 && label == kVersion2Background) label = classification::kBackground;
    if ((label >= d.classes.size() && label != classification::kBackground) ||
        t.source >= nsources || t.segments == 0 || t.off_label_segments > t.segments)
      return bad("bad track record");
    t.label = static_cast<ClassIndex>(label);
    if (!r.get_floats(t.segment_rows, std::size_t{t.segments} * sd) ||
        !r.get_floats(t.holistic_rows, std::size_t{t.segments} * hd)) {
      return bad("truncated track descriptors");
    }
    if (version >= kDatasetFormatVersion) {
      std::uint32_t path_points = 0, snapshots = 0;
      if (!r.get(path_points) || (path_points != 0 && path_points != t.segments) ||
          !r.get_floats(t.path, std::size_t{path_points} * 2) || !r.get(snapshots) ||
          snapshots > kMaxStoredSnapshots)
        return bad("truncated or bad track path");
      t.snapshots.resize(snapshots);
      for (TrackSnapshot& snap : t.snapshots) {
        std::uint32_t points = 0;
        if (!r.get(snap.segment) || snap.segment >= t.segments || !r.get(points) ||
            points > kMaxStoredSnapshotPoints ||
            !r.get_floats(snap.points, std::size_t{points} * 4))
          return bad("truncated or bad track snapshot");
      }
    }
    d.tracks.push_back(std::move(t));
  }
  if (r.at != r.bytes.size()) return bad("trailing bytes");
  return d;
}

learning::TrackExample track_example(DatasetTrack t) {
  learning::TrackExample e;
  e.label = t.label;
  e.segments = std::move(t.segment_rows);
  const std::size_t hd = holistic_dims();
  if (t.holistic_rows.size() >= hd)
    e.holistic.assign(t.holistic_rows.end() - static_cast<std::ptrdiff_t>(hd),
                      t.holistic_rows.end());
  return e;
}

rt::Result<Dataset> read_labelled_dataset(const std::filesystem::path& dir,
                                          const std::string& job) {
  auto d = read_dataset(dir);
  if (d && !d->labelled)
    return rt::make_error(dir.string() +
                          ": has no labels (made by `stac dataset` without --truth); " + job +
                          " needs labelled tracks (`stac dataset --truth`)");
  return d;
}

rt::Status append_dataset(Dataset& into, Dataset&& more, const std::string& more_name) {
  if (into.tracks.empty() && into.sources.empty()) {
    into.classes = more.classes;
    into.labelled = more.labelled;
  }
  if (more.labelled != into.labelled)
    return rt::make_error(more_name + ": " + (more.labelled ? "labelled" : "without labels") +
                          ", the other datasets " +
                          (into.labelled ? "labelled" : "without labels") + "; do not mix them");
  if (more.classes != into.classes)
    return rt::make_error(more_name + ": its classes (" + classification::joined(more.classes) +
                          ") differ from the other datasets' (" +
                          classification::joined(into.classes) +
                          "); make every dataset with the same --class options");
  const auto offset = static_cast<std::uint32_t>(into.sources.size());
  for (std::string& s : more.sources) into.sources.push_back(std::move(s));
  for (DatasetTrack& t : more.tracks) {
    t.source += offset;
    into.tracks.push_back(std::move(t));
  }
  return {};
}

std::uint32_t off_label_segments(ClassIndex label, std::span<const SegmentTruth> segments) {
  std::uint32_t off = 0;
  if (label == classification::kBackground) {
    for (const SegmentTruth& s : segments) off += s.object >= 0 ? 1u : 0u;
    return off;
  }
  std::map<std::int64_t, std::uint32_t> votes;  // offline: a track's few objects
  for (const SegmentTruth& s : segments)
    if (s.object >= 0 && s.cls == label) ++votes[s.object];
  std::int64_t own = -1;
  std::uint32_t most = 0;
  for (const auto& [id, v] : votes) {
    if (v > most) {
      most = v;
      own = id;
    }
  }
  for (const SegmentTruth& s : segments) off += own < 0 || s.object != own ? 1u : 0u;
  return off;
}

rt::Status map_classes(Dataset& data, const classification::ClassNames& to,
                       const std::string& name) {
  if (!data.labelled || data.classes == to) {
    data.classes = to;
    return {};
  }
  std::vector<classification::ClassIndex> map(data.classes.size(), classification::kBackground);
  for (std::size_t k = 0; k < to.size(); ++k) {
    const auto it = std::find(data.classes.begin(), data.classes.end(), to[k]);
    if (it == data.classes.end())
      return rt::make_error(name + ": its classes (" + classification::joined(data.classes) +
                            ") lack " + to[k] + "; make it with `stac dataset --class " + to[k] +
                            "`");
    map[static_cast<std::size_t>(it - data.classes.begin())] =
        static_cast<classification::ClassIndex>(k);
  }
  for (DatasetTrack& t : data.tracks)
    if (t.label != classification::kBackground && t.label < map.size()) t.label = map[t.label];
  data.classes = to;
  return {};
}

}  // namespace stac::formats

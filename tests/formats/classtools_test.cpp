// Model and dataset files of the track classifier: round trips, and every bad file refused with
// a message naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "formats/dataset_file.hpp"
#include "formats/model_file.hpp"
#include "perception/classification/holistic.hpp"
#include "perception/learning/track_training.hpp"
#include "rt/splitmix64.hpp"

namespace stac::formats {
namespace {

// An empty folder of this name under the system temp folder.
std::filesystem::path fresh_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

using classification::ClassIndex;

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void write_bytes(const std::filesystem::path& p, const std::vector<std::uint8_t>& b) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

// Tracks whose descriptors are noise shifted by the class: learnable in a few rounds.
Dataset synthetic_dataset(std::size_t tracks) {
  Dataset d;
  d.sources = {"synthetic"};
  rt::SplitMix64 rng(7);
  for (std::size_t i = 0; i < tracks; ++i) {
    DatasetTrack t;
    t.id = i;
    t.label = i % 4 == 3 ? classification::kBackground : static_cast<ClassIndex>(i % 4);
    t.segments = 3;
    const float shift = static_cast<float>(i % 4);
    for (std::size_t k = 0; k < t.segments * descriptors::kDimensions; ++k) {
      t.segment_rows.push_back(shift + static_cast<float>(rng.next() % 1000) / 2000.0f);
    }
    for (std::size_t k = 0; k < t.segments * classification::kHolisticDimensions; ++k) {
      t.holistic_rows.push_back(shift + static_cast<float>(rng.next() % 1000) / 2000.0f);
    }
    d.tracks.push_back(std::move(t));
  }
  return d;
}

classification::TrackClassifierModel trained_model() {
  const Dataset d = synthetic_dataset(40);
  std::vector<learning::TrackExample> ex;
  for (const DatasetTrack& t : d.tracks) {
    ex.push_back(
        {t.label,
         t.segment_rows,
         {t.holistic_rows.end() - static_cast<std::ptrdiff_t>(classification::kHolisticDimensions),
          t.holistic_rows.end()}});
  }
  learning::TrackTrainingConfig c;
  c.segment.rounds = 20;
  c.holistic.rounds = 20;
  auto m = learning::train_track_classifier(ex, classification::default_class_names(),
                                            classification::build_layouts(), c);
  EXPECT_TRUE(m) << m.error().message;
  return std::move(*m);
}

TEST(ModelFile, RoundTripsAndRefusesMissingTruncatedCorruptAndFolders) {
  const auto dir = fresh_dir("stac_model_file");
  const auto path = dir / "m.stac";
  const classification::TrackClassifierModel model = trained_model();
  ASSERT_TRUE(write_model_file(path, model));
  EXPECT_FALSE(std::filesystem::exists(dir / "m.stac.tmp"));
  auto back = read_model_file(path);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(classification::serialize(*back), classification::serialize(model));

  auto missing = read_model_file(dir / "none.stac");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("none.stac"), std::string::npos);
  EXPECT_NE(missing.error().message.find("stac train"), std::string::npos);

  auto folder = read_model_file(dir);
  ASSERT_FALSE(folder);
  EXPECT_NE(folder.error().message.find("folder"), std::string::npos);

  const std::vector<std::uint8_t> bytes = read_bytes(path);
  std::vector<std::uint8_t> half(bytes.begin(),
                                 bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() / 2));
  write_bytes(dir / "half.stac", half);
  std::vector<std::uint8_t> flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x40;
  write_bytes(dir / "flip.stac", flipped);
  std::vector<std::uint8_t> version = bytes;
  version[8] = 99;  // the u32 after the 8-byte magic
  write_bytes(dir / "version.stac", version);
  write_bytes(dir / "empty.stac", {});
  for (const char* name : {"half.stac", "flip.stac", "version.stac", "empty.stac"}) {
    auto r = read_model_file(dir / name);
    ASSERT_FALSE(r) << name;
    EXPECT_NE(r.error().message.find(name), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("retrain"), std::string::npos) << r.error().message;
  }
  EXPECT_FALSE(write_model_file(dir / "no" / "such" / "m.stac", model));
}

// A run's capture and truth are kept apart, spaces in their paths and all, in tracks.bin and in
// manifest.json (issue 47: they were joined by a space, so "a b.pcap c.jsonl" could not be told
// apart); an older dataset's joined source reads back whole.
TEST(DatasetFile, EachSourceKeepsItsCaptureAndTruthApartWhateverTheirNames) {
  const auto dir = fresh_dir("stac_dataset_sources");
  Dataset d = synthetic_dataset(2);
  d.sources = {source_of("drives with space/d 1.pcap", "drives with space/d 1.truth.jsonl"),
               source_of("kitti drive/2011_09_26_drive_0005_sync", ""), "old.pcap old.truth.jsonl"};
  d.tracks[1].source = 2;
  ASSERT_TRUE(write_dataset(dir / "a", d));
  auto back = read_dataset(dir / "a");
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->sources.size(), 3u);
  EXPECT_EQ(source_files(back->sources[0]).capture, "drives with space/d 1.pcap");
  EXPECT_EQ(source_files(back->sources[0]).truth, "drives with space/d 1.truth.jsonl");
  EXPECT_EQ(source_files(back->sources[1]).capture, "kitti drive/2011_09_26_drive_0005_sync");
  EXPECT_EQ(source_files(back->sources[1]).truth, "");
  EXPECT_EQ(source_files(back->sources[2]).capture, "old.pcap old.truth.jsonl");

  std::ifstream manifest_file(dir / "a" / "manifest.json");
  const nlohmann::json sources = nlohmann::json::parse(manifest_file).at("sources");
  ASSERT_EQ(sources.size(), 3u);
  EXPECT_EQ(sources[0], (nlohmann::json{{"capture", "drives with space/d 1.pcap"},
                                        {"truth", "drives with space/d 1.truth.jsonl"}}));
  EXPECT_EQ(sources[1], (nlohmann::json{{"capture", "kitti drive/2011_09_26_drive_0005_sync"}}));
  EXPECT_EQ(sources[2], (nlohmann::json{{"capture", "old.pcap old.truth.jsonl"}}));
  std::filesystem::remove_all(dir);
}

TEST(DatasetFile, RoundTripsAppendsAndRefusesMissingTruncatedAndCorrupt) {
  const auto dir = fresh_dir("stac_dataset_file");
  Dataset d = synthetic_dataset(6);
  d.tracks[2].off_label_segments = 1;  // of 3: inconsistent
  ASSERT_TRUE(write_dataset(dir / "a", d));
  EXPECT_TRUE(std::filesystem::exists(dir / "a" / "manifest.json"));
  auto back = read_dataset(dir / "a");
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->tracks.size(), d.tracks.size());
  for (std::size_t i = 0; i < d.tracks.size(); ++i) {
    EXPECT_EQ(back->tracks[i].id, d.tracks[i].id);
    EXPECT_EQ(back->tracks[i].label, d.tracks[i].label);
    EXPECT_EQ(back->tracks[i].off_label_segments, d.tracks[i].off_label_segments);
    EXPECT_EQ(back->tracks[i].segment_rows, d.tracks[i].segment_rows);
    EXPECT_EQ(back->tracks[i].holistic_rows, d.tracks[i].holistic_rows);
  }
  Dataset both = std::move(*back);
  auto again = read_dataset(dir / "a");
  ASSERT_TRUE(again);
  ASSERT_TRUE(append_dataset(both, std::move(*again), "again"));
  EXPECT_EQ(both.tracks.size(), 12u);
  EXPECT_EQ(both.sources.size(), 2u);
  EXPECT_EQ(both.tracks.back().source, 1u);

  auto missing = read_dataset(dir / "none");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("stac dataset"), std::string::npos);

  // The manifest counts the inconsistent tracks; a record with more off-label segments than
  // segments is refused.
  std::ifstream manifest_file(dir / "a" / "manifest.json");
  const nlohmann::json manifest = nlohmann::json::parse(manifest_file);
  const nlohmann::json& inconsistent = manifest.at("inconsistent_tracks_per_class");
  EXPECT_EQ(inconsistent.at("bicyclist"), 1);  // track 2 (labels are i % 4)
  EXPECT_EQ(inconsistent.at("car"), 0);
  EXPECT_EQ(inconsistent.at("background"), 0);
  Dataset bad = synthetic_dataset(2);
  bad.tracks[1].off_label_segments = 4;
  ASSERT_TRUE(write_dataset(dir / "bad", bad));
  auto refused = read_dataset(dir / "bad");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("bad track record"), std::string::npos)
      << refused.error().message;

  const std::vector<std::uint8_t> bytes = read_bytes(dir / "a" / "tracks.bin");
  std::filesystem::create_directories(dir / "half");
  write_bytes(dir / "half" / "tracks.bin",
              {bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() / 2)});
  std::filesystem::create_directories(dir / "flip");
  std::vector<std::uint8_t> flipped = bytes;
  flipped[bytes.size() / 3] ^= 1;
  write_bytes(dir / "flip" / "tracks.bin", flipped);
  for (const char* name : {"half", "flip"}) {
    auto r = read_dataset(dir / name);
    ASSERT_FALSE(r) << name;
    EXPECT_NE(r.error().message.find((dir / name / "tracks.bin").string()), std::string::npos)
        << r.error().message;
  }
}

// Version 5 keeps what a person looks at when asked about a track (`stac label`): its path and a
// few segments' points; a path that is not one point per segment, or a snapshot of a segment the
// track does not have, is refused.
TEST(DatasetFile, PathsAndSnapshotsRoundTrip) {
  const auto dir = fresh_dir("stac_dataset_snapshots");
  Dataset d = synthetic_dataset(3);
  d.tracks[1].path = {1.0f, 2.0f, 1.5f, 2.25f, 2.0f, 2.5f};
  d.tracks[1].snapshots = {{0, {0.1f, 0.2f, 0.3f, 40.0f}},
                           {2,
                            {-0.5f, 0.0f, 1.2f, 7.0f,  //
                             0.5f, 0.1f, 0.2f, 9.0f}}};
  ASSERT_TRUE(write_dataset(dir / "ok", d));
  auto r = read_dataset(dir / "ok");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->tracks[1].path, d.tracks[1].path);
  ASSERT_EQ(r->tracks[1].snapshots.size(), 2u);
  EXPECT_EQ(r->tracks[1].snapshots[1].segment, 2u);
  EXPECT_EQ(r->tracks[1].snapshots[1].points, d.tracks[1].snapshots[1].points);
  EXPECT_TRUE(r->tracks[0].snapshots.empty());

  Dataset short_path = d;
  short_path.tracks[1].path.resize(4);  // two points for three segments
  ASSERT_TRUE(write_dataset(dir / "short", short_path));
  Dataset past = d;
  past.tracks[1].snapshots[1].segment = 3;  // the track has segments 0..2
  ASSERT_TRUE(write_dataset(dir / "past", past));
  for (const char* name : {"short", "past"}) {
    auto refused = read_dataset(dir / name);
    ASSERT_FALSE(refused) << name;
    EXPECT_NE(refused.error().message.find("bad track"), std::string::npos)
        << refused.error().message;
  }
}

// Version 3 stores the class names, so a dataset can hold a class beyond the default three;
// a version 2 file (no class list: the default three, label 3 background) still reads.
TEST(DatasetFile, ClassNamesRoundTripAndVersion2StillReads) {
  const auto dir = fresh_dir("stac_dataset_classes");
  Dataset d = synthetic_dataset(8);
  d.classes = {"car", "pedestrian", "bicyclist", "pole"};
  d.tracks[5].label = 3;  // a pole
  ASSERT_TRUE(write_dataset(dir / "four", d));
  auto four = read_dataset(dir / "four");
  ASSERT_TRUE(four) << four.error().message;
  EXPECT_EQ(four->classes, d.classes);
  EXPECT_EQ(four->tracks[5].label, 3);
  EXPECT_EQ(four->tracks[3].label, classification::kBackground);
  Dataset three = synthetic_dataset(2);
  auto mixed = append_dataset(three, std::move(*four), "four");
  ASSERT_FALSE(mixed);
  EXPECT_NE(mixed.error().message.find("four: its classes (car, pedestrian, bicyclist, pole)"),
            std::string::npos)
      << mixed.error().message;
  EXPECT_EQ(three.tracks.size(), 2u);  // nothing appended

  // Version 2 of the same tracks: no class list after the header, background labelled 3.
  Dataset v3 = synthetic_dataset(8);
  ASSERT_TRUE(write_dataset(dir / "v3", v3));
  std::vector<std::uint8_t> b = read_bytes(dir / "v3" / "tracks.bin");
  constexpr std::size_t kHeader = 8 + 4 * 4 + 8 * 3;
  constexpr std::size_t kClassList =
      4 + (4 + 3) + (4 + 10) + (4 + 9);  // car, pedestrian, bicyclist
  const auto reseal = [](std::vector<std::uint8_t>& bytes) {
    bytes.resize(bytes.size() - 8);
    const std::uint64_t sum = classification::fnv1a64(bytes);
    for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<std::uint8_t>(sum >> (8 * i)));
  };
  // `bytes` as DATASET/tracks.bin under `name`, read back.
  const auto read_bytes_as = [&dir](const char* name, const std::vector<std::uint8_t>& bytes) {
    std::filesystem::create_directories(dir / name);
    write_bytes(dir / name / "tracks.bin", bytes);
    return read_dataset(dir / name);
  };
  // Version 4: the same without each track's path and snapshot counts (two zero u32s, as these
  // tracks have neither).
  {
    std::size_t at = kHeader + kClassList + 1 + 4 + std::string("synthetic").size();
    for (const DatasetTrack& t : v3.tracks) {
      at += 8 + 4 * 4 + 4 * (t.segment_rows.size() + t.holistic_rows.size());
      ASSERT_EQ(std::vector<std::uint8_t>(b.begin() + static_cast<std::ptrdiff_t>(at),
                                          b.begin() + static_cast<std::ptrdiff_t>(at + 8)),
                std::vector<std::uint8_t>(8, 0));
      b.erase(b.begin() + static_cast<std::ptrdiff_t>(at),
              b.begin() + static_cast<std::ptrdiff_t>(at + 8));
    }
    b[8] = 4;
    reseal(b);
    auto r4 = read_bytes_as("v4bytes", b);
    ASSERT_TRUE(r4) << r4.error().message;
    ASSERT_EQ(r4->tracks.size(), v3.tracks.size());
    EXPECT_EQ(r4->tracks[7].segment_rows, v3.tracks[7].segment_rows);
    EXPECT_TRUE(r4->tracks[7].path.empty());
  }
  // Version 3: the class list, no labelled flag (version 4's byte after it): labelled.
  {
    std::vector<std::uint8_t> b3 = b;
    ASSERT_EQ(b3[kHeader + kClassList], 1);  // labelled
    b3.erase(b3.begin() + static_cast<std::ptrdiff_t>(kHeader + kClassList));
    b3[8] = 3;
    reseal(b3);
    auto r3 = read_bytes_as("v3bytes", b3);
    ASSERT_TRUE(r3) << r3.error().message;
    EXPECT_TRUE(r3->labelled);
    EXPECT_EQ(r3->tracks.size(), v3.tracks.size());
  }
  // Without labels: the flag round-trips, and labelled and unlabeled data do not mix.
  {
    Dataset unl = synthetic_dataset(3);
    unl.labelled = false;
    ASSERT_TRUE(write_dataset(dir / "unl", unl));
    auto r = read_dataset(dir / "unl");
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_FALSE(r->labelled);
    EXPECT_FALSE(read_labelled_dataset(dir / "unl", "stac train"));
    Dataset into = synthetic_dataset(2);
    EXPECT_FALSE(append_dataset(into, std::move(*r), "unl"));
  }
  b.erase(b.begin() + kHeader, b.begin() + kHeader + kClassList + 1);
  b[8] = 2;                                                        // version
  std::size_t at = kHeader + 4 + std::string("synthetic").size();  // the source
  for (const DatasetTrack& t : v3.tracks) {
    if (t.label == classification::kBackground) b[at + 12] = 3;  // after u64 id, u32 source
    at += 8 + 4 * 4 + 4 * (t.segment_rows.size() + t.holistic_rows.size());
  }
  b.resize(b.size() - 8);
  const std::uint64_t h = classification::fnv1a64(b);
  for (int i = 0; i < 8; ++i) b.push_back(static_cast<std::uint8_t>(h >> (8 * i)));
  std::filesystem::create_directories(dir / "v2");
  write_bytes(dir / "v2" / "tracks.bin", b);
  auto v2 = read_dataset(dir / "v2");
  ASSERT_TRUE(v2) << v2.error().message;
  EXPECT_EQ(v2->classes, classification::default_class_names());
  ASSERT_EQ(v2->tracks.size(), v3.tracks.size());
  for (std::size_t i = 0; i < v3.tracks.size(); ++i) {
    EXPECT_EQ(v2->tracks[i].label, v3.tracks[i].label) << i;
    EXPECT_EQ(v2->tracks[i].holistic_rows, v3.tracks[i].holistic_rows) << i;
  }
}

TEST(DatasetConsistency, OffLabelSegmentsFollowTheThesisRule) {
  using S = SegmentTruth;
  const S car5{5, classification::kCar}, car6{6, classification::kCar}, none{};
  const S ped7{7, classification::kPedestrian};
  // A car track on one car: nothing off; over-segmentation (pieces of car 5) is not an error.
  std::vector<S> seg(20, car5);
  EXPECT_EQ(off_label_segments(classification::kCar, seg), 0u);
  // Two segments lost in the background (or under-segmented: no object over half the points)
  // and one on another car (an identity switch): 3 of 20, over 10%.
  seg[3] = none;
  seg[4] = none;
  seg[9] = car6;
  EXPECT_EQ(off_label_segments(classification::kCar, seg), 3u);
  DatasetTrack t;
  t.segments = 20;
  t.off_label_segments = 3;
  EXPECT_FALSE(consistent(t));
  t.off_label_segments = 2;  // exactly 10%: kept
  EXPECT_TRUE(consistent(t));
  // Its own object is the one most segments are on, whichever comes first.
  std::vector<S> switched(10, car6);
  for (int i = 0; i < 4; ++i) switched[static_cast<std::size_t>(i)] = car5;
  EXPECT_EQ(off_label_segments(classification::kCar, switched), 4u);
  // A background track: only segments that are mostly one foreground object are off.
  std::vector<S> bg(10, none);
  bg[0] = ped7;
  EXPECT_EQ(off_label_segments(classification::kBackground, bg), 1u);
  bg[1] = car5;
  EXPECT_EQ(off_label_segments(classification::kBackground, bg), 2u);
  // A pedestrian track whose segments are all of a car has no own object: all off.
  EXPECT_EQ(off_label_segments(classification::kPedestrian, std::vector<S>(5, car5)), 5u);
  EXPECT_EQ(off_label_segments(classification::kCar, {}), 0u);
}

}  // namespace
}  // namespace stac::formats

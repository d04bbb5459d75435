// The resumable state of `stac induct` (docs/learning.md "The state folder"): DIR/state.bin holds
// the classes, the settings, the sources read, the user's labelled tracks, the buffer of groups
// and the current model; it is replaced atomically (written to a temporary file, fsynced, renamed,
// the folder fsynced) once per round, so a kill at any moment loses at most the round in progress.
// The user's answers live in DIR/labels.jsonl, appended and fsynced one line at a time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "formats/durable_file.hpp"
#include "perception/classification/model.hpp"
#include "perception/learning/induction.hpp"
#include "rt/expected.hpp"

namespace stac::formats {

// A dataset folder the state has read, and what it was read as.
enum class SourceRole : std::uint8_t { kUnlabeled = 0, kLabels = 1, kBackground = 2 };

// How far an unlabeled chunk got: a rerun after a kill goes on from there.
enum class ChunkStage : std::uint8_t { kNew = 0, kTrained = 1, kAsked = 2 };

struct InductionSource {
  std::string path;  // as given on the command line
  SourceRole role = SourceRole::kUnlabeled;
  ChunkStage stage = ChunkStage::kNew;  // unlabeled chunks: its round done, its questions asked
  // The checksum of the tracks.bin read there (Dataset::checksum); 0 until first read (and in a
  // state of version 2 or older). Questions and answers name tracks by index, so a dataset remade
  // at the same path is refused rather than read as the same tracks.
  std::uint64_t dataset_checksum = 0;
};

// A track the user labelled (an answer of labels.jsonl with its descriptors).
struct LabelledTrack {
  std::uint32_t source = 0;  // index into InductionState::sources
  std::uint64_t track = 0;   // index of the track in that dataset
  classification::ClassIndex label = classification::kBackground;
  std::vector<float> segments;  // rows of segment descriptors
  std::vector<float> holistic;  // the track's last holistic descriptor
};

struct InductionState {
  classification::ClassNames classes;
  learning::InductionConfig induction;
  std::uint32_t rounds = 0;   // rounds done
  bool reset_pending = true;  // the next training phase restarts H (retrospection)
  // Bit k: class k came with the model the state started from and is kept as it is (neither
  // trained, reset nor asked about) while the added classes are taught (`--add-classes`).
  std::uint32_t kept_classes = 0;
  std::uint64_t answers_applied = 0;  // lines of labels.jsonl taken into `labels`
  std::vector<InductionSource> sources;
  std::vector<LabelledTrack> labels;
  std::vector<learning::Group> buffer;  // Group::source indexes `sources`
  // Tracks the user has answered about (labelled or skipped): never asked again.
  std::vector<std::pair<std::uint32_t, std::uint64_t>> seen;
  bool has_model = false;
  classification::TrackClassifierModel model;
};

// Version 3 added each source's dataset checksum (older states learn it at the next read);
// version 2 added kept_classes (a version 1 state reads as keeping none).
inline constexpr std::uint32_t kInductionStateVersion = 3;

// DIR/state.bin. Errors name the file and say what to do.
rt::Result<InductionState> read_induction_state(const std::filesystem::path& dir);
// The bytes of a state.bin, `name` naming them in errors (read_induction_state; the fuzzing
// harness fuzz/induction_state_fuzz.cpp).
rt::Result<InductionState> parse_induction_state(std::span<const std::uint8_t> bytes,
                                                 const std::string& name);
// Whether a line of labels.jsonl is a whole answer: a JSON object with "source" (a dataset path,
// a string), "track" (its index, an unsigned number) and "label" (a string).
bool is_answer_line(const std::string& line);
// Whether a line is a whole JSON value: a last line that is, but is no answer, was written so by
// a person (not torn by a kill) and is refused, not cut (complete_or_cut_tail).
bool is_json_line(const std::string& line);
rt::Status write_induction_state(const std::filesystem::path& dir, const InductionState& state);

// The dataset read at `path` (its tracks.bin's `checksum`) checked against the source of that path
// among a state's `sources`: an error when the state read other contents there (the dataset was
// remade), naming both checksums and what to do; a source not read before learns the checksum.
rt::Status bind_source_dataset(std::vector<InductionSource>& sources, const std::string& path,
                               std::uint64_t checksum);

}  // namespace stac::formats

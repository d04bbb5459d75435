// candump's ASCII log format (can-utils `candump -l`, replayed by `canplayer`), one frame a line:
//   (1700000000.123456) can0 123#11223344      standard id: 3 hex digits
//   (1700000000.123456) can0 1ABCDEF0#0011     extended id: 8 hex digits (error frames: 0x20000000)
//   (1700000000.123456) can0 123#R             remote frame (optionally R followed by the dlc)
// Bytes may be separated by '.'; an optional trailing direction token (R or T) is accepted.
// Policy: blank lines and CAN FD lines (`##`) are skipped and counted; any other line that does
// not parse stops reading with an error naming the file, the line and what is wrong.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <memory>
#include <string>
#include <string_view>

#include "drivers/can/frame.hpp"
#include "rt/expected.hpp"

namespace stac::can {

enum class CandumpLineKind : std::uint8_t { kFrame, kBlank, kCanFd, kMalformed };

struct CandumpLine {
  CandumpLineKind kind = CandumpLineKind::kMalformed;
  const char* reason = "";     // for kMalformed: what is wrong
  std::string_view interface;  // for kFrame and kCanFd
};

// Parses one line (without its newline). No allocation.
CandumpLine parse_candump_line(std::string_view line, Frame& frame) noexcept;

struct CandumpCounters {
  std::uint64_t lines = 0;
  std::uint64_t frames = 0;
  std::uint64_t blank = 0;
  std::uint64_t can_fd = 0;  // CAN FD frames: not supported, skipped
};

class CandumpReader {
 public:
  static rt::Result<CandumpReader> open(const std::filesystem::path& file);
  // The same over a log's text in memory; `name` stands for the file in messages.
  static CandumpReader from_text(std::string text, const std::string& name);
  // True with the next frame, false at the end of the file, an error for a malformed line.
  rt::Result<bool> next(Frame& frame);
  const CandumpCounters& counters() const noexcept { return counters_; }

 private:
  std::unique_ptr<std::istream> in_;  // the file, or the text
  std::string file_;
  std::string line_;
  CandumpCounters counters_;
};

class CandumpWriter {
 public:
  // `interface` is written on every line (e.g. "can0").
  static rt::Result<CandumpWriter> open(const std::filesystem::path& file, std::string interface);
  // Writes one line in the format above (uppercase hex, microsecond stamps as candump does).
  bool write(const Frame& frame);
  // Flushes and closes; false when anything failed to reach the file.
  bool close();

 private:
  std::ofstream out_;
  std::string interface_;
};

}  // namespace stac::can

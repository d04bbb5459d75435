// An offline job's output on the terminal (offline/job_output.hpp): text on stderr, results on
// stdout, a progress bar per stage on stderr (cleared before anything is printed, drawn again on
// the next step).
#pragma once

#include <optional>

#include "offline/job_output.hpp"
#include "tools/support/progress.hpp"

namespace stac::tools {

class TerminalOutput {
 public:
  TerminalOutput() = default;
  TerminalOutput(const TerminalOutput&) = delete;
  TerminalOutput& operator=(const TerminalOutput&) = delete;
  ~TerminalOutput() { finish(); }

  // Callbacks that print through this object (which must outlive the job).
  offline::JobOutput output();
  // Clears the bar (before the caller prints).
  void finish();

 private:
  std::optional<Progress> progress_;
};

}  // namespace stac::tools

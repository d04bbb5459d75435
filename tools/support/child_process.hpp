// Another `stac` command run as a child process of this one (the same binary, /proc/self/exe),
// its stdout and stderr into a log file. Used by `stac demo` to run `stac run` and `stac replay`
// exactly as a user would, and by `stac label` to run a round. The destructor kills (SIGKILL) and
// reaps a child still running, so no error path leaves one behind; OnParentDeath::kTerminate also
// covers the end no destructor sees (this process killed by SIGKILL).
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::tools {

// What becomes of the child when this process ends without its destructor running.
enum class OnParentDeath {
  kKeepRunning,
  // SIGTERM to the child (Linux PR_SET_PDEATHSIG). Linux sends it when the thread that started
  // the child ends, so start it from a thread that lives as long as the process.
  kTerminate,
};

class ChildProcess {
 public:
  // Starts `stac args...` (this binary); an error when it cannot be started (its errno's text).
  static rt::Result<ChildProcess> start(
      const std::vector<std::string>& args, const std::filesystem::path& log,
      OnParentDeath on_parent_death = OnParentDeath::kKeepRunning);
  // Starts `program args...`, where program is a stac binary named by its path (tests, which
  // are not stac themselves).
  static rt::Result<ChildProcess> start_program(
      const std::filesystem::path& program, const std::vector<std::string>& args,
      const std::filesystem::path& log,
      OnParentDeath on_parent_death = OnParentDeath::kKeepRunning);
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&&) = delete;
  ChildProcess(const ChildProcess&) = delete;
  ~ChildProcess();

  // Its exit code if it has ended (-1: killed by a signal), nullopt while it runs. Never blocks.
  std::optional<int> poll();
  // Waits up to timeout_s for it to end: its exit code, or nullopt if it still runs.
  std::optional<int> wait_for(double timeout_s);
  // Sends `sig`, then waits up to timeout_s; if it still runs, SIGKILL. The exit code (-1: killed).
  int stop(int sig, double timeout_s);
  // Sends `sig` and returns at once; false when it has ended.
  bool signal(int sig);
  // The log's last `lines` lines (what it printed), for error messages.
  [[nodiscard]] std::string log_tail(int lines) const;
  [[nodiscard]] std::string log() const;
  [[nodiscard]] const std::filesystem::path& log_path() const noexcept { return log_; }
  [[nodiscard]] pid_t pid() const noexcept { return pid_; }

 private:
  ChildProcess(pid_t pid, std::filesystem::path log) : pid_(pid), log_(std::move(log)) {}
  pid_t pid_;
  std::optional<int> code_;
  std::filesystem::path log_;
};

}  // namespace stac::tools

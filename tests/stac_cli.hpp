// Runs the real `stac` binary as a user would (tests that define STAC_CLI, its path).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace stac::testing {

struct CliResult {
  int code;
  std::string output;  // stdout and stderr
};

// Runs a shell command line, its stderr into its stdout.
inline CliResult run_shell(const std::string& command) {
  const std::string cmd = command + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof(buf), p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

inline CliResult stac(const std::string& args) {
  return run_shell(std::string(STAC_CLI) + " " + args);
}

// `stac ARGS`, killed after `seconds` (exit code 137) if it has not ended by then.
inline CliResult stac_within(int seconds, const std::string& args) {
  return run_shell("timeout -s KILL " + std::to_string(seconds) + " " + std::string(STAC_CLI) +
                   " " + args);
}

// An empty folder of this name under the system's temp folder (emptied first).
inline std::filesystem::path fresh_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace stac::testing

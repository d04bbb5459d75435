// Runs the real `stac` binary (STAC_CLI, set by the test target) as a user would.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace stac::tools {

struct CliResult {
  int code;
  std::string output;  // stdout and stderr
};

inline CliResult stac(const std::string& args) {
  const std::string cmd = std::string(STAC_CLI) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof(buf), p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace stac::tools

// Runs the real `stac` binary as a user would (its path: stac::testing::stac_cli()).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "test_paths.hpp"

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
  return run_shell(std::string(::stac::testing::stac_cli()) + " " + args);
}

// `stac ARGS`, killed after `seconds` (exit code 137) if it has not ended by then.
inline CliResult stac_within(int seconds, const std::string& args) {
  return run_shell("timeout -s KILL " + std::to_string(seconds) + " " +
                   std::string(::stac::testing::stac_cli()) + " " + args);
}

// An empty folder of this name under the system's temp folder (emptied first).
inline std::filesystem::path fresh_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// A build with AddressSanitizer or ThreadSanitizer (-DSTAC_SANITIZE=...): the pipeline runs 2 to
// 5 times slower there, which assertions on what fits in a time budget must allow for.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitizerBuild = true;
#else
inline constexpr bool kSanitizerBuild = false;
#endif
// How far behind the sensor perception may run in such a build (s): a scan is published up to
// this much later than in a plain build, where it is published within its deadline (0.1 s).
// (Measured under ASan with two tests at a time on 2 cores: up to 0.8 s. A time window shorter
// than this is empty in such a build; the plain build checks it.)
inline constexpr double kSanitizerLagS = kSanitizerBuild ? 0.8 : 0.0;

// The shipped configuration (config/stac.yaml) written into `dir` as stac.yaml, with `edits`
// applied (each a key of a section, as "  key: value", which must be there once) and its relative
// paths (calibration, dbc, model, config_file, velodyne.model_calibrations' files) made absolute,
// since the copy lives elsewhere.
// Returns its path, or an empty path (and why in `*error`) when an edit finds no such key.
inline std::filesystem::path shipped_config_with(
    const std::filesystem::path& dir, const std::vector<std::pair<std::string, std::string>>& edits,
    std::string* error = nullptr) {
  const std::filesystem::path config_dir =
      std::filesystem::path(::stac::testing::source_dir()) / "config";
  std::ifstream in(config_dir / "stac.yaml");
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  for (const auto& [key, value] : edits) {
    const std::regex line("\n  " + key + ":[^\n]*");
    const auto found =
        std::distance(std::sregex_iterator(text.begin(), text.end(), line), std::sregex_iterator());
    if (found != 1) {
      if (error != nullptr)
        *error =
            "config/stac.yaml has '  " + key + ":' " + std::to_string(found) + " times, not once";
      return {};
    }
    text = std::regex_replace(text, line, "\n  " + key + ": " + value);
  }
  std::string out;
  const std::regex path_line(
      R"(^(  (?:calibration|dbc|model|config_file): |    [A-Za-z0-9 .-]+: )([^ #/][^ #]*/[^ #]*)(.*)$)");
  std::istringstream lines(text);
  for (std::string l; std::getline(lines, l);) {
    std::smatch m;
    if (std::regex_match(l, m, path_line))
      l = m[1].str() + (config_dir / m[2].str()).lexically_normal().string() + m[3].str();
    out += l + "\n";
  }
  const auto file = dir / "stac.yaml";
  std::ofstream(file) << out;
  return file;
}

}  // namespace stac::testing

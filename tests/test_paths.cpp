#include "test_paths.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

namespace stac::testing {

namespace {

constexpr const char* kFileName = "stac_test_paths.txt";

[[noreturn]] void fail(const std::string& why) {
  std::fprintf(stderr, "test paths: %s\n", why.c_str());
  std::exit(2);
}

// KEY=VALUE lines of the nearest stac_test_paths.txt above this executable.
std::map<std::string, std::string> read_paths() {
  std::error_code error;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) fail("cannot read /proc/self/exe: " + error.message());
  for (auto dir = exe.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    const auto file = dir / kFileName;
    if (std::filesystem::exists(file)) {
      std::map<std::string, std::string> paths;
      std::ifstream in(file);
      for (std::string line; std::getline(in, line);) {
        const auto eq = line.find('=');
        if (eq != std::string::npos) paths[line.substr(0, eq)] = line.substr(eq + 1);
      }
      paths["BINARY_DIR"] = dir.string();
      return paths;
    }
    if (dir == dir.root_path()) break;
  }
  fail(std::string("no ") + kFileName + " in a folder above " + exe.string() +
       " (run the tests from the build tree they were built in; cmake writes the file)");
}

const char* path(const char* key) {
  static const std::map<std::string, std::string> paths = read_paths();
  const auto it = paths.find(key);
  if (it == paths.end()) fail(std::string(kFileName) + " has no " + key + "= line (re-run cmake)");
  return it->second.c_str();
}

}  // namespace

const char* source_dir() {
  return path("SOURCE_DIR");
}
const char* binary_dir() {
  return path("BINARY_DIR");
}
const char* shared_data_dir() {
  return path("SHARED_DATA_DIR");
}
const char* stac_cli() {
  return path("STAC");
}
const char* stac_node() {
  return path("STAC_NODE");
}
const char* c_subscriber() {
  return path("C_SUBSCRIBER");
}

}  // namespace stac::testing

#include "shared_drives.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "stac_cli.hpp"
#include "test_paths.hpp"

namespace stac::testing {
namespace {

namespace fs = std::filesystem;

std::string hex(std::uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const char c : s) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

// An exclusive flock on PATH, held until destroyed (a killed test releases it too).
class Lock {
 public:
  explicit Lock(const fs::path& path)
      : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ >= 0) ::flock(fd_, LOCK_EX);
  }
  ~Lock() {
    if (fd_ >= 0) ::close(fd_);
  }
  Lock(const Lock&) = delete;
  Lock& operator=(const Lock&) = delete;
  [[nodiscard]] bool held() const { return fd_ >= 0; }

 private:
  int fd_;
};

// BINARY_DIR/test-drives/STAMP, STAMP naming this `stac` (size and modification time); made on
// first use, other stamps' folders (an earlier `stac`'s drives) removed then.
const fs::path& drives_root() {
  static const fs::path root = [] {
    struct stat st {};
    const std::string stac = stac_cli();
    const std::string stamp =
        ::stat(stac.c_str(), &st) == 0
            ? hex(fnv1a(std::to_string(st.st_size) + ":" + std::to_string(st.st_mtim.tv_sec) + "." +
                        std::to_string(st.st_mtim.tv_nsec)))
            : "no-stac";
    const fs::path all = fs::path(binary_dir()) / "test-drives";
    fs::create_directories(all);
    const Lock lock(all / ".lock");
    std::error_code ignored;
    for (const auto& entry : fs::directory_iterator(all, ignored)) {
      if (entry.is_directory() && entry.path().filename() != stamp)
        fs::remove_all(entry.path(), ignored);
    }
    fs::create_directories(all / stamp);
    return all / stamp;
  }();
  return root;
}

// The folder for KEY, made by MAKE(folder) once: "" when it is there, else why not.
Shared once(const std::string& key, const std::function<std::string(const fs::path&)>& make) {
  const fs::path dir = drives_root() / hex(fnv1a(key));
  const Lock lock(dir.string() + ".lock");
  if (!lock.held()) return {"", "cannot open the lock file beside " + dir.string()};
  if (fs::exists(dir / "made")) return {dir.string(), ""};
  fs::remove_all(dir);  // a run killed half-way
  fs::create_directories(dir);
  const std::string error = make(dir);
  if (!error.empty()) return {"", error};
  std::ofstream(dir / "made") << key << "\n";
  return {dir.string(), ""};
}

std::string run(const std::string& args) {
  const CliResult r = stac(args);
  return r.code == 0 ? "" : "stac " + args + " exited " + std::to_string(r.code) + ":\n" + r.output;
}

}  // namespace

Shared shared_run(const std::string& args) {
  return once(args, [&](const fs::path& d) {
    std::string command = args;
    for (auto at = command.find("{out}"); at != std::string::npos; at = command.find("{out}"))
      command.replace(at, 5, d.string());
    return run(command);
  });
}

Shared shared_sim(const std::string& sim_args) {
  const Shared dir =
      shared_run("sim " + sim_args + " --out {out}/drive.pcap --truth {out}/drive.jsonl");
  if (!dir) return dir;
  return {(fs::path(dir.path) / "drive").string(), ""};
}

Shared shared_dataset(const std::string& sim_args, bool with_truth,
                      const std::string& dataset_args) {
  const Shared drive = shared_sim(sim_args);
  if (!drive) return drive;
  const Shared dir = shared_run("dataset --in " + drive.path + ".pcap" +
                                (with_truth ? " --truth " + drive.path + ".jsonl" : "") + " " +
                                dataset_args + " --out {out}/data");
  if (!dir) return dir;
  return {(fs::path(dir.path) / "data").string(), ""};
}

}  // namespace stac::testing

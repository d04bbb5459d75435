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
#include <vector>

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

// An exclusive flock on PATH (waiting for it when WAIT), held until destroyed (a killed test
// releases it too).
class Lock {
 public:
  explicit Lock(const fs::path& path, bool wait = true)
      : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ >= 0 && ::flock(fd_, wait ? LOCK_EX : LOCK_EX | LOCK_NB) != 0) {
      busy_ = true;
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~Lock() {
    if (fd_ >= 0) ::close(fd_);
  }
  Lock(const Lock&) = delete;
  Lock& operator=(const Lock&) = delete;
  [[nodiscard]] bool held() const { return fd_ >= 0; }
  [[nodiscard]] bool busy() const { return busy_; }  // another process holds it (not WAIT)

 private:
  int fd_;
  bool busy_ = false;
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

constexpr const char* kBusy = "busy";  // once(..., false): another test is making it

// The folder for KEY, made by MAKE(folder) once: "" when it is there, else why not. Without WAIT,
// a folder another test is making is left to it (the error kBusy).
Shared once(const std::string& key, const std::function<std::string(const fs::path&)>& make,
            bool wait) {
  const fs::path dir = drives_root() / hex(fnv1a(key));
  const Lock lock(dir.string() + ".lock", wait);
  if (lock.busy()) return {"", kBusy};
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

std::vector<Shared> shared_runs(const std::vector<std::string>& runs) {
  std::vector<Shared> made(runs.size());
  // Those no other test is making first, then the rest, waiting for them: two tests that need the
  // same drives make them side by side instead of one waiting for the other to make them all.
  for (const bool wait : {false, true}) {
    for (std::size_t i = 0; i < runs.size(); ++i) {
      if (wait && made[i].error != kBusy) continue;
      made[i] = once(
          runs[i],
          [&](const fs::path& d) {
            std::string command = runs[i];
            for (auto at = command.find("{out}"); at != std::string::npos;
                 at = command.find("{out}"))
              command.replace(at, 5, d.string());
            return run(command);
          },
          wait);
    }
  }
  return made;
}

Shared shared_run(const std::string& args) {
  return shared_runs({args}).front();
}

std::vector<Shared> shared_sims(const std::vector<std::string>& sims) {
  std::vector<std::string> runs;
  for (const std::string& args : sims)
    runs.push_back("sim " + args + " --out {out}/drive.pcap --truth {out}/drive.jsonl");
  std::vector<Shared> made = shared_runs(runs);
  for (Shared& m : made)
    if (m) m.path = (fs::path(m.path) / "drive").string();
  return made;
}

Shared shared_sim(const std::string& sim_args) {
  return shared_sims({sim_args}).front();
}

std::vector<Shared> shared_datasets(const std::vector<SharedDataset>& datasets) {
  std::vector<std::string> sims;
  for (const SharedDataset& d : datasets) sims.push_back(d.sim_args);
  std::vector<Shared> made = shared_sims(sims);
  std::vector<std::string> runs;
  std::vector<std::size_t> of;  // the dataset each run makes
  for (std::size_t i = 0; i < datasets.size(); ++i) {
    if (!made[i]) continue;
    const std::string& drive = made[i].path;
    runs.push_back("dataset --in " + drive + ".pcap" +
                   (datasets[i].with_truth ? " --truth " + drive + ".jsonl" : "") + " " +
                   datasets[i].dataset_args + " --out {out}/data");
    of.push_back(i);
  }
  const std::vector<Shared> folders = shared_runs(runs);
  for (std::size_t k = 0; k < folders.size(); ++k) {
    made[of[k]] = folders[k];
    if (folders[k]) made[of[k]].path = (fs::path(folders[k].path) / "data").string();
  }
  return made;
}

Shared shared_dataset(const std::string& sim_args, bool with_truth,
                      const std::string& dataset_args) {
  return shared_datasets({{sim_args, with_truth, dataset_args}}).front();
}

}  // namespace stac::testing

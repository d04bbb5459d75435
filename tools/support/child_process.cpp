#include "tools/support/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

extern char** environ;

namespace stac::tools {

rt::Result<ChildProcess> ChildProcess::start(const std::vector<std::string>& args,
                                             const std::filesystem::path& log) {
  return start_program("/proc/self/exe", args, log);
}

rt::Result<ChildProcess> ChildProcess::start_program(const std::filesystem::path& program,
                                                     const std::vector<std::string>& args,
                                                     const std::filesystem::path& log) {
  std::vector<std::string> words{program.string()};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(words.size() + 1);
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  // The child starts with no signal blocked, whatever this thread blocks (`stac label` blocks
  // SIGINT and SIGTERM for its sigwait thread).
  posix_spawnattr_t attr{};
  posix_spawnattr_init(&attr);
  sigset_t none{};
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, &attr, argv.data(), environ);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    return rt::make_error("starting stac" + (args.empty() ? "" : " " + args.front()) + ": " +
                          std::strerror(rc));
  }
  return ChildProcess(pid, log);
}

ChildProcess::ChildProcess(ChildProcess&& other) noexcept
    : pid_(other.pid_), code_(other.code_), log_(std::move(other.log_)) {
  other.pid_ = -1;
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !code_) {
    ::kill(pid_, SIGKILL);
    (void)::waitpid(pid_, nullptr, 0);
  }
}

std::optional<int> ChildProcess::poll() {
  if (code_ || pid_ <= 0) return code_;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (r < 0 && errno == ECHILD) code_ = -1;
  return code_;
}

std::optional<int> ChildProcess::wait_for(double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!poll() && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return code_;
}

bool ChildProcess::signal(int sig) {
  if (poll()) return false;
  return ::kill(pid_, sig) == 0;
}

int ChildProcess::stop(int sig, double timeout_s) {
  if (poll()) return *code_;
  ::kill(pid_, sig);
  if (wait_for(timeout_s)) return *code_;
  ::kill(pid_, SIGKILL);
  int status = 0;
  (void)::waitpid(pid_, &status, 0);
  code_ = -1;
  return -1;
}

std::string ChildProcess::log() const {
  std::ifstream f(log_);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

std::string ChildProcess::log_tail(int lines) const {
  const std::string all = log();
  std::size_t at = all.size();
  if (at > 0 && all[at - 1] == '\n') --at;
  for (int n = 0; n < lines && at != std::string::npos && at > 0; ++n) at = all.rfind('\n', at - 1);
  return at == std::string::npos || at == 0 ? all : all.substr(at + 1);
}

}  // namespace stac::tools

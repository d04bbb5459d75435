#include "tools/support/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
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
                                             const std::filesystem::path& log,
                                             OnParentDeath on_parent_death) {
  return start_program("/proc/self/exe", args, log, on_parent_death);
}

rt::Result<ChildProcess> ChildProcess::start_program(const std::filesystem::path& program,
                                                     const std::vector<std::string>& args,
                                                     const std::filesystem::path& log,
                                                     OnParentDeath on_parent_death) {
  const auto failed = [&](int error) {
    return rt::make_error("starting stac" + (args.empty() ? "" : " " + args.front()) + ": " +
                          std::strerror(error));
  };
  std::vector<std::string> words{program.string()};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(words.size() + 1);
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (out < 0) return failed(errno);
  // The child writes its errno here when it cannot exec; closed on exec, so EOF means started.
  int report[2] = {-1, -1};
  if (::pipe2(report, O_CLOEXEC) != 0) {
    const int error = errno;
    ::close(out);
    return failed(error);
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Only async-signal-safe calls until exec: this process may have other threads.
    // The child starts with no signal blocked, whatever this thread blocks (`stac label` blocks
    // SIGINT and SIGTERM for its sigwait thread).
    sigset_t none{};
    sigemptyset(&none);
    int error = 0;
    if (::sigprocmask(SIG_SETMASK, &none, nullptr) != 0) error = errno;
    if (error == 0 && on_parent_death == OnParentDeath::kTerminate) {
      if (::prctl(PR_SET_PDEATHSIG, SIGTERM) != 0) error = errno;
      // A parent that ended before prctl sent no signal: getppid() is already another process.
      else if (::getppid() != parent)
        error = ESRCH;
    }
    if (error == 0 && (::dup2(out, 1) < 0 || ::dup2(out, 2) < 0)) error = errno;
    if (error == 0) ::execve(argv[0], argv.data(), environ);
    if (error == 0) error = errno;
    (void)!::write(report[1], &error, sizeof error);
    ::_exit(127);
  }
  const int fork_error = errno;
  ::close(out);
  ::close(report[1]);
  if (pid < 0) {
    ::close(report[0]);
    return failed(fork_error);
  }
  int child_error = 0;
  ssize_t n = 0;
  do n = ::read(report[0], &child_error, sizeof child_error);
  while (n < 0 && errno == EINTR);
  ::close(report[0]);
  if (n > 0) {
    (void)::waitpid(pid, nullptr, 0);
    return failed(child_error);
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

#include "rt/scheduling.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <utility>

namespace stac::rt {

Status validate(const ThreadSchedule& s, const std::string& what) {
  if (s.fifo_priority < 0 || s.fifo_priority > 99) {
    return make_error(what + ": SCHED_FIFO priority " + std::to_string(s.fifo_priority) +
                      " is not 0..99");
  }
  if (s.cpu < -1 || s.cpu >= CPU_SETSIZE)
    return make_error(what + ": cpu " + std::to_string(s.cpu) + " is not -1..");
  return {};
}

Status lock_memory() noexcept {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return {};
  const int e = errno;
  return make_error(std::string("mlockall(MCL_CURRENT|MCL_FUTURE) refused (") + std::strerror(e) +
                    "): memory may page-fault; needs CAP_IPC_LOCK or a larger RLIMIT_MEMLOCK "
                    "(ulimit -l unlimited / LimitMEMLOCK=infinity)");
}

Status apply_schedule(const std::string& thread, const ThreadSchedule& s) {
  if (auto v = validate(s, thread); !v) return v;
  std::string refused;
  if (s.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<std::size_t>(s.cpu), &set);
    const int e = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (e != 0) {
      refused = thread + " thread: pinning to cpu " + std::to_string(s.cpu) + " refused (" +
                std::strerror(e) + "): is that CPU in this process's cpuset (nproc, taskset -p)?";
    }
  }
  if (s.fifo_priority > 0) {
    sched_param p{};
    p.sched_priority = s.fifo_priority;
    const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
    if (e != 0) {
      if (!refused.empty()) refused += "; ";
      refused += thread + " thread: SCHED_FIFO priority " + std::to_string(s.fifo_priority) +
                 " refused (" + std::strerror(e) +
                 "): runs SCHED_OTHER; needs CAP_SYS_NICE or RLIMIT_RTPRIO >= the priority "
                 "(LimitRTPRIO=, a container started with --cap-add SYS_NICE)";
    }
  }
  if (!refused.empty()) return make_error(refused);
  return {};
}

Result<CpuLatencyRequest> CpuLatencyRequest::hold(int max_us, const char* device) {
  if (max_us < 0) return make_error("CPU wake-up latency " + std::to_string(max_us) + " us is < 0");
  UniqueFd fd(open(device, O_WRONLY | O_CLOEXEC));
  if (!fd) {
    const int e = errno;
    return make_error(std::string("CPU wake-up latency request: cannot open ") + device + " (" +
                      std::strerror(e) +
                      "): idle CPUs may sleep deeply; needs root (the device is root's, mode 600) "
                      "or a kernel with PM QoS (CONFIG_CPU_IDLE)");
  }
  const std::int32_t value = max_us;
  if (write(fd.get(), &value, sizeof(value)) != static_cast<ssize_t>(sizeof(value))) {
    const int e = errno;
    return make_error(std::string("CPU wake-up latency request: writing ") +
                      std::to_string(max_us) + " us to " + device + " failed (" + std::strerror(e) +
                      ")");
  }
  return CpuLatencyRequest(std::move(fd));
}

Result<int> CpuLatencyRequest::current(const char* device) {
  const UniqueFd fd(open(device, O_RDONLY | O_CLOEXEC));
  if (!fd) {
    const int e = errno;
    return make_error(std::string("cannot open ") + device + " (" + std::strerror(e) + ")");
  }
  std::int32_t value = 0;
  const ssize_t n = read(fd.get(), &value, sizeof(value));
  if (n != static_cast<ssize_t>(sizeof(value)))
    return make_error(std::string(device) + ": not a 4-byte PM QoS value");
  return static_cast<int>(value);
}

void name_thread(const char* name) noexcept {
  (void)pthread_setname_np(pthread_self(), name);
}

}  // namespace stac::rt

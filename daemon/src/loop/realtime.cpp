#include "hystbench/daemon/loop/realtime.hpp"

#include <alloca.h>
#include <linux/capability.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace hystbench::daemon {

namespace {

bool has_cap_ipc_lock() noexcept {
  __user_cap_header_struct header{};
  header.version = _LINUX_CAPABILITY_VERSION_3;
  header.pid = 0;
  __user_cap_data_struct data[_LINUX_CAPABILITY_U32S_3]{};
  if (syscall(SYS_capget, &header, data) != 0) return false;
  return (data[CAP_IPC_LOCK / 32].effective & (1u << (CAP_IPC_LOCK % 32))) != 0;
}

}  // namespace

bool RealtimeStatus::not_permitted() const noexcept { return error == EPERM || error == EACCES; }

std::string RealtimeStatus::describe() const {
  if (ok()) return "ok";
  return std::string(step) + ": " + std::strerror(error);
}

RealtimeStatus set_fifo_priority(int priority) noexcept {
  if (priority < 1 || priority > 99) return {EINVAL, "sched_setscheduler"};
  sched_param param{};
  param.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  return {rc, "sched_setscheduler"};
}

RealtimeStatus set_normal_scheduling() noexcept {
  sched_param param{};
  param.sched_priority = 0;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_OTHER, &param);
  return {rc, "sched_setscheduler"};
}

RealtimeStatus set_timer_slack(long nanoseconds) noexcept {
  if (nanoseconds < 1) return {EINVAL, "prctl(PR_SET_TIMERSLACK)"};
  if (prctl(PR_SET_TIMERSLACK, static_cast<unsigned long>(nanoseconds), 0, 0, 0) != 0) {
    return {errno, "prctl(PR_SET_TIMERSLACK)"};
  }
  return {};
}

RealtimeStatus pin_to_cpu(int cpu) noexcept {
  if (cpu < 0) return {};
  if (cpu >= CPU_SETSIZE) return {EINVAL, "pthread_setaffinity_np"};
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
  return {rc, "pthread_setaffinity_np"};
}

RealtimeStatus lock_memory() noexcept {
  // Without CAP_IPC_LOCK, MCL_FUTURE would make every allocation past RLIMIT_MEMLOCK fail later
  // (malloc, thread stacks): refuse up front unless the limit cannot bite.
  rlimit limit{};
  const bool unlimited = getrlimit(RLIMIT_MEMLOCK, &limit) == 0 && limit.rlim_cur == RLIM_INFINITY;
  if (!unlimited && !has_cap_ipc_lock()) return {EPERM, "mlockall"};
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) return {errno, "mlockall"};
  return {};
}

RealtimeStatus unlock_memory() noexcept {
  if (munlockall() != 0) return {errno, "munlockall"};
  return {};
}

void prefault_stack(std::size_t bytes) noexcept {
  constexpr std::size_t kPage = 4096;
  constexpr std::size_t kMax = std::size_t{4} << 20;  // stays well inside an 8 MiB stack
  if (bytes > kMax) bytes = kMax;
  auto* area = static_cast<volatile unsigned char*>(alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += kPage) area[i] = 0;
}

RealtimeReport apply_realtime(const RealtimeOptions& options) noexcept {
  RealtimeReport report;
  set_timer_slack(1);  // best effort: only matters when SCHED_FIFO is not granted
  if (options.fifo) report.scheduling = set_fifo_priority(options.priority);
  report.affinity = pin_to_cpu(options.cpu);
  if (options.lock_memory) {
    report.memory = lock_memory();
    if (report.memory.ok()) prefault_stack();
  }
  return report;
}

std::string RealtimeReport::summary(const RealtimeOptions& requested) const {
  std::string s = "real-time: ";
  if (simulated_clock) {
    s += "simulated clock: SCHED_FIFO and memory lock not taken (the loop runs free during runs)";
    if (requested.cpu >= 0) {
      s += ", cpu " + std::to_string(requested.cpu) + " " + affinity.describe();
    }
    if (degraded()) s += " (running degraded)";
    return s;
  }
  if (requested.fifo) {
    s += "SCHED_FIFO " + std::to_string(requested.priority) + " " + scheduling.describe();
  } else {
    s += "SCHED_FIFO not requested";
  }
  if (requested.cpu >= 0) s += ", cpu " + std::to_string(requested.cpu) + " " + affinity.describe();
  s += requested.lock_memory ? ", memory lock " + memory.describe() : ", memory not locked";
  if (degraded()) s += " (running degraded)";
  return s;
}

}  // namespace hystbench::daemon

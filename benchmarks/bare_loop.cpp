// hystbench-bare-loop: the floor for the loop's wake-up latency -- a bare clock_nanosleep
// (TIMER_ABSTIME) loop at a fixed rate, with the daemon's timer slack (1 ns) and optionally
// SCHED_FIFO, nothing else. Prints one JSON line:
//   {"rate_hz":..,"fifo":true|false,"fifo_granted":..,"ticks":..,"p50_ns":..,"p99_ns":..,
//    "max_ns":..,"overruns":..}
// usage: hystbench-bare-loop RATE_HZ SECONDS [--fifo]
#include <sched.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace {

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s RATE_HZ SECONDS [--fifo]\n", argv[0]);
    return 2;
  }
  const double rate = std::atof(argv[1]), seconds = std::atof(argv[2]);
  const bool fifo = argc > 3 && std::strcmp(argv[3], "--fifo") == 0;
  if (!(rate > 0) || !(seconds > 0)) return 2;
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  bool granted = false;
  if (fifo) {
    sched_param sp{};
    sp.sched_priority = 80;
    granted = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
  }
  const std::int64_t period = static_cast<std::int64_t>(1e9 / rate);
  const auto ticks = static_cast<std::size_t>(rate * seconds);
  std::vector<std::int64_t> late;
  late.reserve(ticks);
  std::uint64_t overruns = 0;
  std::int64_t next = now_ns() + period;
  for (std::size_t k = 0; k < ticks; ++k) {
    timespec ts{static_cast<time_t>(next / 1'000'000'000), static_cast<long>(next % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
    }
    const std::int64_t wake = now_ns();
    late.push_back(wake - next);
    next += period;
    if (wake >= next) {  // missed the next deadline: skip to the following one, as the loop does
      ++overruns;
      next += ((wake - next) / period + 1) * period;
    }
  }
  std::sort(late.begin(), late.end());
  auto q = [&](double p) { return late[static_cast<std::size_t>(p * (late.size() - 1))]; };
  std::printf(
      "{\"rate_hz\":%g,\"fifo\":%s,\"fifo_granted\":%s,\"ticks\":%zu,\"p50_ns\":%lld,"
      "\"p99_ns\":%lld,\"max_ns\":%lld,\"overruns\":%llu}\n",
      rate, fifo ? "true" : "false", granted ? "true" : "false", late.size(),
      static_cast<long long>(q(0.5)), static_cast<long long>(q(0.99)),
      static_cast<long long>(late.back()), static_cast<unsigned long long>(overruns));
  return 0;
}

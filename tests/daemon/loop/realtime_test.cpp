#include "hystbench/daemon/loop/realtime.hpp"

#include <alloca.h>
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/resource.h>

#include <cerrno>
#include <iostream>
#include <thread>

namespace hd = hystbench::daemon;

TEST(Realtime, FifoPriorityIsAppliedOrReportedNotPermitted) {
  EXPECT_EQ(hd::set_fifo_priority(0).error, EINVAL);
  EXPECT_EQ(hd::set_fifo_priority(100).error, EINVAL);
  std::thread t([] {
    const auto st = hd::set_fifo_priority(10);
    EXPECT_TRUE(st.ok() || st.not_permitted()) << st.describe();
    if (st.ok()) {
      int policy = 0;
      sched_param param{};
      pthread_getschedparam(pthread_self(), &policy, &param);
      EXPECT_EQ(policy, SCHED_FIFO);
      EXPECT_EQ(param.sched_priority, 10);
      EXPECT_TRUE(hd::set_normal_scheduling().ok());
      pthread_getschedparam(pthread_self(), &policy, &param);
      EXPECT_EQ(policy, SCHED_OTHER);
    } else {
      EXPECT_NE(st.describe().find("sched_setscheduler"), std::string::npos);
    }
  });
  t.join();
}

TEST(Realtime, TimerSlackIsSetForTheCallingThread) {
  EXPECT_EQ(hd::set_timer_slack(0).error, EINVAL);
  std::thread t([] {
    ASSERT_TRUE(hd::set_timer_slack(1).ok());
    EXPECT_EQ(prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0), 1);
  });
  t.join();
}

TEST(Realtime, AffinityPinsTheCallingThread) {
  EXPECT_TRUE(hd::pin_to_cpu(-1).ok());
  EXPECT_EQ(hd::pin_to_cpu(100000).error, EINVAL);
  std::thread t([] {
    ASSERT_TRUE(hd::pin_to_cpu(0).ok());
    EXPECT_EQ(sched_getcpu(), 0);
  });
  t.join();
}

TEST(Realtime, ApplyReportsEachStepAndSaysWhenDegraded) {
  std::thread t([] {
    const hd::RealtimeOptions options{true, 20, 0, true};
    const auto report = hd::apply_realtime(options);
    const std::string line = report.summary(options);
    std::cout << "[ measure  ] " << line << "\n";
    EXPECT_NE(line.find("SCHED_FIFO 20"), std::string::npos);
    EXPECT_EQ(report.degraded(), line.find("running degraded") != std::string::npos);
    EXPECT_TRUE(report.affinity.ok());
    hd::set_normal_scheduling();
    if (report.memory.ok()) {
      EXPECT_TRUE(hd::unlock_memory().ok());
    }
  });
  t.join();
  const auto nothing = hd::apply_realtime({false, 80, -1, false});
  EXPECT_FALSE(nothing.degraded());
}

namespace {

long minor_faults_of_this_thread() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return u.ru_minflt;
}

// Touches `bytes` of stack below the caller, one write per page; returns the minor page faults
// that took.
[[gnu::noinline]] long faults_touching_stack(std::size_t bytes) {
  const long before = minor_faults_of_this_thread();
  auto* area = static_cast<volatile unsigned char*>(alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += 4096) area[i] = 1;
  return minor_faults_of_this_thread() - before;
}

// In a fresh thread (its stack not yet touched): the page faults of touching 1 MiB of stack,
// after prefaulting `prefault` bytes (0: none).
long faults_after_prefault(std::size_t prefault) {
  long faults = -1;
  std::thread t([&] {
    if (prefault > 0) hd::prefault_stack(prefault);
    faults = faults_touching_stack(std::size_t{1} << 20);
  });
  t.join();
  return faults;
}

}  // namespace

// The loop thread prefaults its stack so that a deep call in a tick takes no page fault: after
// it, touching the stack again faults no more (256 pages of a fresh stack fault without it).
TEST(Realtime, PrefaultedStackTakesNoPageFaults) {
  const long cold = faults_after_prefault(0);
  if (cold < 128) {
    GTEST_SKIP() << "touching 256 fresh stack pages took " << cold
                 << " faults here (huge pages back the stack): nothing to measure";
  }
  EXPECT_LT(faults_after_prefault(std::size_t{2} << 20), 16) << "without prefault: " << cold;
  // A request beyond the stack's bound is clamped to it rather than overflowing the stack.
  std::thread t([] { hd::prefault_stack(std::size_t{64} << 20); });
  t.join();
}

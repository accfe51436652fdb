// identify's diagnoses run beside the verification: the one taken is the one computed ahead
// when it is ready, waited for when it is running, run on the caller's thread otherwise (without
// waiting for the worker); the rest stop, once the verification has chosen (focus) only the chosen
// one runs, and a diagnosis that throws reaches the caller.
#include "runs/details/diagnosis_ahead.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

namespace hd = hystbench::daemon::details;
namespace hc = hystbench::compensation;

namespace {

// A diagnosis that names the candidate it was made for.
hc::Diagnosis marked(std::size_t candidate) {
  hc::Diagnosis d;
  d.verdict = "candidate " + std::to_string(candidate);
  return d;
}

// A diagnosis that reports progress until it is cancelled, which it notes.
[[noreturn]] void work_until_cancelled(const hd::DiagnosisAhead::Progress& progress,
                                       std::atomic<bool>& cancelled) {
  try {
    for (;;) {
      progress(0.5, "working");
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  } catch (...) {
    cancelled = true;
    throw;
  }
}

// Candidate 0's diagnosis notes that it started, then works until cancelled; the others pass.
void zero_works_until_cancelled(std::size_t candidate, const hd::DiagnosisAhead::Progress& progress,
                                std::atomic<bool>& started, std::atomic<bool>& cancelled) {
  if (candidate != 0) return;
  started = true;
  work_until_cancelled(progress, cancelled);
}

void wait_until(const std::function<bool()>& done) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!done() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(done());
}

}  // namespace

// The worker diagnoses on one thread: the loop plays the verification on the other core.
TEST(DiagnosisAhead, TheOneReadyIsTakenWithoutRunningItAgain) {
  std::atomic<int> runs[3] = {0, 0, 0};
  std::atomic<std::size_t> widest{0};
  hd::DiagnosisAhead ahead(
      [&](std::size_t i, const hd::DiagnosisAhead::Controls& controls) {
        ++runs[i];
        widest = std::max<std::size_t>(widest, controls.threads == 0 ? 1000 : controls.threads);
        return marked(i);
      },
      {0, 1, 2});
  wait_until([&] { return runs[2].load() == 1; });
  const auto taken = ahead.take(1, nullptr);
  EXPECT_EQ(taken.diagnosis.verdict, "candidate 1");
  EXPECT_EQ(taken.how, "during the verification");
  EXPECT_EQ(runs[0].load() + runs[1].load() + runs[2].load(), 3);
  EXPECT_EQ(widest.load(), 1U);
}

// The worker is inside candidate 0's diagnosis, between two progress reports; taking candidate 1
// diagnoses it at once on the caller's thread, on every core (the loop idle then) and with the
// caller's progress, without waiting for 0 to reach its next report; 0 is cancelled there.
TEST(DiagnosisAhead, ACandidateNotReachedRunsOnTheCallersThreadAndTheWorkerStops) {
  std::atomic<bool> zero_started{false};
  std::atomic<bool> zero_cancelled{false};
  std::atomic<bool> one_started{false};
  std::atomic<bool> zero_saw_one{false};
  std::thread::id ran_on;
  std::size_t one_threads = 1;
  hd::DiagnosisAhead ahead(
      [&](std::size_t i, const hd::DiagnosisAhead::Controls& controls) {
        if (i == 0) {
          zero_started = true;
          // A long stretch without a report: the caller does not wait for it.
          wait_until([&] { return one_started.load(); });
          zero_saw_one = one_started.load();
          work_until_cancelled(controls.progress, zero_cancelled);
        }
        one_started = true;
        one_threads = controls.threads;
        ran_on = std::this_thread::get_id();
        controls.progress(1.0, "done");
        return marked(i);
      },
      {0, 1});
  wait_until([&] { return zero_started.load(); });
  int reports = 0;
  const auto taken = ahead.take(1, [&](double, const std::string&) { ++reports; });
  EXPECT_TRUE(zero_saw_one.load());
  EXPECT_TRUE(zero_cancelled.load());
  EXPECT_EQ(taken.diagnosis.verdict, "candidate 1");
  EXPECT_EQ(taken.how, "after the verification");
  EXPECT_EQ(ran_on, std::this_thread::get_id());
  EXPECT_EQ(one_threads, 0U);
  EXPECT_EQ(reports, 1);
}

// Once the verification has chosen candidate 2, the worker abandons candidate 0, skips 1 and
// diagnoses 2 on its own thread, ready to be taken.
TEST(DiagnosisAhead, FocusAbandonsTheOneRunningForTheChosenOne) {
  std::atomic<bool> zero_started{false};
  std::atomic<bool> zero_cancelled{false};
  std::atomic<int> one_runs{0};
  std::thread::id two_ran_on;
  hd::DiagnosisAhead ahead(
      [&](std::size_t i, const hd::DiagnosisAhead::Controls& controls) {
        zero_works_until_cancelled(i, controls.progress, zero_started, zero_cancelled);
        if (i == 1) ++one_runs;
        if (i == 2) two_ran_on = std::this_thread::get_id();
        return marked(i);
      },
      {0, 1, 2});
  wait_until([&] { return zero_started.load(); });
  EXPECT_FALSE(ahead.ready(2));
  ahead.focus(2);
  wait_until([&] { return ahead.ready(2); });
  EXPECT_TRUE(zero_cancelled.load());
  EXPECT_FALSE(ahead.ready(0));
  const auto taken = ahead.take(2, nullptr);
  EXPECT_EQ(taken.diagnosis.verdict, "candidate 2");
  EXPECT_EQ(taken.how, "during the verification");
  EXPECT_NE(two_ran_on, std::this_thread::get_id());
  EXPECT_EQ(one_runs.load(), 0);
}

// A diagnosis abandoned inside a long fit stops there: the worker's controls say so to the fits
// (DiagnosisOptions::cancelled), not only at its next progress report.
TEST(DiagnosisAhead, OneAbandonedStopsInsideAFit) {
  std::atomic<bool> zero_started{false};
  std::atomic<bool> zero_stopped{false};
  hd::DiagnosisAhead ahead(
      [&](std::size_t i, const hd::DiagnosisAhead::Controls& controls) -> hc::Diagnosis {
        if (i == 0) {
          zero_started = true;
          while (!controls.cancelled()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
          zero_stopped = true;
          throw hc::DiagnosisCancelled();
        }
        return marked(i);
      },
      {0, 1});
  wait_until([&] { return zero_started.load(); });
  ahead.focus(1);
  wait_until([&] { return ahead.ready(1); });
  EXPECT_TRUE(zero_stopped.load());
  EXPECT_FALSE(ahead.ready(0));
  const auto taken = ahead.take(1, nullptr);
  EXPECT_EQ(taken.diagnosis.verdict, "candidate 1");
  EXPECT_EQ(taken.how, "during the verification");
}

// Focused on the one running: it goes on, and nothing starts after it.
TEST(DiagnosisAhead, FocusOnTheOneRunningLetsItFinishAndStartsNoOther) {
  std::atomic<bool> release{false};
  std::atomic<int> runs[2] = {0, 0};
  hd::DiagnosisAhead ahead(
      [&](std::size_t i, const hd::DiagnosisAhead::Controls& controls) {
        ++runs[i];
        while (i == 0 && !release.load()) {
          controls.progress(0.5, "working");
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        return marked(i);
      },
      {0, 1});
  wait_until([&] { return runs[0].load() == 1; });
  ahead.focus(0);
  release = true;
  wait_until([&] { return ahead.ready(0); });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // room for a wrong start of 1
  const auto taken = ahead.take(0, nullptr);
  EXPECT_EQ(taken.diagnosis.verdict, "candidate 0");
  EXPECT_EQ(runs[1].load(), 0);
}

// Taken while it runs: waited for, not started again, and nothing after it starts.
TEST(DiagnosisAhead, TheOneRunningIsWaitedForAndTheNextNeverStarts) {
  std::atomic<bool> release{false};
  std::atomic<bool> started{false};
  std::atomic<int> second{0};
  hd::DiagnosisAhead ahead(
      [&](std::size_t i, const hd::DiagnosisAhead::Controls&) {
        if (i == 1) ++second;
        started = true;
        while (i == 0 && !release.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        return marked(i);
      },
      {0, 1});
  wait_until([&] { return started.load(); });
  std::thread releaser([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    release = true;
  });
  const auto taken = ahead.take(0, nullptr);
  releaser.join();
  EXPECT_EQ(taken.diagnosis.verdict, "candidate 0");
  EXPECT_EQ(taken.how, "partly during the verification");
  EXPECT_EQ(second.load(), 0);
}

TEST(DiagnosisAhead, AFailedDiagnosisReachesTheCaller) {
  std::atomic<bool> done{false};
  hd::DiagnosisAhead ahead(
      [&](std::size_t, const hd::DiagnosisAhead::Controls&) -> hc::Diagnosis {
        done = true;
        throw std::runtime_error("the record is too short");
      },
      {0});
  wait_until([&] { return done.load(); });
  EXPECT_THROW(
      {
        try {
          (void)ahead.take(0, nullptr);
        } catch (const std::runtime_error& e) {
          EXPECT_STREQ(e.what(), "the record is too short");
          throw;
        }
      },
      std::runtime_error);
}

// A session that ends before anything is taken (stop, shutdown) cancels the one running.
TEST(DiagnosisAhead, DestroyingItCancelsTheOneRunning) {
  std::atomic<bool> started{false};
  std::atomic<bool> cancelled{false};
  {
    hd::DiagnosisAhead ahead(
        [&](std::size_t, const hd::DiagnosisAhead::Controls& controls) -> hc::Diagnosis {
          started = true;
          work_until_cancelled(controls.progress, cancelled);
        },
        {0});
    wait_until([&] { return started.load(); });
  }
  EXPECT_TRUE(cancelled.load());
}

// Started on the first candidate while the others are still being fitted: the worker waits
// for more, the candidates queued later are diagnosed by the task given with them, and once
// focused no candidate joins any more.
TEST(DiagnosisAhead, CandidatesFittedLaterJoinTheQueue) {
  std::atomic<int> first_task_runs{0};
  hd::DiagnosisAhead ahead(
      [&](std::size_t i, const hd::DiagnosisAhead::Controls&) {
        ++first_task_runs;
        return marked(i);
      },
      {0});
  wait_until([&] { return ahead.ready(0); });
  std::thread::id later_ran_on;
  const auto later = [&](std::size_t i, const hd::DiagnosisAhead::Controls&) {
    later_ran_on = std::this_thread::get_id();
    hc::Diagnosis d = marked(i);
    d.verdict += " (later)";
    return d;
  };
  ahead.queue_more(later, {0, 1});
  wait_until([&] { return ahead.ready(1); });
  EXPECT_EQ(first_task_runs.load(), 1);  // candidate 0 is not diagnosed twice
  EXPECT_NE(later_ran_on, std::this_thread::get_id());
  ahead.focus(1);
  ahead.queue_more(later, {2});
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(ahead.ready(2));
  const auto taken = ahead.take(1, nullptr);
  EXPECT_EQ(taken.diagnosis.verdict, "candidate 1 (later)");
  EXPECT_EQ(taken.how, "during the verification");
}

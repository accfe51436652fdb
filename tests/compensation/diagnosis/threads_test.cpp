// DiagnosisThreads: the candidates tested side by side (DiagnosisOptions::threads) give the
// diagnosis one thread gives, value for value; a progress callback that throws to cancel, and a
// cancelled() that turns true inside a candidate's fits, stop the diagnosis on any thread count.
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>

#include "compensation/diagnosis/diagnosis_test_support.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::test::diagnosis {

namespace {

hc::Diagnosis diagnose_on(const Record& r, std::size_t threads) {
  hc::DiagnosisOptions options;
  options.threads = threads;
  return hc::diagnose(r.t, r.u, r.y, options);
}

}  // namespace

TEST(DiagnosisThreads, TheCandidatesSideBySideGiveWhatOneThreadGives) {
  const HiddenData data = make_hidden({hc::Cause::kCreep, 500.0, 104});
  const hc::Diagnosis one = diagnose_on(data.first, 1);
  const hc::Diagnosis two = diagnose_on(data.first, 2);
  ASSERT_EQ(one.candidates.size(), two.candidates.size());
  for (std::size_t i = 0; i < one.candidates.size(); ++i) {
    const hc::CandidateReport& a = one.candidates[i];
    const hc::CandidateReport& b = two.candidates[i];
    SCOPED_TRACE(std::string(hc::to_string(a.cause)));
    EXPECT_EQ(a.cause, b.cause);
    EXPECT_EQ(a.statistic, b.statistic);
    EXPECT_EQ(a.heldout.rmse, b.heldout.rmse);
    EXPECT_EQ(a.gain, b.gain);
    EXPECT_EQ(a.extension, b.extension);
    EXPECT_EQ(a.evidence, b.evidence);
  }
  EXPECT_EQ(one.cause, hc::Cause::kCreep);
  EXPECT_EQ(two.cause, one.cause);
  EXPECT_EQ(two.verdict, one.verdict);
  EXPECT_EQ(two.extended_heldout.rmse, one.extended_heldout.rmse);
}

TEST(DiagnosisThreads, AProgressThatThrowsCancelsOnEveryThreadCount) {
  const HiddenData data = make_hidden({hc::Cause::kNone, 200.0, 101});
  for (const std::size_t threads : {1, 2}) {
    SCOPED_TRACE(threads);
    hc::DiagnosisOptions options;
    options.threads = threads;
    options.progress = [](double, const std::string& what) {
      if (what == "testing creep") throw std::runtime_error("cancelled");
    };
    EXPECT_THROW(hc::diagnose(data.first.t, data.first.u, data.first.y, options),
                 std::runtime_error);
  }
}

// Polled inside the fits: once it turns true during the candidates' tests, the diagnosis stops
// there with DiagnosisCancelled, and polls no more.
TEST(DiagnosisThreads, ACancelledPolledInsideTheFitsStopsIt) {
  const HiddenData data = make_hidden({hc::Cause::kNone, 200.0, 101});
  for (const std::size_t threads : {1, 2}) {
    SCOPED_TRACE(threads);
    std::atomic<bool> testing{false};
    std::atomic<int> polls_after{0};
    hc::DiagnosisOptions options;
    options.threads = threads;
    options.progress = [&](double, const std::string& what) {
      if (what.starts_with("testing")) testing = true;
    };
    options.cancelled = [&] { return testing && ++polls_after > 0; };
    EXPECT_THROW(hc::diagnose(data.first.t, data.first.u, data.first.y, options),
                 hc::DiagnosisCancelled);
    EXPECT_GE(polls_after.load(), 1);
    EXPECT_LE(polls_after.load(), static_cast<int>(threads));
  }
}

}  // namespace hystbench::test::diagnosis

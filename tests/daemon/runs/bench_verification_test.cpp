// Which verified candidate identify keeps: the lowest verified max error on the triangle, where
// figures within the bench's repeatability count as equal and the lower held-out error (the
// candidates' order) decides; left-out candidates never win; none verified: the first.
#include <gtest/gtest.h>

#include <vector>

#include "runs/details/identify_session.hpp"

namespace hd = hystbench::daemon;
using nlohmann::json;

namespace {

hd::IdentifyCandidate verified(double max_percent) {
  hd::IdentifyCandidate c;
  c.verification = {{"end", "completed"}, {"max_error_percent", max_percent}};
  return c;
}

hd::IdentifyCandidate not_completed() {
  hd::IdentifyCandidate c;
  c.verification = {{"end", "aborted"}, {"max_error_percent", 0.1}};
  return c;
}

}  // namespace

TEST(BestVerified, TheLowestMaxWinsByMoreThanTheBenchsRepeatability) {
  const std::vector<hd::IdentifyCandidate> c = {verified(2.0), verified(1.8), verified(1.9)};
  EXPECT_EQ(hd::best_verified(c, {}), 1U);
}

TEST(BestVerified, WithinThreePercentTheLowerHeldOutErrorDecides) {
  // 1.811 and 1.801 differ by 0.6 %: one bench run's noise, not the models.
  const std::vector<hd::IdentifyCandidate> c = {verified(1.811), verified(1.801)};
  EXPECT_EQ(hd::best_verified(c, {}), 0U);
  const std::vector<hd::IdentifyCandidate> far = {verified(1.90), verified(1.801)};
  EXPECT_EQ(hd::best_verified(far, {}), 1U);
}

TEST(BestVerified, LeftOutAndUnfinishedCandidatesDoNotWin) {
  const std::vector<hd::IdentifyCandidate> c = {verified(1.0), not_completed(), verified(1.5),
                                                verified(1.52)};
  EXPECT_EQ(hd::best_verified(c, {}), 0U);
  EXPECT_EQ(hd::best_verified(c, {0}), 2U);
  EXPECT_EQ(hd::best_verified(c, {0, 2}), 3U);
}

TEST(BestVerified, NoneVerifiedTakesTheFirstNotLeftOut) {
  const std::vector<hd::IdentifyCandidate> c = {hd::IdentifyCandidate{}, not_completed(),
                                                hd::IdentifyCandidate{}};
  EXPECT_EQ(hd::best_verified(c, {}), 0U);
  EXPECT_EQ(hd::best_verified(c, {0}), 1U);
}

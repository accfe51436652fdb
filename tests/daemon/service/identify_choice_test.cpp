// Which verified candidate identify keeps: the lowest verified max error on the triangle, where
// figures within the bench's repeatability count as equal and the lower held-out error (the
// candidates' order) decides; left-out candidates never win; none verified: the first.
#include <gtest/gtest.h>

#include <vector>

#include "service/details/identify_session.hpp"

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

namespace {

// A candidate verified at `triangle_rms` % on the triangle and `fast` / `mid` % on the sines.
constexpr hd::PartsBand kFast = hd::PartsBand::kFast;
constexpr hd::PartsBand kSlow = hd::PartsBand::kSlow;

hd::IdentifyCandidate on_sines(double triangle_rms, double fast, double mid) {
  hd::IdentifyCandidate c;
  c.verification = {{"end", "completed"},
                    {"max_error_percent", 2.0 * triangle_rms},
                    {"rms_error_percent", triangle_rms}};
  c.sines[500.0] = {{"end", "completed"}, {"rms_error_percent", fast}};
  c.sines[200.0] = {{"end", "completed"}, {"rms_error_percent", mid}};
  return c;
}

}  // namespace

// An extension that gains on the fast sine is adopted unless the triangle or the middle sine
// loses more than two runs spread apart. Where every sine gains 2x (a delay the model missed:
// 22.6 -> 1.02 % at 500 Hz, 8.9 -> 0.91 % at 200 Hz in one run), the triangle's rms may lose as
// much as runs apart in the bench's history do (0.75 -> 0.89 % in that run).
TEST(ExtensionTracksBetter, ADecisiveGainOnEverySineOutweighsTheTrianglesHistory) {
  const hd::IdentifyCandidate base = on_sines(0.747, 22.56, 8.89);
  EXPECT_TRUE(hd::extension_tracks_better(base, on_sines(0.889, 1.02, 0.91), 500.0, 200.0));
  EXPECT_FALSE(hd::extension_tracks_better(base, on_sines(1.05, 1.02, 0.91), 500.0, 200.0));
  // A gain of 1.1x on the fast sine is within reach of the runs' spread: the triangle's holds.
  const hd::IdentifyCandidate slow = on_sines(0.747, 8.5, 4.0);
  EXPECT_FALSE(hd::extension_tracks_better(slow, on_sines(0.889, 7.6, 3.9), 500.0, 200.0));
  EXPECT_TRUE(hd::extension_tracks_better(slow, on_sines(0.85, 7.6, 3.9), 500.0, 200.0));
  // Decisive on the fast sine but not on the middle one: the triangle's spread holds too.
  EXPECT_FALSE(hd::extension_tracks_better(base, on_sines(0.889, 1.02, 8.0), 500.0, 200.0));
  // The middle sine may not lose beyond the spread, however the fast one gains.
  EXPECT_FALSE(hd::extension_tracks_better(slow, on_sines(0.75, 1.0, 4.9), 500.0, 200.0));
}

// Each loss within the spread, yet together worse: a delay grafted on a rate law that already
// followed the actuator's lag gained 13 % on the fast sine and gave back 10 % on the middle one
// and 7 % on the triangle (one identify on the rate-dependent truth). Not adopted; the same
// gain with the losses halved is.
TEST(ExtensionTracksBetter, LossesWithinTheSpreadMayNotOutweighTheFastGain) {
  const hd::IdentifyCandidate base = on_sines(0.976, 8.557, 4.022);
  EXPECT_FALSE(hd::extension_tracks_better(base, on_sines(1.043, 7.559, 4.453), 500.0, 200.0));
  EXPECT_TRUE(hd::extension_tracks_better(base, on_sines(1.009, 7.559, 4.237), 500.0, 200.0));
  // A rate law against its rate-free self (no middle sine): the triangle may not give back what
  // the rate sine gains.
  EXPECT_FALSE(hd::extension_tracks_better(base, on_sines(1.09, 7.9, 4.0), 500.0));
  EXPECT_TRUE(hd::extension_tracks_better(base, on_sines(1.0, 7.9, 4.0), 500.0));
}

// Below 5 % on the fast sine, an extension that gains on every reference and 5 % together is
// adopted: a 1-sample delay the identification had left out gained 4 % at 500 Hz, 21 % at
// 200 Hz and 20 % on the triangle. A fast sine that loses, or gains too little overall, is not.
TEST(ExtensionTracksBetter, GainsOnEveryReferenceAddUp) {
  const hd::IdentifyCandidate base = on_sines(0.968, 7.892, 5.346);
  EXPECT_TRUE(hd::extension_tracks_better(base, on_sines(0.806, 7.567, 4.413), 500.0, 200.0));
  EXPECT_FALSE(hd::extension_tracks_better(base, on_sines(0.806, 7.95, 4.413), 500.0, 200.0));
  EXPECT_FALSE(hd::extension_tracks_better(base, on_sines(0.96, 7.85, 5.3), 500.0, 200.0));
}

// An extension whose mode and delay gain 68x at 500 Hz, but whose creep and rate law (their
// state set at rest each run) lose 3x on the triangle: not adopted whole (a run under load,
// 0.071 -> 0.213 % rms). Its fast parts alone are tried, and adopted where they track better;
// each part then says whether it was taken.
TEST(FastParts, TriedWhereTheWholeExtensionGainedFastButLostOnTheTriangle) {
  const hd::IdentifyCandidate base = on_sines(0.071, 15.73, 6.28);
  const hd::IdentifyCandidate whole = on_sines(0.213, 0.232, 0.197);
  const json parts = json::array({{{"cause", "delay"}},
                                  {{"cause", "dynamics"}},
                                  {{"cause", "creep"}},
                                  {{"cause", "rate_dependence"}}});
  ASSERT_FALSE(hd::extension_tracks_better(base, whole, 500.0, 200.0));
  EXPECT_TRUE(
      hd::parts_alone_worth_trying(base, whole, hd::split_parts(parts), kFast, 500.0, 200.0));
  // Not where the whole extension is adopted, holds no slow part or no fast one, or lost on the
  // fast sine too.
  EXPECT_FALSE(hd::parts_alone_worth_trying(base, on_sines(0.08, 0.232, 0.197),
                                            hd::split_parts(parts), kFast, 500.0, 200.0));
  const json fast_only = json::array({{{"cause", "delay"}}, {{"cause", "dynamics"}}});
  EXPECT_FALSE(
      hd::parts_alone_worth_trying(base, whole, hd::split_parts(fast_only), kFast, 500.0, 200.0));
  const json slow_only = json::array({{{"cause", "creep"}}});
  EXPECT_FALSE(
      hd::parts_alone_worth_trying(base, whole, hd::split_parts(slow_only), kFast, 500.0, 200.0));
  EXPECT_FALSE(hd::parts_alone_worth_trying(base, on_sines(0.213, 16.0, 0.197),
                                            hd::split_parts(parts), kFast, 500.0, 200.0));
  // The slow band is not tried here: the whole extension gained on the middle sine, but on the
  // fast one too, so its mode and delay are what gained.
  EXPECT_FALSE(
      hd::parts_alone_worth_trying(base, whole, hd::split_parts(parts), kSlow, 500.0, 200.0));

  json extension = {
      {"parts", parts}, {"adopted", false}, {"fast_parts", {{"parts", {"delay", "dynamics"}}}}};
  ASSERT_TRUE(
      hd::adopt_parts_alone(base, on_sines(0.075, 0.25, 0.2), kFast, 500.0, 200.0, extension));
  EXPECT_TRUE(extension["adopted"].get<bool>());
  EXPECT_TRUE(extension["fast_parts"]["adopted"].get<bool>());
  EXPECT_NEAR(extension["fast_parts"]["verified"]["fast_gain"].get<double>(), 15.73 / 0.25, 1e-9);
  hd::mark_adopted_parts(extension, true, kFast);
  for (const json& p : extension["parts"]) {
    const std::string cause = p["cause"];
    EXPECT_EQ(p["adopted"].get<bool>(), cause == "delay" || cause == "dynamics") << p;
  }
  // Alone, they may lose on the triangle as well: nothing adopted, and every part says so.
  json lost = {{"parts", parts}, {"fast_parts", {{"parts", {"delay", "dynamics"}}}}};
  EXPECT_FALSE(hd::adopt_parts_alone(base, on_sines(0.2, 0.25, 0.2), kFast, 500.0, 200.0, lost));
  EXPECT_FALSE(lost["fast_parts"]["adopted"].get<bool>());
  EXPECT_FALSE(lost.contains("adopted"));
  hd::mark_adopted_parts(lost, false, std::nullopt);
  for (const json& p : lost["parts"]) EXPECT_FALSE(p["adopted"].get<bool>()) << p;
}

// The mirror case, one run on a 1 kHz bench with a 190 Hz mode and rate dependence on: the
// plane's extension (its relays widening with the rate, and a mode fitted at 180 Hz, damping
// 0.11) gained 1.9x on the middle sine and 13 % on the triangle but lost 23 % on the fast one.
// Its slow parts alone (the base's own dynamics) are tried, and adopted where they gain on the
// middle sine without giving back on the fast one beyond the spread between runs.
TEST(SlowParts, TriedWhereTheWholeExtensionGainedOnTheMiddleSineButLostOnTheFastOne) {
  const hd::IdentifyCandidate base = on_sines(0.434, 2.577, 1.463);
  const hd::IdentifyCandidate whole = on_sines(0.378, 3.169, 0.775);
  const json parts = json::array({{{"cause", "dynamics"}}, {{"cause", "rate_dependence"}}});
  ASSERT_FALSE(hd::extension_tracks_better(base, whole, 500.0, 200.0));
  EXPECT_TRUE(
      hd::parts_alone_worth_trying(base, whole, hd::split_parts(parts), kSlow, 500.0, 200.0));
  EXPECT_FALSE(
      hd::parts_alone_worth_trying(base, whole, hd::split_parts(parts), kFast, 500.0, 200.0));
  // Not where the middle sine did not gain, or the fast one gained too.
  EXPECT_FALSE(hd::parts_alone_worth_trying(base, on_sines(0.378, 3.169, 1.5),
                                            hd::split_parts(parts), kSlow, 500.0, 200.0));
  EXPECT_FALSE(hd::parts_alone_worth_trying(base, on_sines(0.5, 2.5, 0.775), hd::split_parts(parts),
                                            kSlow, 500.0, 200.0));

  json extension = {
      {"parts", parts}, {"adopted", false}, {"slow_parts", {{"parts", {"rate_dependence"}}}}};
  ASSERT_TRUE(
      hd::adopt_parts_alone(base, on_sines(0.40, 2.62, 0.80), kSlow, 500.0, 200.0, extension));
  EXPECT_TRUE(extension["adopted"].get<bool>());
  EXPECT_TRUE(extension["slow_parts"]["adopted"].get<bool>());
  hd::mark_adopted_parts(extension, true, kSlow);
  for (const json& p : extension["parts"]) {
    EXPECT_EQ(p["adopted"].get<bool>(), p["cause"] == "rate_dependence") << p;
  }
  // Alone they may still lose on the fast sine (beyond the spread), or gain too little on the
  // middle one: not adopted.
  json fast_lost = {{"parts", parts}, {"slow_parts", {{"parts", {"rate_dependence"}}}}};
  EXPECT_FALSE(
      hd::adopt_parts_alone(base, on_sines(0.40, 3.0, 0.80), kSlow, 500.0, 200.0, fast_lost));
  EXPECT_FALSE(fast_lost["slow_parts"]["adopted"].get<bool>());
  EXPECT_FALSE(fast_lost.contains("adopted"));
  json too_little = {{"parts", parts}, {"slow_parts", {{"parts", {"rate_dependence"}}}}};
  EXPECT_FALSE(
      hd::adopt_parts_alone(base, on_sines(0.434, 2.577, 1.45), kSlow, 500.0, 200.0, too_little));
}

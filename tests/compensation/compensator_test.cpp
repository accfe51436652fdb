#include "hystbench/compensation/compensator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/tracking_metrics.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;

namespace {

// An integral-and-proportional loop on the feedforward's target: kp [1], ki [1/s], v within
// +/- limit [um].
hc::FeedbackController feedback(double kp, double ki, double limit, double dt) {
  hc::FeedbackLaw law;
  law.pid = {kp, ki, 0.0, 0.0, -limit, limit};
  return hc::FeedbackController(law, dt);
}

struct TrackFigures {
  double max_error, hysteresis;
};

// Tracks a 1 Hz triangle with `kind` on a plant equal to `truth`, at 10 kHz.
TrackFigures track(hc::CompensatorKind kind, const hc::ActuatorModel& model,
                   hc::ActuatorModel truth) {
  std::optional<hc::FeedbackController> pid;
  if (hc::uses_feedback(kind)) pid.emplace(feedback(0.015, 60.0, 45.0, 1e-4));
  std::unique_ptr<hc::InverseModel> inverse;
  if (hc::needs_model(kind)) {
    inverse = hc::make_inverse(model, kind == hc::CompensatorKind::kInverseMultiplicative
                                          ? hc::InverseKind::kMultiplicative
                                          : hc::InverseKind::kAuto);
  }
  const double y0 = truth.peek_static(0.0), y1 = truth.peek_static(150.0);
  hc::Compensator comp(kind, std::move(inverse), pid, {(y1 - y0) / 150.0, y0});
  truth.reset(0.0);
  comp.reset(0.0);
  std::vector<double> yr, y;
  double y_prev = NAN;
  for (int k = 0; k < 30000; ++k) {
    const double phase = std::fmod(k / 10000.0, 1.0);
    const double tri = phase < 0.5 ? 2 * phase : 2 * (1 - phase);
    const double ref = y0 + (y1 - y0) * (0.1 + 0.8 * tri);
    const auto out = comp.step(ref, y_prev);
    y_prev = truth.step(std::clamp(out.u, 0.0, 150.0));
    if (k >= 10000) {
      yr.push_back(ref);
      y.push_back(y_prev);
    }
  }
  return {hc::error_stats(yr, y).max_abs / (y1 - y0), hc::hysteresis_percent(yr, y)};
}

}  // namespace

TEST(Compensator, InverseRemovesTheHysteresisOfAnExactModel) {
  std::mt19937_64 rng(8);
  const hc::ActuatorModel model = hystbench::testing::random_mpi_actuator(rng, 12, 2, 150.0, 1e-4);
  const TrackFigures none = track(hc::CompensatorKind::kNone, model, model);
  const TrackFigures inverse = track(hc::CompensatorKind::kInverse, model, model);
  const TrackFigures multiplicative =
      track(hc::CompensatorKind::kInverseMultiplicative, model, model);
  const TrackFigures pid = track(hc::CompensatorKind::kInversePid, model, model);
  EXPECT_GT(none.hysteresis, 2.0);
  EXPECT_LT(inverse.max_error, 1e-9);
  EXPECT_LT(inverse.hysteresis, 1e-6);
  EXPECT_LT(multiplicative.max_error, 0.01);
  EXPECT_LT(pid.max_error, 0.01);
}

// A copy plays ahead what the compensator would do from the same state (its inverse's memory,
// its PID's integral) without moving the original.
TEST(Compensator, ACopyPlaysAheadFromTheSameStateAndLeavesTheOriginal) {
  std::mt19937_64 rng(10);
  const hc::ActuatorModel model = hystbench::testing::random_mpi_actuator(rng, 12, 2, 150.0, 1e-4);
  const double y0 = model.peek_static(0.0), y1 = model.peek_static(150.0);
  hc::Compensator original(hc::CompensatorKind::kInversePid, hc::make_inverse(model),
                           feedback(0.015, 60.0, 1.5, 1e-4), {(y1 - y0) / 150.0, y0});
  original.reset(0.0);
  const auto reference = [&](int k) { return y0 + (y1 - y0) * (0.5 + 0.4 * std::sin(k * 1e-3)); };
  for (int k = 0; k < 3000; ++k) (void)original.step(reference(k), reference(k) - 0.1);
  hc::Compensator copy = original;
  std::vector<double> ahead;
  for (int k = 3000; k < 6000; ++k) ahead.push_back(copy.step(reference(k), reference(k)).u);
  for (int k = 3000; k < 6000; ++k) {
    ASSERT_DOUBLE_EQ(original.step(reference(k), reference(k)).u, ahead[k - 3000]) << k;
  }
}

TEST(Compensator, PidAloneFollowsASlowReferenceOnAMismatchedPlant) {
  std::mt19937_64 rng(9);
  hc::ActuatorModel truth(
      std::make_unique<hc::ModifiedPiModel>(hystbench::testing::random_mpi(rng, 12, 2, 150.0)));
  truth.configure(1e-4);
  const TrackFigures pid = track(hc::CompensatorKind::kPid, truth, truth);
  const TrackFigures none = track(hc::CompensatorKind::kNone, truth, truth);
  EXPECT_LT(pid.hysteresis, none.hysteresis);
}

// The run log's feedback_saturated flag comes from here: set while the loop sits at its clamp.
TEST(Compensator, SaysWhenTheFeedbackIsAtItsClamp) {
  hc::Compensator c(hc::CompensatorKind::kPid, nullptr, feedback(0.0, 1000.0, 5.0, 1e-3), {});
  c.reset(0.0);
  hc::CompensatorOutput out = c.step(1.0, 0.0);
  EXPECT_FALSE(out.feedback_saturated);
  for (int k = 0; k < 20; ++k) out = c.step(1.0, 0.0);  // 1 um short: integrates 1 V per tick
  EXPECT_TRUE(out.feedback_saturated);
  EXPECT_DOUBLE_EQ(out.u_fb, 5.0);
  for (int k = 0; k < 20 && out.feedback_saturated; ++k) out = c.step(0.0, 1.0);
  EXPECT_FALSE(out.feedback_saturated);
  EXPECT_LT(out.u_fb, 5.0);
  hc::Compensator none(hc::CompensatorKind::kNone, nullptr, std::nullopt, {1.0, 0.0});
  EXPECT_FALSE(none.step(1e9, 0.0).feedback_saturated);
}

// A resonator beside a loop without gain: what it integrated (a start from rest) drives its
// output until restart_harmonics() drops it; the PID's state stays, and the resonator integrates
// again from then on.
TEST(Compensator, RestartingTheHarmonicsDropsWhatTheResonatorsIntegratedAndKeepsThePid) {
  const double dt = 1e-3;
  hc::FeedbackLaw law;
  law.pid = {0.0, 100.0, 0.0, 0.0, -50.0, 50.0};
  law.harmonics.resonators.push_back({50.0, {1.0, 0.0}, 0.1});
  hc::Compensator c(hc::CompensatorKind::kPid, nullptr, hc::FeedbackController(law, dt),
                    {1.0, 0.0});
  hc::Compensator pid_alone(hc::CompensatorKind::kPid, nullptr, feedback(0.0, 100.0, 50.0, dt),
                            {1.0, 0.0});
  c.reset(0.0);
  pid_alone.reset(0.0);
  for (int k = 0; k < 5; ++k) {  // a 1 um error, as a start from rest leaves
    c.step(1.0, 0.0);
    pid_alone.step(1.0, 0.0);
  }
  const double integrated = c.step(0.0, 0.0).u_fb - pid_alone.step(0.0, 0.0).u_fb;
  EXPECT_GT(std::abs(integrated), 0.1);  // the resonator holds the error it integrated
  c.restart_harmonics();
  // From rest: with no error since, the resonator adds nothing to the PID's output.
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(c.step(0.0, 0.0).u_fb, pid_alone.step(0.0, 0.0).u_fb, 1e-12) << k;
  }
  // And it integrates again.
  c.step(1.0, 0.0);
  pid_alone.step(1.0, 0.0);
  EXPECT_GT(std::abs(c.step(0.0, 0.0).u_fb - pid_alone.step(0.0, 0.0).u_fb), 0.05);
  hc::Compensator none(hc::CompensatorKind::kNone, nullptr, std::nullopt, {1.0, 0.0});
  none.restart_harmonics();  // nothing to restart
  EXPECT_DOUBLE_EQ(none.step(1.0, 0.0).u_fb, 0.0);
}

// The loop's output corrects the feedforward's target: u = inverse(target + v). The feedforward
// alone (u_ff) is what the same inverse gives for the target, and on a plant that is the model
// plus an offset the loop takes the offset out, whatever the model's local slope there.
TEST(Compensator, TheFeedbackCorrectsTheTargetThroughTheInverseAndUffStaysTheFeedforwards) {
  std::mt19937_64 rng(11);
  hc::ActuatorModel model = hystbench::testing::random_mpi_actuator(rng, 12, 2, 150.0, 1e-4);
  const double y0 = model.peek_static(0.0), y1 = model.peek_static(150.0);
  hc::Compensator c(hc::CompensatorKind::kInversePid, hc::make_inverse(model),
                    feedback(0.0, 300.0, 10.0, 1e-4), {(y1 - y0) / 150.0, y0});
  std::unique_ptr<hc::InverseModel> plain = hc::make_inverse(model);
  hc::ActuatorModel truth = model;
  truth.reset(0.0);
  c.reset(0.0);
  plain->reset(0.0);
  double y = NAN, last_error = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double yr = y0 + (y1 - y0) * (0.5 + 0.4 * std::sin(2.0 * M_PI * k / 10000.0));
    const hc::CompensatorOutput out = c.step(yr, y);
    ASSERT_DOUBLE_EQ(out.u_ff, plain->step(yr)) << k;
    ASSERT_DOUBLE_EQ(out.u_fb, out.u - out.u_ff) << k;
    y = truth.step(out.u) + 0.5;  // the actuator sits 0.5 um above the model
    last_error = yr - y;
  }
  EXPECT_LT(std::abs(last_error), 0.01);
}

// The integral holds while the drive sits at a bound of its range: no wind-up while the
// target is out of reach, so the loop lets go as soon as it is back in reach.
TEST(Compensator, TheLoopDoesNotWindUpWhileTheDriveSitsAtItsBound) {
  hc::Compensator c(hc::CompensatorKind::kPid, nullptr, feedback(0.0, 1000.0, 100.0, 1e-3),
                    {1.0, 0.0});
  c.set_drive_range(0.0, 10.0);
  c.reset(0.0);
  hc::CompensatorOutput out;
  for (int k = 0; k < 200; ++k) out = c.step(9.5, std::min(out.u, 10.0) - 2.0);  // 2 short
  EXPECT_GE(out.u, 10.0);
  EXPECT_LT(out.v, 3.0);  // stopped at the bound, not wound up over 200 ticks
}

TEST(Compensator, RefusesAnInverseKindWithoutAModel) {
  EXPECT_THROW(hc::Compensator(hc::CompensatorKind::kInverse, nullptr, std::nullopt, {}),
               std::invalid_argument);
  EXPECT_THROW(hc::Compensator(hc::CompensatorKind::kPid, nullptr, std::nullopt, {}),
               std::invalid_argument);
  EXPECT_EQ(hc::compensator_kind_from_string("inverse+pid"), hc::CompensatorKind::kInversePid);
  EXPECT_FALSE(hc::compensator_kind_from_string("bogus").has_value());
}

TEST(TrackingMetrics, HysteresisPercentMeasuresTheLoopWidth) {
  // y lags the reference like an ellipse: width 2*a*sin(phi) at mid level for y = a sin(wt - phi).
  std::vector<double> yr, y;
  const double phi = 0.2;
  for (int k = 0; k < 20000; ++k) {
    const double w = 2 * M_PI * k / 1000.0;
    yr.push_back(std::sin(w));
    y.push_back(std::sin(w - phi));
  }
  // Widest at the middle: 2 sin(phi) over a range of 2.
  EXPECT_NEAR(hc::hysteresis_percent(yr, y), 100.0 * std::sin(phi), 0.5);
  EXPECT_NEAR(hc::hysteresis_percent(yr, yr), 0.0, 1e-12);
}

// A step answered by a second-order lag: its overshoot and its settling to 1 % as the formulas
// give them (zeta 0.5: 16.3 % overshoot; the envelope exp(-zeta wn t) within 1 % of the step by
// about 4.6 / (zeta wn), give or take the oscillation's phase).
TEST(TrackingMetrics, StepFiguresMeasureOvershootAndSettling) {
  const double dt = 1e-4, wn = 2.0 * M_PI * 500.0, zeta = 0.5;
  std::vector<double> yr, y;
  double x = 0.0, v = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double target = (k / 5000) % 2 == 0 ? 0.0 : 10.0;  // up at 5000, down at 10000 ...
    yr.push_back(target);
    for (int s = 0; s < 10; ++s) {  // the lag integrated finely
      const double a = wn * wn * (target - x) - 2.0 * zeta * wn * v;
      v += a * dt / 10.0;
      x += v * dt / 10.0;
    }
    y.push_back(x);
  }
  const hc::StepFigures f = hc::step_figures(yr, y, dt, 1.0);
  EXPECT_EQ(f.steps, 3u);
  EXPECT_DOUBLE_EQ(f.mean_size, 10.0);
  EXPECT_NEAR(f.max_overshoot, std::exp(-zeta * M_PI / std::sqrt(1.0 - zeta * zeta)), 0.01);
  const double settling = 4.6 / (zeta * wn);
  EXPECT_NEAR(f.max_settling_s, settling, 0.3 * settling);
  EXPECT_TRUE(f.settled);
  // A reference without a step has none; a response that never gets there is not settled.
  EXPECT_EQ(
      hc::step_figures(std::vector<double>(100, 1.0), std::vector<double>(100, 1.0), dt, 0.1).steps,
      0u);
  std::vector<double> stuck(yr.size(), 0.0);
  EXPECT_FALSE(hc::step_figures(yr, stuck, dt, 1.0).settled);
}

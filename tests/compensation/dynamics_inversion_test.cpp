// The feedforward that inverts a model's delay and second-order dynamics from a previewed
// reference: composed with the model it follows a band-limited reference far closer than the
// static inverse alone, and a step reference gives a bounded drive.
#include "hystbench/compensation/dynamics_inversion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <numbers>

#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-4;  // 10 kHz

// A stack-like modified PI with the loopback actuator's dynamics (3 kHz, damping 0.08) and a
// 0.2 ms input delay.
hc::ActuatorModel full_model(bool dynamics, double delay_s, double dt = kDt) {
  hc::PiParameters play;
  for (int i = 0; i < 10; ++i) {
    play.thresholds.push_back(7.5 * i);
    play.weights.push_back(i == 0 ? 0.18 : 0.02);
  }
  hc::DeadZoneParameters dz{{-15.0, 0.0, 12.0}, {0.15, 1.0, 0.4}};
  hc::ActuatorModel m(
      std::make_unique<hc::ModifiedPiModel>(hc::ModifiedPiParameters{play, dz, 21.0}));
  if (dynamics) m.set_dynamics(hc::DynamicsParameters{3000.0, 0.08});
  m.set_delay(delay_s);
  m.input_min = 0.0;
  m.input_max = 150.0;
  m.configure(dt);
  m.reset(0.0);
  return m;
}

struct Tracking {
  double rms = 0.0, max = 0.0, max_drive_step = 0.0;
};

// Drives `model` with the static inverse of its hysteresis fed either the reference itself or the
// inversion's target, and scores y(k) against r(t_k) after the first period.
Tracking track(const hc::ActuatorModel& truth, const std::function<double(double)>& r,
               double periods_s, double skip_s, bool invert, double dt = kDt) {
  hc::ActuatorModel model = truth;
  hc::ActuatorModel static_part = truth;
  static_part.set_delay(0.0);
  static_part.set_dynamics(std::nullopt);
  static_part.configure(dt);
  const double u0 = 75.0;
  model.reset(u0);
  static_part.reset(u0);
  auto inverse = hc::make_inverse(static_part);
  inverse->reset(u0);
  const hc::DynamicsInversion inversion(truth, dt);
  Tracking t;
  double sum2 = 0.0, u_prev = u0;
  std::size_t n = 0;
  for (int k = 0; k * dt < periods_s; ++k) {
    const double tk = k * dt;
    double target = r(tk);
    if (invert) {
      const double tl = tk + inversion.lead_s(), h = inversion.step_s();
      target = inversion.target(r(tl - h), r(tl), r(tl + h));
    }
    const double u = inverse->step(target);
    const double y = model.step(u);
    t.max_drive_step = std::max(t.max_drive_step, std::abs(u - u_prev));
    u_prev = u;
    if (tk >= skip_s) {
      const double e = y - r(tk);
      sum2 += e * e;
      t.max = std::max(t.max, std::abs(e));
      ++n;
    }
  }
  t.rms = std::sqrt(sum2 / static_cast<double>(n));
  return t;
}

}  // namespace

TEST(DynamicsInversion, PreviewAndDerivativesFollowAFastSineWhereTheStaticInverseLags) {
  const hc::ActuatorModel truth = full_model(true, 2e-4);
  const hc::DynamicsInversion inversion(truth, kDt);
  ASSERT_TRUE(inversion.active());
  EXPECT_EQ(inversion.preview_samples(), 3);  // 2 delay - half a sample + h = 1 sample
  // A sine over 10-35 um (about 80 % of the range), after a start-up period.
  for (const double f : {200.0, 500.0}) {
    auto r = [f](double t) { return 22.5 - 12.5 * std::cos(2.0 * std::numbers::pi * f * t); };
    const Tracking plain = track(truth, r, 20.0 / f, 2.0 / f, false);
    const Tracking inverted = track(truth, r, 20.0 / f, 2.0 / f, true);
    const double range = 25.0;
    std::cout << f << " Hz: static inverse rms " << 100 * plain.rms / range << " %, with the "
              << "dynamics inversion " << 100 * inverted.rms / range << " % of range\n";
    EXPECT_LT(inverted.rms, 0.2 * plain.rms) << f << " Hz";
    EXPECT_LT(inverted.rms, 0.01 * range) << f << " Hz";
  }
}

TEST(DynamicsInversion, AStepReferenceGivesABoundedDrive) {
  const hc::ActuatorModel truth = full_model(true, 2e-4);
  auto step = [](double t) { return t < 0.01 ? 10.0 : 30.0; };
  const Tracking t = track(truth, step, 0.03, 0.02, true);
  // The derivatives are rolled off: the drive stays within the input range (the inverse clamps
  // there anyway) and settles on the step.
  EXPECT_LE(t.max_drive_step, 150.0);
  EXPECT_LT(t.rms, 0.5) << "settled after the step";
}

TEST(DynamicsInversion, AStaticModelNeedsNothingAndTheTargetIsTheReference) {
  const hc::DynamicsInversion none(full_model(false, 0.0), kDt);
  EXPECT_FALSE(none.active());
  EXPECT_EQ(none.preview_samples(), 0);
  EXPECT_EQ(none.target(1.0, 2.0, 5.0), 2.0);
  EXPECT_EQ(none.describe(), "nothing (a static model)");
  const hc::DynamicsInversion delay_only(full_model(false, 3e-4), kDt);
  EXPECT_TRUE(delay_only.active());
  EXPECT_NEAR(delay_only.lead_s(), 3e-4, 1e-12);
  EXPECT_EQ(delay_only.target(1.0, 2.0, 5.0), 2.0);
}

// A 500 Hz reference on a 2 kHz loop (4 samples a period) with the 3 kHz resonance above its
// Nyquist frequency: the inversion is rolled off (default bandwidth a quarter of the loop rate),
// so the drive stays bounded and within the input range and the error does not grow.
TEST(DynamicsInversion, AFastReferenceOnASlowLoopStaysBounded) {
  const double dt = 5e-4;
  const hc::ActuatorModel truth = full_model(true, 2e-4, dt);
  const hc::DynamicsInversion inversion(truth, dt);
  EXPECT_DOUBLE_EQ(inversion.bandwidth_hz(), 500.0);
  auto r = [](double t) { return 22.5 - 12.5 * std::cos(2.0 * std::numbers::pi * 500.0 * t); };
  const Tracking first = track(truth, r, 0.05, 0.01, true, dt);
  const Tracking longer = track(truth, r, 0.5, 0.4, true, dt);
  EXPECT_TRUE(std::isfinite(longer.rms));
  EXPECT_LE(longer.max_drive_step, 150.0);
  EXPECT_LT(longer.rms, 1.5 * first.rms + 0.1) << "the error does not grow over the run";
  EXPECT_LT(longer.max, 25.0) << "within the reference's span";
}

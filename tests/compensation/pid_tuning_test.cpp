#include "hystbench/compensation/pid_tuning.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "hystbench/compensation/pid_controller.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The feedback behind a feedforward that leaves error d(t) = offset + a periodic part at f0 on
// an actuator with a lag the model does not know: y = g (u - tau du/dt) + d, a right-half-plane
// zero at 1 / tau (the signed rate law falling with the rate). Returns the rms of the error's
// periodic part and its mean over the last whole periods.
struct LoopResult {
  double periodic_rms = 0.0, mean = 0.0;
};
LoopResult close_loop(const hc::PidTuning& t, double f0, double offset, double gain, double tau) {
  const double dt = 1e-4;
  hc::PidController pid({t.kp, t.ki, t.kd, 0.0, -30.0, 30.0, t.output_filter_hz, t.error_period_s},
                        dt);
  const int per = static_cast<int>(std::lround(1.0 / (f0 * dt)));
  const int n = 40 * per;
  std::vector<double> e(n);
  double u_prev = 0.0, err = 0.0;
  for (int k = 0; k < n; ++k) {
    const double u = pid.step(err);
    const double ph = kTwoPi * f0 * k * dt;
    const double d = offset + 0.5 * std::sin(ph) + 0.15 * std::sin(3.0 * ph + 0.4);
    const double y = gain * (u - tau * (u - u_prev) / dt) + d;
    u_prev = u;
    err = -y;  // the reference is what the feedforward already delivers: 0 here
    e[k] = err;
  }
  LoopResult r;
  const int from = n - 10 * per;
  for (int k = from; k < n; ++k) r.mean += e[k];
  r.mean /= (n - from);
  for (int k = from; k < n; ++k) r.periodic_rms += (e[k] - r.mean) * (e[k] - r.mean);
  r.periodic_rms = std::sqrt(r.periodic_rms / (n - from));
  return r;
}

}  // namespace

TEST(PidTuning, IntegralOnlyAtTheLoopRateOver500AtMost2Hz) {
  const hc::PidTuning t = hc::tune_pid(0.3, 10000.0, 0.0, nullptr);
  EXPECT_DOUBLE_EQ(t.bandwidth_hz, 2.0);
  EXPECT_DOUBLE_EQ(t.ki, kTwoPi * 2.0 / 0.3);
  EXPECT_EQ(t.kp, 0.0);
  EXPECT_EQ(t.kd, 0.0);
  EXPECT_EQ(t.error_period_s, 0.0);
  EXPECT_DOUBLE_EQ(hc::tune_pid(0.3, 500.0, 0.0, nullptr).bandwidth_hz, 1.0);
  EXPECT_THROW(hc::tune_pid(0.0, 10000.0, 0.0, nullptr), std::invalid_argument);
  EXPECT_THROW(hc::tune_pid(0.3, -1.0, 0.0, nullptr), std::invalid_argument);
}

TEST(PidTuning, APeriodicReferenceAboveTheCrossoverIsAveragedOverItsPeriod) {
  // Up to half the crossover the loop lowers the periodic error itself: no average.
  EXPECT_EQ(hc::tune_pid(0.3, 10000.0, 0.0, nullptr, 0.5).error_period_s, 0.0);
  EXPECT_EQ(hc::tune_pid(0.3, 10000.0, 0.0, nullptr, 1.0).error_period_s, 0.0);
  const hc::PidTuning t2 = hc::tune_pid(0.3, 10000.0, 0.0, nullptr, 1.5);
  EXPECT_DOUBLE_EQ(t2.error_period_s, 1.0 / 1.5);
  EXPECT_DOUBLE_EQ(t2.bandwidth_hz, 0.15);
  // Behind the linear map (`pid`) up to the crossover: the hysteresis it removes is carried by
  // the fundamental.
  EXPECT_EQ(
      hc::tune_pid(0.3, 10000.0, 0.0, nullptr, 1.5, hc::FeedforwardKind::kLinearMap).error_period_s,
      0.0);
  EXPECT_DOUBLE_EQ(
      hc::tune_pid(0.3, 10000.0, 0.0, nullptr, 2.5, hc::FeedforwardKind::kLinearMap).error_period_s,
      0.4);
  const hc::PidTuning t19 = hc::tune_pid(0.3, 10000.0, 0.0, nullptr, 19.0);
  EXPECT_DOUBLE_EQ(t19.error_period_s, 1.0 / 19.0);
  EXPECT_DOUBLE_EQ(t19.bandwidth_hz, 1.9);  // a tenth of the reference: the average's delay
  EXPECT_NE(t19.basis.find("averaged over the reference's period"), std::string::npos) << t19.basis;
  const hc::PidTuning t50 = hc::tune_pid(0.3, 10000.0, 0.0, nullptr, 50.0);
  EXPECT_DOUBLE_EQ(t50.bandwidth_hz, 2.0);
  EXPECT_DOUBLE_EQ(t50.error_period_s, 0.02);
}

// Why: with a lag the model does not know, an integral loop raises every error above its
// crossover by |S| - 1 > 0. Averaged over the reference's period, the loop removes the offset
// and leaves the periodic part as the feedforward left it.
TEST(PidTuning, TheAveragedLoopRemovesTheOffsetAndNeverRaisesThePeriodicError) {
  const double gain = 0.3, tau = 1.0 / (kTwoPi * 17.8), fc = 1.27;
  for (const double f0 : {5.0, 10.0, 19.0, 50.0}) {
    const double alone =
        std::sqrt((0.5 * 0.5 + 0.15 * 0.15) / 2.0);  // the feedforward's periodic error
    const LoopResult plain =
        close_loop(hc::tune_pid(gain, 10000.0, fc, nullptr), f0, 0.2, gain, tau);
    const LoopResult averaged =
        close_loop(hc::tune_pid(gain, 10000.0, fc, nullptr, f0), f0, 0.2, gain, tau);
    EXPECT_LT(std::abs(plain.mean), 0.01) << f0;
    EXPECT_LT(std::abs(averaged.mean), 0.01) << f0;
    EXPECT_LE(averaged.periodic_rms, 1.002 * alone) << f0 << " Hz";
    EXPECT_GT(plain.periodic_rms, 1.04 * alone) << f0 << " Hz";  // measured 5-8 % above
  }
}

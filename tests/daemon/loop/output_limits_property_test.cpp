// Property: whatever the model, reference, PID gains, measurement and limit settings, the
// output after the limiter never leaves [u_min, u_max], never moves by more than the slew step
// per tick and is never NaN -- the Compensator + OutputLimiter path of the bench loop
// (including the safe-output jumps the loop makes via reset()). Over a million ticks.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/daemon/loop/output_limiter.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::daemon;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Scenario {
  hd::OutputLimits limits;
  double dt = 1e-4;
  hc::CompensatorKind kind = hc::CompensatorKind::kNone;
  hc::PidParameters pid;
};

Scenario random_scenario(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto log_uniform = [&](double lo, double hi) {
    return std::exp(std::log(lo) + (std::log(hi) - std::log(lo)) * unit(rng));
  };
  Scenario s;
  // Mostly a piezo amplifier's range; otherwise anything from a 1 µV span to 300 V anywhere.
  const bool typical = unit(rng) < 0.7;
  s.limits.u_min = typical ? 0.0 : (unit(rng) - 0.5) * 200.0;
  s.limits.u_max = s.limits.u_min + (typical ? 50.0 + 100.0 * unit(rng) : log_uniform(1e-6, 300.0));
  s.limits.slew_v_per_s = log_uniform(1e-3, 1e9);
  static const double rates[] = {1e3, 1e4, 2e4, 5e4};
  s.dt = 1.0 / rates[rng() % 4];
  static const hc::CompensatorKind kinds[] = {
      hc::CompensatorKind::kNone, hc::CompensatorKind::kInverse,
      hc::CompensatorKind::kInverseMultiplicative, hc::CompensatorKind::kInversePid,
      hc::CompensatorKind::kPid};
  s.kind = kinds[rng() % 5];
  s.pid.kp = unit(rng) < 0.2 ? 0.0 : log_uniform(1e-4, 1e3);
  s.pid.ki = unit(rng) < 0.2 ? 0.0 : log_uniform(1e-2, 1e7);
  s.pid.kd = unit(rng) < 0.5 ? 0.0 : log_uniform(1e-8, 1e-1);
  s.pid.derivative_filter_hz = unit(rng) < 0.5 ? 0.0 : log_uniform(10.0, 0.4 / s.dt);
  const double fb = log_uniform(1e-3, 1e4);
  s.pid.output_min = -fb;
  s.pid.output_max = fb * unit(rng);
  return s;
}

}  // namespace

TEST(OutputLimitsProperty, NeverExceededOverAMillionTicks) {
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uint64_t ticks = 0, clamps = 0, slews = 0;
  int scenarios = 0;
  while (ticks < 1'200'000) {
    const Scenario s = random_scenario(rng);
    SCOPED_TRACE(::testing::Message()
                 << "scenario " << scenarios << " u=[" << s.limits.u_min << ", " << s.limits.u_max
                 << "] slew " << s.limits.slew_v_per_s << " dt " << s.dt << " kind "
                 << hc::to_string(s.kind));
    // A random invertible model; the actuator is the same model (plus noise) or a linear one.
    const int n = 1 + static_cast<int>(rng() % 20);
    const double span = 150.0;
    hc::ActuatorModel model =
        unit(rng) < 0.5
            ? hc::ActuatorModel(
                  std::make_unique<hc::PiModel>(hystbench::testing::random_pi(rng, n, span)))
            : hc::ActuatorModel(std::make_unique<hc::ModifiedPiModel>(
                  hystbench::testing::random_mpi(rng, n, static_cast<int>(rng() % 5), span)));
    std::unique_ptr<hc::InverseModel> inverse;
    if (s.kind == hc::CompensatorKind::kInverseMultiplicative) {
      try {  // the multiplicative structure exists for some model kinds only
        inverse = hc::make_inverse(model, hc::InverseKind::kMultiplicative);
      } catch (const std::exception&) {
      }
    }
    if (hc::needs_model(s.kind) && !inverse) inverse = hc::make_inverse(model);
    std::optional<hc::FeedbackController> pid;
    if (hc::uses_feedback(s.kind)) pid.emplace(hc::FeedbackLaw{{}, s.pid, {}, {}}, s.dt);
    hc::Compensator comp(s.kind, std::move(inverse), pid, hc::LinearMap{0.1 + unit(rng), 0.0});
    hd::OutputLimiter limiter(s.limits, s.dt);
    const double safe = s.limits.u_min + (s.limits.u_max - s.limits.u_min) * unit(rng);
    limiter.reset(safe);
    comp.reset(safe);
    const double max_step = s.limits.slew_v_per_s * s.dt;
    // References beyond any range, measurements with noise, spikes, NaN and infinities.
    const bool wild = unit(rng) < 0.3;
    const auto ref = hystbench::testing::random_reversal_signal(
        rng, 2000 + rng() % 20000, wild ? -300.0 : 0.0, wild ? 300.0 : 40.0);
    double prev = limiter.last(), y = kNaN;
    for (std::size_t k = 0; k < ref.size(); ++k, ++ticks) {
      const auto out = comp.step(ref[k], y);
      const auto lim = limiter.apply(out.u);
      comp.notify_saturation(lim.direction);
      ASSERT_FALSE(std::isnan(lim.u)) << "tick " << k;
      ASSERT_GE(lim.u, s.limits.u_min) << "tick " << k;
      ASSERT_LE(lim.u, s.limits.u_max) << "tick " << k;
      ASSERT_LE(std::abs(lim.u - prev), max_step * (1 + 1e-12) + 1e-12) << "tick " << k;
      prev = lim.u;
      const double r = unit(rng);
      y = r < 0.001   ? kNaN
          : r < 0.002 ? (r < 0.0015 ? kInf : -kInf)
          : r < 0.005 ? 1e12 * (r - 0.0035)
                      : model.step(lim.u) + (unit(rng) - 0.5);
      if (unit(rng) < 1e-4) {  // the loop's safe-output jump (fault, run end): reset anywhere
        const double jump = (unit(rng) - 0.5) * 1e4;
        limiter.reset(jump);
        comp.reset(jump);
        prev = limiter.last();
        ASSERT_GE(prev, s.limits.u_min);
        ASSERT_LE(prev, s.limits.u_max);
      }
    }
    clamps += limiter.clamp_count();
    slews += limiter.slew_count();
    ++scenarios;
  }
  std::cout << ticks << " ticks over " << scenarios << " scenarios, " << clamps << " clamped, "
            << slews << " slew-limited\n";
  // The limits were exercised, not just respected by a tame controller.
  EXPECT_GT(clamps, ticks / 100);
  EXPECT_GT(slews, ticks / 100);
}

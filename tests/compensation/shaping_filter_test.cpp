#include "hystbench/compensation/shaping_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "hystbench/compensation/feedback_controller.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A sine of f_hz through step(): the steady state's amplitude and phase against the input's,
// from its projection on the input's sine and cosine over whole periods.
template <typename Step>
std::complex<double> measured_response(Step step, double f_hz, double dt) {
  const int per = static_cast<int>(std::lround(1.0 / (f_hz * dt)));
  const double w = kTwoPi / per;
  std::complex<double> acc = 0.0;
  const int settle = 200 * per;
  for (int k = 0; k < settle + 20 * per; ++k) {
    const double y = step(std::sin(w * k));
    if (k >= settle) acc += y * std::polar(1.0, -(w * k - kTwoPi / 4.0));
  }
  return acc * 2.0 / (20.0 * per);
}

}  // namespace

TEST(ShapingFilter, ANotchHasItsDepthAtItsCentreAndUnitGainAwayFromIt) {
  const double dt = 1e-4;
  const hc::ShapingFilter f({{{3000.0, 0.3, 0.05}}, {}}, dt);
  EXPECT_NEAR(std::abs(f.response(3000.0)), 0.05, 1e-9);
  EXPECT_NEAR(std::abs(f.response(1e-3)), 1.0, 1e-6);
  EXPECT_NEAR(std::abs(f.response(100.0)), 1.0, 0.01);
  // Its -3 dB band is about 2 zeta f0 wide (well below the Nyquist frequency, where the
  // bilinear map does not narrow it).
  const hc::ShapingFilter low({{{300.0, 0.3, 0.05}}, {}}, 1e-4);
  EXPECT_LT(std::abs(low.response(300.0 * 0.8)), 0.75);
  EXPECT_GT(std::abs(low.response(300.0 * 0.65)), 0.75);
}

TEST(ShapingFilter, TheLowPassIsDownThreeDecibelsAtItsCornerAndUnitAtDc) {
  const hc::ShapingFilter f({{}, {800.0, 1.0 / std::sqrt(2.0)}}, 1e-4);
  EXPECT_NEAR(std::abs(f.response(800.0)), 1.0 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(std::abs(f.response(1e-3)), 1.0, 1e-9);
  EXPECT_NEAR(std::arg(f.response(800.0)), -kTwoPi / 4.0, 1e-6);
}

TEST(ShapingFilter, StepFollowsItsResponse) {
  const double dt = 1e-4;
  const hc::ShapingFilterSpec spec{{{3000.0, 0.3, 0.1}, {1200.0, 0.5, 0.2}}, {2000.0, 0.6}};
  for (const double f : {50.0, 500.0, 1250.0, 2500.0}) {
    hc::ShapingFilter filter(spec, dt);
    const std::complex<double> measured =
        measured_response([&](double x) { return filter.step(x); }, f, dt);
    SCOPED_TRACE(f);
    EXPECT_NEAR(std::abs(measured - filter.response(f)), 0.0, 2e-3);
  }
}

TEST(ShapingFilter, ResetSettlesEverySectionAtItsInput) {
  hc::ShapingFilter f({{{3000.0, 0.3, 0.1}}, {1000.0, 0.7}}, 1e-4);
  f.reset(2.5);
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(f.step(2.5), 2.5, 1e-12);
}

TEST(ShapingFilter, RefusesSectionsAtOrAboveNyquistOrWithoutWidth) {
  EXPECT_THROW(hc::ShapingFilter({{{5000.0, 0.3, 0.1}}, {}}, 1e-4), std::invalid_argument);
  EXPECT_THROW(hc::ShapingFilter({{{3000.0, 0.0, 0.1}}, {}}, 1e-4), std::invalid_argument);
  EXPECT_THROW(hc::ShapingFilter({{{3000.0, 0.3, 1.5}}, {}}, 1e-4), std::invalid_argument);
  EXPECT_THROW(hc::ShapingFilter({{}, {6000.0, 0.7}}, 1e-4), std::invalid_argument);
  std::vector<hc::Notch> many(hc::ShapingFilter::kMaxNotches + 1, {1000.0, 0.3, 0.1});
  EXPECT_THROW(hc::ShapingFilter({many, {}}, 1e-4), std::invalid_argument);
}

TEST(FeedbackController, ItsResponseIsThePidsTimesTheShapingsAndStepFollowsIt) {
  const double dt = 1e-4;
  hc::FeedbackLaw law;
  law.pid.kp = 0.3;
  law.pid.ki = 2000.0;
  law.shaping = {{{3000.0, 0.4, 0.1}}, {2500.0, 0.7071}};
  for (const double f : {20.0, 300.0, 2000.0}) {
    hc::FeedbackController c(law, dt);
    // The integrator's steady state needs an input without mean: a sine is one.
    const std::complex<double> measured =
        measured_response([&](double e) { return c.step(e); }, f, dt);
    SCOPED_TRACE(f);
    EXPECT_NEAR(std::abs(measured / c.response(f) - 1.0), 0.0, 0.02);
  }
}

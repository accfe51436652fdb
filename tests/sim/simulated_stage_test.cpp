#include "hystbench/sim/simulated_stage.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include "hystbench/compensation/mimo_identification.hpp"
#include "hystbench/sim/simulated_actuator.hpp"

namespace hs = hystbench::sim;
namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-4;  // the loopback's default 10 kHz
constexpr double kPi = std::numbers::pi;

hs::SimulatedStageConfig uncoupled(hs::SimulatedStageConfig c) {
  c.coupling.enabled = false;
  return c;
}

// The truth without noise: what the coupling adds is read from true positions.
hs::SimulatedStageConfig noise_free(hs::SimulatedStageConfig c) {
  for (auto& axis : c.axes) axis.actuator.sensor_noise.enabled = false;
  return c;
}

// Amplitude of x's component at f_hz (lock-in over whole periods).
double amplitude_at(const std::vector<double>& x, double f_hz) {
  std::complex<double> sum = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sum += x[k] * std::polar(1.0, -2.0 * kPi * f_hz * static_cast<double>(k) * kDt);
  }
  return 2.0 * std::abs(sum) / static_cast<double>(x.size());
}

struct CrossResponse {
  double stroke_amplitude = 0.0;  // x's stroke at f [µm]
  double cross_amplitude = 0.0;   // what the coupling adds to y at f [µm]
};

// x driven by a sine at f_hz around mid-range with y held at its bottom: x's stroke and the
// difference between y's true position with and without the coupling, over whole periods
// after a settling second.
CrossResponse cross_response(double f_hz, double amplitude_v) {
  const hs::SimulatedStageConfig c = noise_free(hs::SimulatedStageConfig::xy());
  hs::SimulatedStage coupled(c, kDt);
  hs::SimulatedStage alone(uncoupled(c), kDt);
  const std::size_t settle = 10000;
  const auto samples = static_cast<std::size_t>(std::lround(std::ceil(f_hz * 0.5) / f_hz / kDt));
  std::vector<double> stroke, cross;
  std::vector<double> y(2);
  for (std::size_t k = 0; k < settle + samples; ++k) {
    const double u[2] = {75.0 + amplitude_v * std::sin(2.0 * kPi * f_hz * k * kDt), 0.0};
    coupled.step(u, y);
    alone.step(u, y);
    if (k < settle) continue;
    stroke.push_back(coupled.axis(0).last_stroke());
    cross.push_back(coupled.axis(1).true_position() - alone.axis(1).true_position());
  }
  return {amplitude_at(stroke, f_hz), amplitude_at(cross, f_hz)};
}

}  // namespace

TEST(SimulatedStage, OneAxisIsItsActuatorSampleForSample) {
  hs::SimulatedStageConfig c;
  c.axes = {{"z", hs::SimulatedActuatorConfig{}}};
  hs::SimulatedStage stage(c, kDt);
  hs::SimulatedActuator actuator(hs::SimulatedActuatorConfig{}, kDt);
  double y[1] = {0.0};
  for (int k = 0; k < 20000; ++k) {
    const double u[1] = {75.0 + 70.0 * std::sin(2.0 * kPi * 7.0 * k * kDt)};
    stage.step(u, y);
    ASSERT_EQ(y[0], actuator.step(u[0])) << "sample " << k;
  }
}

TEST(SimulatedStage, WithoutTheCouplingEachAxisIsItsOwnActuator) {
  const hs::SimulatedStageConfig c = uncoupled(hs::SimulatedStageConfig::xy());
  hs::SimulatedStage stage(c, kDt);
  hs::SimulatedActuator x(c.axes[0].actuator, kDt);
  hs::SimulatedActuator y(c.axes[1].actuator, kDt);
  std::vector<double> out(2);
  for (int k = 0; k < 10000; ++k) {
    const double u[2] = {75.0 + 70.0 * std::sin(2.0 * kPi * 5.0 * k * kDt),
                         75.0 + 60.0 * std::sin(2.0 * kPi * 3.0 * k * kDt)};
    stage.step(u, out);
    ASSERT_EQ(out[0], x.step(u[0])) << "sample " << k;
    ASSERT_EQ(out[1], y.step(u[1])) << "sample " << k;
  }
}

TEST(SimulatedStage, TheAxesDifferInTheirHysteresis) {
  hs::SimulatedStage stage(noise_free(hs::SimulatedStageConfig::xy()), kDt);
  std::vector<double> y(2);
  double largest = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double v = 75.0 - 75.0 * std::cos(2.0 * kPi * 1.0 * k * kDt);
    const double u[2] = {v, v};
    stage.step(u, y);
    largest =
        std::max(largest, std::abs(stage.axis(0).last_stroke() - stage.axis(1).last_stroke()));
  }
  EXPECT_GT(largest, 1.0);  // µm, of a ~45 µm range
}

TEST(SimulatedStage, TheStrokeOfOneAxisReachesTheOtherWithItsDcGain) {
  // 2 Hz: far below the shared mode, where the cross path's gain is its DC gain.
  const hs::SimulatedStageConfig c = hs::SimulatedStageConfig::xy();
  const CrossResponse r = cross_response(2.0, 60.0);
  ASSERT_GT(r.stroke_amplitude, 10.0);
  EXPECT_NEAR(r.cross_amplitude / r.stroke_amplitude, c.coupling.gains[1][0], 0.002);
}

TEST(SimulatedStage, TheCrossPathResonatesAtTheSharedMode) {
  const hs::SimulatedStageConfig c = hs::SimulatedStageConfig::xy();
  const CrossResponse low = cross_response(20.0, 2.0);
  const CrossResponse peak = cross_response(c.coupling.shared_mode_hz, 2.0);
  const double rise =
      (peak.cross_amplitude / peak.stroke_amplitude) / (low.cross_amplitude / low.stroke_amplitude);
  // A second-order mode peaks at 1 / (2 zeta) of its DC gain (6.25 for zeta 0.08).
  EXPECT_NEAR(rise, 1.0 / (2.0 * c.coupling.shared_damping_ratio), 0.6);
}

TEST(SimulatedStage, ResetRepeatsARunSampleForSample) {
  hs::SimulatedStage stage(hs::SimulatedStageConfig::xy(), kDt);
  const auto run = [&] {
    std::vector<double> trace, y(2);
    for (int k = 0; k < 5000; ++k) {
      const double u[2] = {75.0 + 50.0 * std::sin(k * 2e-3), 40.0 + 30.0 * std::sin(k * 3e-3)};
      stage.step(u, y);
      trace.insert(trace.end(), y.begin(), y.end());
    }
    return trace;
  };
  const std::vector<double> first = run();
  stage.reset();
  EXPECT_EQ(run(), first);
}

TEST(SimulatedStage, ResetSettlesTheCouplingWithTheAxes) {
  // Settled at rest, a held input leaves every axis where it is: nothing rings after reset().
  const hs::SimulatedStageConfig c = noise_free(hs::SimulatedStageConfig::xy());
  hs::SimulatedStage stage(c, kDt);
  const double u0[2] = {100.0, 30.0};
  stage.reset(u0);
  const double x0 = stage.axis(0).true_position(), y0 = stage.axis(1).true_position();
  std::vector<double> y(2);
  stage.step(u0, y);
  EXPECT_NEAR(stage.axis(0).true_position(), x0, 1e-9);
  EXPECT_NEAR(stage.axis(1).true_position(), y0, 1e-9);
}

TEST(SimulatedStage, MissingOrNonFiniteInputsHoldTheAxis) {
  hs::SimulatedStage stage(noise_free(hs::SimulatedStageConfig::xy()), kDt);
  const double u[2] = {120.0, 80.0};
  std::vector<double> y(2);
  stage.step(u, y);
  const double held[1] = {std::nan("")};
  stage.step(held, y);
  EXPECT_NEAR(stage.axis(0).applied_input(), 120.0, 0.01);
  EXPECT_NEAR(stage.axis(1).applied_input(), 80.0, 0.01);
}

// The coupling as the bench would see it: one axis excited at a time by a random-phase multisine
// around mid-range, the other held there, in turn; then a MIMO linear fit of the record (the one
// `fit` makes of a record of several inputs). The ratio of the cross to the direct response at
// low frequency is the coupling's DC gain: both carry the same stroke, the hysteresis included.
TEST(SimulatedStage, AMimoFitOfItsRecordRecoversTheCoupling) {
  const hs::SimulatedStageConfig c = hs::SimulatedStageConfig::xy();
  constexpr std::size_t kPeriod = 2048, kPeriods = 3, kRealizations = 4, kBins = 40;
  hc::PeriodicRecord record;
  record.period = kPeriod;
  record.periods = kPeriods;
  record.dt = kDt;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * kPi);
  for (std::size_t r = 0; r < kRealizations; ++r) {
    hs::SimulatedStage stage(c, kDt);
    const double mid[2] = {75.0, 75.0};
    stage.reset(mid);
    const auto n = static_cast<Eigen::Index>(kPeriod * kPeriods);
    const auto excited = static_cast<Eigen::Index>(r % 2);
    Eigen::MatrixXd u = Eigen::MatrixXd::Constant(2, n, 75.0), y(2, n);
    for (std::size_t b = 1; b <= kBins; ++b) {
      const double ph = phase(rng);
      for (Eigen::Index t = 0; t < n; ++t) {
        u(excited, t) += 1.5 * std::cos(2.0 * kPi * static_cast<double>(b * t) / kPeriod + ph);
      }
    }
    for (Eigen::Index t = 0; t < n; ++t) {
      const double in[2] = {u(0, t), u(1, t)};
      double out[2];
      stage.step(in, out);
      y(0, t) = out[0];
      y(1, t) = out[1];
    }
    record.u.push_back(std::move(u));
    record.y.push_back(std::move(y));
  }
  const hc::PeriodicSpectra spectra = hc::periodic_spectra(record);
  const hc::MimoFitResult fit = hc::identify_mimo_linear(spectra);
  // The lowest excited line, 4.9 Hz.
  const Eigen::MatrixXcd g = fit.model.response(spectra.z(0));
  const double x_to_y = std::abs(g(1, 0)) / std::abs(g(0, 0));
  const double y_to_x = std::abs(g(0, 1)) / std::abs(g(1, 1));
  EXPECT_NEAR(x_to_y, c.coupling.gains[1][0], 0.1 * c.coupling.gains[1][0]);
  EXPECT_NEAR(y_to_x, c.coupling.gains[0][1], 0.1 * c.coupling.gains[0][1]);
}

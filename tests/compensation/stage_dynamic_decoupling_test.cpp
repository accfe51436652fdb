#include "hystbench/compensation/stage_dynamic_decoupling.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/refusal.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-4;  // 10 kHz

std::string refusal(const auto& make) { return hystbench::test::invalid_argument_message(make); }

// A stage the decoupler's form does not hold. Axis i's output is a sensor's first-order
// low-pass (3 kHz) of its own mode (3 kHz, damping 0.06) driven by s_i, plus every other axis's
// s_j through a path of two modes (1.5 kHz, 80 % of the gain; 4 kHz, 20 %) with the gain
// K_ij. `coupled` false: each axis alone.
Eigen::MatrixXd stage_outputs(const Eigen::MatrixXd& k, const Eigen::MatrixXd& s,
                              bool coupled = true) {
  constexpr double kPole = 0.1518;  // exp(-2 pi 3000 Hz x 100 us)
  const Eigen::Index n = s.rows();
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(n, s.cols());
  for (Eigen::Index i = 0; i < n; ++i) {
    hc::SecondOrderDynamics own({3000.0, 0.06}, kDt);
    own.reset(s(i, 0));
    for (Eigen::Index t = 0; t < s.cols(); ++t) x(i, t) += own.step(s(i, t));
    for (Eigen::Index j = 0; j < n && coupled; ++j) {
      if (i == j) continue;
      hc::SecondOrderDynamics first({1500.0, 0.08}, kDt), second({4000.0, 0.05}, kDt);
      first.reset(s(j, 0));
      second.reset(s(j, 0));
      for (Eigen::Index t = 0; t < s.cols(); ++t) {
        x(i, t) += k(i, j) * (0.8 * first.step(s(j, t)) + 0.2 * second.step(s(j, t)));
      }
    }
  }
  Eigen::MatrixXd y(n, s.cols());
  for (Eigen::Index i = 0; i < n; ++i) {
    double seen = x(i, 0);
    for (Eigen::Index t = 0; t < s.cols(); ++t)
      y(i, t) = seen = kPole * seen + (1.0 - kPole) * x(i, t);
  }
  return y;
}

Eigen::MatrixXd xy_gains() {
  Eigen::MatrixXd k(2, 2);
  k << 0.0, 0.056, 0.1, 0.0;
  return k;
}

// The responses an identify measures when axis `moved` is excited alone: a sine at each of 118
// lines from 10 Hz to 4.5 kHz (on a 1000-sample period's grid), each axis's output line over
// whole periods after the transient, over the sine's; at four operating points, each with its
// own small gain error. own: the moved axis's; cross: the other's.
struct Measured {
  std::vector<hc::MeasuredResponse> own, cross;
};

Measured measure(Eigen::Index moved) {
  hc::MeasuredResponse own, cross;
  for (int m = 0; m < 118; ++m) {
    const double f = std::max(10.0, std::round(std::pow(450.0, m / 117.0)) * 10.0);
    if (!own.frequency_hz.empty() && f <= own.frequency_hz.back()) continue;
    Eigen::MatrixXd s = Eigen::MatrixXd::Zero(2, 3000);
    for (Eigen::Index k = 0; k < s.cols(); ++k) {
      s(moved, k) = std::sin(2.0 * std::numbers::pi * f * static_cast<double>(k) * kDt);
    }
    const Eigen::MatrixXd y = stage_outputs(xy_gains(), s);
    std::complex<double> line_own = 0.0, line_cross = 0.0;
    for (Eigen::Index k = 2000; k < s.cols(); ++k) {
      const auto turn = std::polar(1.0, -2.0 * std::numbers::pi * f * static_cast<double>(k) * kDt);
      line_own += y(moved, k) * turn;
      line_cross += y(1 - moved, k) * turn;
    }
    // The sine's line is -j / 2 per sample.
    const std::complex<double> input(0.0, -500.0);
    for (auto [r, line] : {std::pair{&own, line_own}, std::pair{&cross, line_cross}}) {
      r->frequency_hz.push_back(f);
      r->response.push_back(line / input);
      r->noise.push_back(1e-4);
      r->coherence.push_back(0.99);
    }
  }
  Measured out;
  for (int p = 0; p < 4; ++p) {
    for (auto [from, to] : {std::pair{&own, &out.own}, std::pair{&cross, &out.cross}}) {
      to->push_back(*from);
      to->back().label = "operating point " + std::to_string(p);
      for (auto& v : to->back().response) v *= 1.0 + 0.01 * (p - 1.5);
    }
  }
  return out;
}

// A raster: x a triangle at `fast_hz` over 24 µm, y a ramp over 24 µm in `seconds`.
Eigen::MatrixXd raster(double fast_hz, double seconds) {
  const auto samples = static_cast<Eigen::Index>(std::llround(seconds / kDt));
  Eigen::MatrixXd r(2, samples);
  for (Eigen::Index k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) * kDt;
    const double phase = std::fmod(t * fast_hz, 1.0);
    r(0, k) = 10.0 + 24.0 * (phase < 0.5 ? 2.0 * phase : 2.0 - 2.0 * phase);
    r(1, k) = 10.0 + 24.0 * t / seconds;
  }
  return r;
}

double rms(const Eigen::RowVectorXd& e) { return std::sqrt(e.squaredNorm() / e.size()); }

}  // namespace

// A path of two modes: both found, with their shares, and the fit explains the responses.
TEST(CouplingPath, FindsThePathsModesAndTheirSharesInItsMeasuredCrossResponses) {
  const auto path = hc::coupling_path(measure(0).cross, {}, std::nullopt, kDt);
  ASSERT_TRUE(path.has_value());
  ASSERT_EQ(path->modes.size(), 2u);
  std::vector<hc::CouplingPathShape::Mode> modes = path->modes;
  std::sort(modes.begin(), modes.end(), [](const auto& a, const auto& b) {
    return a.parameters.natural_frequency_hz < b.parameters.natural_frequency_hz;
  });
  EXPECT_NEAR(modes[0].parameters.natural_frequency_hz, 1500.0, 75.0);
  EXPECT_NEAR(modes[1].parameters.natural_frequency_hz, 4000.0, 200.0);
  EXPECT_NEAR(modes[0].share, 0.8, 0.1);
  EXPECT_NEAR(modes[1].share, 0.2, 0.05);
  EXPECT_NEAR(path->direct + modes[0].share + modes[1].share, 1.0, 1e-12);
  EXPECT_GT(path->lag_samples, 0.0);  // the sensor's
  EXPECT_LT(path->misfit, 0.1);
}

// Over the receiving axis's own response: the fit still explains the ratio (its own mode is
// the part the central differences take), and it needs the same lines in both.
TEST(CouplingPath, OverTheReceivingAxisOwnResponseOnTheLinesBothHave) {
  const auto alone = hc::coupling_path(measure(0).cross, {}, std::nullopt, kDt);
  const auto over_own = hc::coupling_path(measure(0).cross, measure(1).own, std::nullopt, kDt);
  ASSERT_TRUE(alone && over_own);
  EXPECT_LT(over_own->misfit, 0.2);
  // Own responses at other lines than the cross's: none in common, no shape.
  std::vector<hc::MeasuredResponse> shifted = measure(1).own;
  for (auto& r : shifted) {
    for (auto& f : r.frequency_hz) f += 1.0;
  }
  EXPECT_FALSE(hc::coupling_path(measure(0).cross, shifted, std::nullopt, kDt).has_value());
}

TEST(CouplingPath, AFlatPathHasNone) {
  std::vector<hc::MeasuredResponse> flat = measure(0).cross;
  for (auto& r : flat) {
    for (auto& v : r.response) v = std::complex<double>(0.1, 0.0);
  }
  EXPECT_FALSE(hc::coupling_path(flat, {}, std::nullopt, kDt).has_value());
  EXPECT_FALSE(hc::coupling_path({}, {}, std::nullopt, kDt).has_value());
}

TEST(DynamicStageDecoupler, WithoutModesGivesTheStaticDecouplingsTargets) {
  const hc::DynamicStageDecoupler decoupler(xy_gains(), {}, kDt);
  EXPECT_FALSE(decoupler.dynamic());
  const Eigen::MatrixXd r = raster(200.0, 0.05);
  const auto solution = decoupler.own_targets(r);
  // (I + K) s = r on every sample.
  const Eigen::MatrixXd back = (Eigen::MatrixXd::Identity(2, 2) + xy_gains()) * solution.own;
  EXPECT_LT((back - r).cwiseAbs().maxCoeff(), 1e-12);
}

// A fast raster's corners ring the shared mode, and the receiving axis lags on the correction
// it must carry. On a stage the fit's form does not hold (a path of two modes, each axis's own
// mode and sensor), each path fitted from the responses identify measures takes out at least
// three times what the static gains leave on the slow axis (3.2x), and never leaves more on the
// fast one. What is left: each axis's output less what it shows tracking its own reference alone.
TEST(DynamicStageDecoupler, AFastRasterLeavesThreeTimesLessThanStaticOnATwoModeStage) {
  const Eigen::MatrixXd k = xy_gains();
  const Measured x_turn = measure(0), y_turn = measure(1);
  hc::DynamicStageDecoupler::PathShapes paths(2,
                                              std::vector<std::optional<hc::CouplingPathShape>>(2));
  paths[1][0] = hc::coupling_path(x_turn.cross, y_turn.own, std::nullopt, kDt);
  paths[0][1] = hc::coupling_path(y_turn.cross, x_turn.own, std::nullopt, kDt);
  ASSERT_TRUE(paths[1][0] && paths[0][1]);
  const hc::DynamicStageDecoupler dynamic(k, paths, kDt), statics(k, {}, kDt);
  ASSERT_TRUE(dynamic.dynamic());
  const Eigen::MatrixXd r = raster(200.0, 0.5);
  const auto solved = dynamic.own_targets(r);
  EXPECT_GT(solved.sweeps, 1);
  EXPECT_LT(solved.change, 1e-6);
  const Eigen::MatrixXd alone = stage_outputs(k, r, false);
  const Eigen::MatrixXd left_dynamic = stage_outputs(k, solved.own) - alone;
  const Eigen::MatrixXd left_static = stage_outputs(k, statics.own_targets(r).own) - alone;
  const Eigen::MatrixXd left_none = stage_outputs(k, r) - alone;
  const double on_y_dynamic = rms(left_dynamic.row(1)), on_y_static = rms(left_static.row(1));
  EXPECT_GT(rms(left_none.row(1)), 10.0 * on_y_static);  // static is a large gain already
  EXPECT_GT(on_y_static, 3.0 * on_y_dynamic) << on_y_static << " " << on_y_dynamic;
  EXPECT_LE(rms(left_dynamic.row(0)), rms(left_static.row(0)));
}

// With the path's exact mode and no other dynamics, the substitutions put the stage at the
// reference to their tolerance.
TEST(DynamicStageDecoupler, WithThePathsExactModeTheStageLandsOnTheReference) {
  Eigen::MatrixXd k = xy_gains();
  hc::DynamicStageDecoupler::PathShapes modes(2,
                                              std::vector<std::optional<hc::CouplingPathShape>>(2));
  const hc::CouplingPathShape one_mode{0.0, {{{1500.0, 0.08}, 1.0}}, 0.0};
  modes[1][0] = one_mode;
  modes[0][1] = one_mode;
  const hc::DynamicStageDecoupler decoupler(k, modes, kDt);
  const Eigen::MatrixXd r = raster(200.0, 0.2);
  const Eigen::MatrixXd s = decoupler.own_targets(r).own;
  Eigen::MatrixXd y = s;
  for (int i = 0; i < 2; ++i) {
    hc::SecondOrderDynamics path({1500.0, 0.08}, kDt);
    path.reset(s(1 - i, 0));
    for (Eigen::Index t = 0; t < s.cols(); ++t) y(i, t) += k(i, 1 - i) * path.step(s(1 - i, t));
  }
  EXPECT_LT((y - r).cwiseAbs().maxCoeff(), 1e-6);
}

// Axis j's feedforward commands a stroke other than its own target (its dynamics inverted):
// the coupling follows the stroke.
TEST(DynamicStageDecoupler, TheCouplingFollowsTheStrokeEachAxisCommands) {
  const Eigen::MatrixXd k = xy_gains();
  hc::DynamicStageDecoupler::PathShapes modes(2,
                                              std::vector<std::optional<hc::CouplingPathShape>>(2));
  modes[1][0] = hc::CouplingPathShape{0.0, {{{1500.0, 0.08}, 1.0}}, 0.0};
  const hc::DynamicStageDecoupler decoupler(k, modes, kDt);
  const Eigen::MatrixXd r = raster(100.0, 0.1);
  // x's stroke: its target plus a constant lead of 1 µm.
  std::vector<hc::DynamicStageDecoupler::StrokeOf> strokes(2);
  strokes[0] = [](std::span<const double> own, std::span<double> stroke) {
    for (std::size_t i = 0; i < own.size(); ++i) stroke[i] = own[i] + 1.0;
  };
  const Eigen::MatrixXd plain = decoupler.own_targets(r).own;
  const Eigen::MatrixXd led = decoupler.own_targets(r, strokes).own;
  // y's target falls by K_yx (DC gain 1) times x's stroke change, 1 µm plus x's own change,
  // which is -K_xy times y's (a static path): dy = -0.1 (1 - 0.056 dy).
  const double dy = -0.1 / (1.0 - 0.1 * 0.056);
  for (Eigen::Index t = 0; t < r.cols(); t += 97) {
    EXPECT_NEAR((led - plain)(1, t), dy, 1e-9);
    EXPECT_NEAR((led - plain)(0, t), -0.056 * dy, 1e-9);
  }
}

TEST(DynamicStageDecoupler, RefusesWhatItCannotSolveNamingTheCause) {
  const Eigen::MatrixXd k = xy_gains();
  EXPECT_NE(refusal([&] { hc::DynamicStageDecoupler d(k, {}, 0.0); }).find("dt"),
            std::string::npos);
  hc::DynamicStageDecoupler::PathShapes short_paths(1);
  EXPECT_NE(refusal([&] { hc::DynamicStageDecoupler d(k, short_paths, kDt); }).find("paths"),
            std::string::npos);
  hc::DynamicStageDecoupler::PathShapes bad(2,
                                            std::vector<std::optional<hc::CouplingPathShape>>(2));
  bad[1][0] = hc::CouplingPathShape{0.0, {{{-5.0, 0.08}, 1.0}}, 0.0};
  EXPECT_NE(refusal([&] { hc::DynamicStageDecoupler d(k, bad, kDt); }).find("path 1 <- 0"),
            std::string::npos);
  const hc::DynamicStageDecoupler ok(k, {}, kDt);
  EXPECT_NE(refusal([&] { (void)ok.own_targets(Eigen::MatrixXd::Zero(3, 10)); }).find("3 axes"),
            std::string::npos);
  Eigen::MatrixXd nan_ref = raster(10.0, 0.01);
  nan_ref(0, 3) = std::nan("");
  EXPECT_NE(refusal([&] { (void)ok.own_targets(nan_ref); }).find("finite"), std::string::npos);
  // Coupling so strong at a lightly damped shared mode that substitution cannot take it out:
  // |K_xy K_yx| / (2 zeta)^2 = 0.49 / 0.0016 >> 1.
  Eigen::MatrixXd strong(2, 2);
  strong << 0.0, 0.7, 0.7, 0.0;
  hc::DynamicStageDecoupler::PathShapes light(
      2, std::vector<std::optional<hc::CouplingPathShape>>(
             2, hc::CouplingPathShape{0.0, {{{1500.0, 0.02}, 1.0}}, 0.0}));
  const hc::DynamicStageDecoupler diverging(strong, light, kDt);
  EXPECT_NE(refusal([&] { (void)diverging.own_targets(raster(200.0, 0.05)); }).find("diverge"),
            std::string::npos);
}

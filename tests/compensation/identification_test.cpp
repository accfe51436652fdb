// Identification: exact recovery of known models from noise-free data, the noise floor on noisy
// data, guaranteed invertibility, order / family / delay / creep selection, bad input, and the
// measured piezo record of the shared data set.
#include "hystbench/compensation/identification.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-3;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Decaying-amplitude sine (1 Hz) plus a faster component whose reversals make nested minor
// loops; `chirp` > 0 sweeps the frequency so that the same levels are crossed at several rates.
std::vector<double> rich_excitation(std::size_t n, double lo, double hi, double chirp = 0.0) {
  std::vector<double> u(n);
  const double mid = 0.5 * (lo + hi);
  const double half = 0.5 * (hi - lo);
  const double duration = static_cast<double>(n) * kDt;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * kDt;
    const double envelope = 1.0 - 0.8 * t / duration;
    const double phase = kTwoPi * (t + 0.5 * chirp * t * t / duration);
    u[k] = mid + half * envelope * (0.75 * std::sin(phase) + 0.25 * std::sin(4.3 * phase));
  }
  return u;
}

std::vector<double> times(std::size_t n) {
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) * kDt;
  return t;
}

std::vector<double> simulate(hc::HysteresisModel& model, const std::vector<double>& u) {
  model.reset(u.front());
  return model.simulate(u);
}

double relative_error(const std::vector<double>& got, const std::vector<double>& want) {
  EXPECT_EQ(got.size(), want.size());
  double err = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < std::min(got.size(), want.size()); ++i) {
    err = std::max(err, std::abs(got[i] - want[i]));
    scale = std::max(scale, std::abs(want[i]));
  }
  return scale > 0.0 ? err / scale : err;
}

double relative_error(double got, double want) {
  return std::abs(got - want) / std::max(std::abs(want), 1.0);
}

hc::FitOptions fixed_options(hc::ModelKind kind) {
  hc::FitOptions o;
  o.kind = kind;
  o.refine_thresholds = false;
  o.delay_samples = 0;
  return o;
}

// Cumulative play weights of a fitted model, for the invertibility bound.
std::vector<double> cumulative(const std::vector<double>& w) {
  std::vector<double> c(w.size());
  double s = 0.0;
  for (std::size_t i = 0; i < w.size(); ++i) c[i] = (s += w[i]);
  return c;
}

// A modified PI whose forward dead zone has w_0 = 1 (the normalisation the error model uses),
// thresholds inside the PI output range about `center`.
hc::ModifiedPiParameters known_mpi(std::mt19937_64& rng, const std::vector<double>& u) {
  hc::ModifiedPiParameters p;
  p.play = hystbench::testing::random_pi(rng, 8, 10.0);
  hc::PiModel pi(p.play);
  const std::vector<double> out = simulate(pi, u);
  const auto [lo, hi] = std::minmax_element(out.begin(), out.end());
  p.center = 0.5 * (*lo + *hi) + 0.1 * (*hi - *lo);
  const double h = 0.5 * (*hi - *lo);
  p.dead_zone.thresholds = {-0.6 * h, -0.3 * h, 0.0, 0.25 * h, 0.55 * h};
  p.dead_zone.weights = {0.4, -0.4, 1.0, -0.3, 0.8};  // cumulative 1.0 | 0.6, 1.0 | 0.7, 1.5
  return p;
}

}  // namespace

// ---------------------------------------------------------------- exact recovery (noise free)

TEST(Identification, RecoversPiParametersFromNoiseFreeData) {
  std::mt19937_64 rng(11);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0);
  const hc::PiParameters truth = hystbench::testing::random_pi(rng, 10, 10.0);
  hc::PiModel model(truth);
  const std::vector<double> y = simulate(model, u);

  hc::FitOptions o = fixed_options(hc::ModelKind::kPi);
  o.play_thresholds = truth.thresholds;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);

  ASSERT_EQ(r.model.hysteresis().kind(), hc::ModelKind::kPi);
  const auto& got = dynamic_cast<const hc::PiModel&>(r.model.hysteresis()).parameters();
  EXPECT_LT(relative_error(got.weights, truth.weights), 1e-6);
  EXPECT_LT(relative_error(got.offset, truth.offset), 1e-6);
  EXPECT_EQ(got.thresholds, truth.thresholds);
  EXPECT_LT(r.heldout.rmse_percent(), 1e-6);
  EXPECT_EQ(r.delay_samples, 0);
}

TEST(Identification, RecoversModifiedPiParametersFromNoiseFreeData) {
  std::mt19937_64 rng(12);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0);
  const hc::ModifiedPiParameters truth = known_mpi(rng, u);
  hc::ModifiedPiModel model(truth);
  const std::vector<double> y = simulate(model, u);

  // Thresholds fixed to the true ones: the plays', and the inverse dead zone's (what the
  // error model estimates on the output side).
  hc::FitOptions o = fixed_options(hc::ModelKind::kModifiedPi);
  o.play_thresholds = truth.play.thresholds;
  o.dead_zone_thresholds =
      hc::DeadZoneSuperposition(truth.dead_zone).inverse().parameters().thresholds;
  o.center = truth.center;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);

  ASSERT_EQ(r.model.hysteresis().kind(), hc::ModelKind::kModifiedPi);
  const auto& got = dynamic_cast<const hc::ModifiedPiModel&>(r.model.hysteresis()).parameters();
  EXPECT_LT(relative_error(got.play.weights, truth.play.weights), 1e-6);
  EXPECT_LT(relative_error(got.play.offset, truth.play.offset), 1e-6);
  EXPECT_LT(relative_error(got.dead_zone.thresholds, truth.dead_zone.thresholds), 1e-6);
  EXPECT_LT(relative_error(got.dead_zone.weights, truth.dead_zone.weights), 1e-6);
  EXPECT_EQ(got.center, truth.center);
  EXPECT_EQ(r.dead_zones, 2);
  EXPECT_LT(r.heldout.rmse_percent(), 1e-6);
}

// An rpi fit on the true thresholds, dead zones and centre: only weights and the rate law left.
hc::FitResult fit_rate_law(const hc::RateDependentPiParameters& truth, const std::vector<double>& u,
                           const std::vector<double>& y) {
  hc::FitOptions o = fixed_options(hc::ModelKind::kRateDependentPi);
  o.play_thresholds = truth.base.play.thresholds;
  o.dead_zone_thresholds =
      hc::DeadZoneSuperposition(truth.base.dead_zone).inverse().parameters().thresholds;
  o.center = truth.base.center;
  return hc::fit_model(times(u.size()), u, y, o);
}

TEST(Identification, RecoversRateDependentWeightsFromNoiseFreeData) {
  // Frequency sweep: the same input levels are crossed at different rates.
  std::mt19937_64 rng(13);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0, 3.0);
  hc::RateDependentPiParameters truth;
  truth.base = known_mpi(rng, u);
  const std::size_t n = truth.base.play.weights.size();
  for (std::size_t i = 0; i < n; ++i) truth.rate_coefficients.push_back(5e-4 * (1.0 + 0.1 * i));
  truth.max_rate = 300.0;
  hc::RateDependentPiModel model(truth, kDt);
  ASSERT_TRUE(model.invertibility().invertible);
  const std::vector<double> y = simulate(model, u);

  const hc::FitResult r = fit_rate_law(truth, u, y);

  ASSERT_EQ(r.model.hysteresis().kind(), hc::ModelKind::kRateDependentPi);
  const auto& got =
      dynamic_cast<const hc::RateDependentPiModel&>(r.model.hysteresis()).parameters();
  EXPECT_LT(relative_error(got.base.play.weights, truth.base.play.weights), 1e-6);
  EXPECT_LT(relative_error(got.rate_coefficients, truth.rate_coefficients), 1e-6);
  EXPECT_LT(relative_error(got.base.dead_zone.weights, truth.base.dead_zone.weights), 1e-6);
  // max_rate is the fastest rate of the record, and the model is invertible up to it.
  EXPECT_GT(got.max_rate, 0.0);
  EXPECT_TRUE(r.model.hysteresis().invertibility().invertible);
}

// The record says which rate law its actuator follows: a signed-rate truth (the paper's eq. 16)
// is fitted with the signed law and a |du/dt| truth with the magnitude, each exactly. Both laws
// widen the loop with rate, as the fit constrains them: the magnitude's weights grow with |rate|,
// the signed law's fall with the rate (lower on loading, higher on unloading).
TEST(Identification, TellsTheSignedRateLawFromItsMagnitude) {
  std::mt19937_64 rng(13);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0, 3.0);
  for (const hc::RateLaw law : {hc::RateLaw::kSigned, hc::RateLaw::kMagnitude}) {
    hc::RateDependentPiParameters truth;
    truth.base = known_mpi(rng, u);
    for (std::size_t i = 0; i < truth.base.play.weights.size(); ++i)
      truth.rate_coefficients.push_back((law == hc::RateLaw::kSigned ? -1e-4 : 2e-4) *
                                        (1.0 + 0.1 * static_cast<double>(i)));
    truth.max_rate = 300.0;
    truth.rate_law = law;
    hc::RateDependentPiModel model(truth, kDt);
    ASSERT_TRUE(model.invertibility().invertible) << hc::to_string(law);
    const std::vector<double> y = simulate(model, u);

    const hc::FitResult r = fit_rate_law(truth, u, y);
    ASSERT_EQ(r.model.hysteresis().kind(), hc::ModelKind::kRateDependentPi);
    const auto& got =
        dynamic_cast<const hc::RateDependentPiModel&>(r.model.hysteresis()).parameters();
    EXPECT_EQ(got.rate_law, law) << hc::to_string(law);
    EXPECT_LT(relative_error(got.rate_coefficients, truth.rate_coefficients), 1e-6)
        << hc::to_string(law);
    EXPECT_LT(relative_error(got.base.play.weights, truth.base.play.weights), 1e-6)
        << hc::to_string(law);
    EXPECT_TRUE(r.model.hysteresis().invertibility().invertible) << hc::to_string(law);
  }
}

// A truth whose thresholds widen with |du/dt| (Al Janaideh's dynamic thresholds) is fitted
// with that law, its widening and rate filter found on the record, and it predicts the held-out
// part as well as the truth does; the weight laws, tried beside it, do not.
TEST(Identification, RecoversTheThresholdsLawFromNoiseFreeData) {
  std::mt19937_64 rng(13);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0, 3.0);
  hc::RateDependentPiParameters truth;
  truth.base = known_mpi(rng, u);
  truth.rate_coefficients.assign(truth.base.play.weights.size(), 0.0);
  truth.rate_law = hc::RateLaw::kThresholds;
  truth.max_rate = hc::smooth_max_rate(u, kDt);
  truth.threshold_rate_s = 0.03 * 10.0 / truth.max_rate;  // 3 % of the span at the fastest
  truth.rate_filter_s = 2.0 * kDt;
  hc::RateDependentPiModel model(truth, kDt);
  const std::vector<double> y = simulate(model, u);

  const hc::FitResult r = fit_rate_law(truth, u, y);

  ASSERT_EQ(r.model.hysteresis().kind(), hc::ModelKind::kRateDependentPi);
  const auto& got =
      dynamic_cast<const hc::RateDependentPiModel&>(r.model.hysteresis()).parameters();
  EXPECT_EQ(got.rate_law, hc::RateLaw::kThresholds);
  EXPECT_NEAR(got.threshold_rate_s, truth.threshold_rate_s, 0.05 * truth.threshold_rate_s);
  EXPECT_DOUBLE_EQ(got.rate_filter_s, truth.rate_filter_s);
  EXPECT_LT(r.heldout.rmse_percent(), 0.1);
  // The best weight law on the same record, for comparison.
  double weights_best = INFINITY;
  for (const auto& c : r.candidates) {
    if (c.method.find("rate-joint") != std::string::npos) {
      weights_best = std::min(weights_best, c.heldout_rmse);
    }
  }
  EXPECT_LT(r.heldout.rmse, 0.5 * weights_best);
}

// A rate law that levels off inside the record's rates (the paper's weights saturate at high
// rates) is found on the cap grid, and the model keeps both the cap and the record's range.
TEST(Identification, FindsWhereTheRateLawLevelsOff) {
  std::mt19937_64 rng(13);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0, 3.0);
  const double record_rate = hc::smooth_max_rate(u, kDt);
  hc::RateDependentPiParameters truth;
  truth.base = known_mpi(rng, u);
  for (std::size_t i = 0; i < truth.base.play.weights.size(); ++i)
    truth.rate_coefficients.push_back(5e-4 * (1.0 + 0.1 * i));
  truth.max_rate = 0.64 * record_rate;  // a point of the grid
  hc::RateDependentPiModel model(truth, kDt);
  const std::vector<double> y = simulate(model, u);

  const hc::FitResult r = fit_rate_law(truth, u, y);
  const auto& got =
      dynamic_cast<const hc::RateDependentPiModel&>(r.model.hysteresis()).parameters();
  EXPECT_NEAR(got.max_rate, truth.max_rate, 1e-9 * record_rate);
  EXPECT_NEAR(got.record_max_rate, record_rate, 1e-9 * record_rate);
  EXPECT_LT(relative_error(got.rate_coefficients, truth.rate_coefficients), 1e-6);
  EXPECT_LT(r.fit.rmse, 1e-6);
}

TEST(Identification, FindsCoupledPlayAsymmetryOnItsGrid) {
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0);
  hc::CoupledPlayParameters truth;
  truth.r = hc::uniform_thresholds(8, 5.0);
  for (const double r : truth.r) {
    // rc > r + rb, or the level switch never acts on an input >= 0; rc < max(u), or the
    // operator never rises again.
    truth.ra.push_back(0.7 * r), truth.rb.push_back(0.7 * r), truth.rc.push_back(2.0 * r);
  }
  // Non-negative: a jumping operator with a negative weight would make the output fall as the
  // input rises (not invertible); a zero weight puts the fit on its bound.
  truth.weights = {1.0, 0.3, 0.0, 0.2, 0.1, 0.05, 0.15, 0.05};
  truth.offset = 3.0;
  hc::CoupledPlayPiModel model(truth);
  const std::vector<double> y = simulate(model, u);

  hc::FitOptions o = fixed_options(hc::ModelKind::kCoupledPlayPi);
  o.play_thresholds = truth.r;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);

  const auto& got = dynamic_cast<const hc::CoupledPlayPiModel&>(r.model.hysteresis()).parameters();
  EXPECT_LT(relative_error(got.rb, truth.rb), 1e-12);
  EXPECT_LT(relative_error(got.rc, truth.rc), 1e-12);
  EXPECT_LT(relative_error(got.weights, truth.weights), 1e-6);
  EXPECT_LT(r.heldout.rmse_percent(), 1e-6);
}

// A saturating output map (a modified PI's dead zones) is what coupled plays cannot form: their
// widths depend on the input level, not the output. The coupled-play family's output dead-zone
// stage fits it as the modified PI does, and the scales are searched on top of it.
TEST(Identification, CoupledPlayFitsAnOutputSaturationWithItsDeadZones) {
  std::mt19937_64 rng(33);
  const std::vector<double> u = rich_excitation(12000, 0.0, 10.0);
  hc::ModifiedPiModel model(known_mpi(rng, u));
  const std::vector<double> y = simulate(model, u);
  const hc::FitResult mpi =
      hc::fit_model(times(u.size()), u, y, fixed_options(hc::ModelKind::kModifiedPi));
  hc::FitOptions o = fixed_options(hc::ModelKind::kCoupledPlayPi);
  const hc::FitResult cpi = hc::fit_model(times(u.size()), u, y, o);
  o.dead_zones = 0;  // the coupled-play paper's model: plays only
  const hc::FitResult plays_only = hc::fit_model(times(u.size()), u, y, o);

  ASSERT_EQ(cpi.model.hysteresis().kind(), hc::ModelKind::kCoupledPlayPi);
  const auto& p = dynamic_cast<const hc::CoupledPlayPiModel&>(cpi.model.hysteresis()).parameters();
  EXPECT_TRUE(p.has_dead_zones());
  EXPECT_EQ(p.rb, p.r);  // the truth is symmetric: no asymmetry beats the modified PI
  EXPECT_EQ(p.rc, p.r);
  EXPECT_EQ(cpi.dead_zones, mpi.dead_zones);
  EXPECT_TRUE(cpi.model.hysteresis().invertibility().invertible);
  // Unit scales make it the modified PI: never worse than it on held-out data.
  EXPECT_LE(cpi.heldout.rmse, mpi.heldout.rmse * (1.0 + 1e-6) + 1e-12);
  EXPECT_EQ(plays_only.dead_zones, 0);
  // The saturation is what plays alone cannot shape: about a third of their error here.
  EXPECT_LT(cpi.heldout.rmse, 0.5 * plays_only.heldout.rmse)
      << "with dead zones " << cpi.heldout.rmse << ", plays only " << plays_only.heldout.rmse
      << ", mpi " << mpi.heldout.rmse;
}

TEST(Identification, TriangularMethodRecoversPiFromOneAscendingBranch) {
  std::vector<double> thresholds = hc::uniform_thresholds(6, 2.0);  // span 4: r_i = i * 4 / 12
  const hc::PiParameters truth{thresholds, {0.8, 0.3, -0.1, 0.25, 0.2, -0.05}, 1.5};
  hc::PiModel model(truth);
  // On a grid that holds the band edges -1 + i * 4/6 (y is piecewise linear between them).
  auto level = [](int k) { return -1.0 + 4.0 * k / 600.0; };
  model.reset(-1.0);
  for (int k = 0; k <= 600; ++k) model.step(level(k));  // up to the maximum
  for (int k = 600; k >= 0; --k) model.step(level(k));  // and down to the minimum
  std::vector<double> ub, yb;
  for (int k = 0; k <= 600; ++k) {
    ub.push_back(level(k));
    yb.push_back(model.step(ub.back()));
  }
  const hc::PiParameters got = hc::identify_pi_triangular(ub, yb, 6);
  EXPECT_LT(relative_error(got.thresholds, truth.thresholds), 1e-9);
  EXPECT_LT(relative_error(got.weights, truth.weights), 1e-9);
  EXPECT_NEAR(got.offset, truth.offset, 1e-9);

  EXPECT_THROW(hc::identify_pi_triangular(ub, std::vector<double>(3), 6), std::invalid_argument);
  std::vector<double> down(ub.rbegin(), ub.rend());
  EXPECT_THROW(hc::identify_pi_triangular(down, yb, 6), std::invalid_argument);
  EXPECT_THROW(hc::identify_pi_triangular(ub, yb, 0), std::invalid_argument);
}

// ------------------------------------------------------------------------ noisy data

TEST(Identification, ReachesTheNoiseFloorOnNoisyData) {
  std::mt19937_64 rng(21);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0);
  const hc::ModifiedPiParameters truth = known_mpi(rng, u);
  for (const bool modified : {false, true}) {
    std::unique_ptr<hc::HysteresisModel> model;
    if (modified) {
      model = std::make_unique<hc::ModifiedPiModel>(truth);
    } else {
      model = std::make_unique<hc::PiModel>(truth.play);
    }
    std::vector<double> y = simulate(*model, u);
    const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
    const double sigma = 0.005 * (*hi - *lo);
    std::normal_distribution<double> noise(0.0, sigma);
    for (double& v : y) v += noise(rng);

    hc::FitOptions o;  // everything automatic: order, thresholds (refined), delay
    o.kind = modified ? hc::ModelKind::kModifiedPi : hc::ModelKind::kPi;
    const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
    std::cout << (modified ? "mpi" : "pi")
              << " on noisy data: held-out RMS / noise RMS = " << r.heldout.rmse / sigma << " ("
              << r.operators << " plays, m = " << r.dead_zones << ", " << r.method << ")\n";
    EXPECT_LT(r.heldout.rmse, 1.10 * sigma)
        << (modified ? "mpi" : "pi") << ": held-out RMS " << r.heldout.rmse << " vs noise " << sigma
        << " (" << r.operators << " plays, m = " << r.dead_zones << ", " << r.method << ")";
    EXPECT_GT(r.heldout.rmse, 0.9 * sigma);  // and does not claim to beat the noise
    EXPECT_TRUE(r.model.hysteresis().invertibility().invertible);
  }
}

// ------------------------------------------------------------------------ invertibility

TEST(Identification, ConstrainsCumulativeWeightsSoTheModelIsAlwaysInvertible) {
  // A branch that folds back (output falls while the input rises over part of the range) has
  // no invertible model; an unconstrained fit would give negative cumulative weights there.
  const std::vector<double> u = rich_excitation(8000, 0.0, 10.0);
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = u[k] + 3.0 * std::sin(1.3 * u[k]);
  hc::FitOptions o = fixed_options(hc::ModelKind::kModifiedPi);
  o.operators = 20;
  o.dead_zones = 3;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
  const auto& mpi = dynamic_cast<const hc::ModifiedPiModel&>(r.model.hysteresis());
  EXPECT_TRUE(mpi.invertibility().invertible) << mpi.invertibility().reason;
  const std::vector<double> W = cumulative(mpi.parameters().play.weights);
  // The bound: min_cumulative_weight * (output span / input span) over the fitted part.
  const auto fitted = [&](const std::vector<double>& v) {
    const auto [lo, hi] = std::minmax_element(v.begin(), v.begin() + 6000);
    return *hi - *lo;
  };
  const double eps = o.min_cumulative_weight * fitted(y) / fitted(u);
  EXPECT_GE(*std::min_element(W.begin(), W.end()), eps * (1.0 - 1e-9));
  // The inverse can be built and round-trips the model.
  EXPECT_NO_THROW(hc::make_inverse(r.model));
}

// ------------------------------------------------------------------------ selection

TEST(Identification, ChoosesTheOrderByHeldOutErrorAndPrefersTheSmallerModel) {
  std::mt19937_64 rng(31);
  const std::vector<double> u = rich_excitation(12000, 0.0, 10.0);
  // True thresholds: the uniform set the identification tries for 6 plays.
  hc::PiParameters truth = hystbench::testing::random_pi(rng, 6, 10.0);
  const auto [lo, hi] = std::minmax_element(u.begin(), u.begin() + 9000);
  truth.thresholds = hc::uniform_thresholds(6, 0.5 * (*hi - *lo));
  hc::PiModel model(truth);
  const std::vector<double> y = simulate(model, u);
  hc::FitOptions o = fixed_options(hc::ModelKind::kPi);
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
  EXPECT_EQ(r.operators, 6);  // 12 and 30 contain the same thresholds but are larger
  EXPECT_LT(r.heldout.rmse_percent(), 1e-6);
  EXPECT_GT(r.candidates.size(), 3u);
}

TEST(Identification, AutomaticFamilyPrefersModifiedPiForAsymmetricLoops) {
  std::mt19937_64 rng(32);
  const std::vector<double> u = rich_excitation(12000, 0.0, 10.0);
  hc::ModifiedPiModel model(known_mpi(rng, u));
  const std::vector<double> y = simulate(model, u);
  hc::FitOptions o;
  o.kind = std::nullopt;
  o.refine_thresholds = false;
  o.delay_samples = 0;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
  double best_pi = std::numeric_limits<double>::infinity();
  for (const auto& c : r.candidates) {
    if (c.kind == hc::ModelKind::kPi) best_pi = std::min(best_pi, c.heldout_rmse);
  }
  EXPECT_NE(r.model.hysteresis().kind(), hc::ModelKind::kPi);
  EXPECT_LT(r.heldout.rmse, 0.5 * best_pi);
}

TEST(Identification, FindsAPureInputDelay) {
  std::mt19937_64 rng(33);
  const std::vector<double> u = rich_excitation(8000, 0.0, 10.0);
  hc::ActuatorModel truth(std::make_unique<hc::ModifiedPiModel>(known_mpi(rng, u)));
  truth.set_delay(2 * kDt);
  const std::vector<double> y = truth.simulate(u, kDt);
  hc::FitOptions o;
  o.refine_thresholds = false;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
  EXPECT_EQ(r.delay_samples, 2);
  EXPECT_EQ(r.model.delay_samples(), 2u);
}

TEST(Identification, RefinesThresholdsOnlyWhenThatImprovesHeldOutError) {
  std::mt19937_64 rng(34);
  const std::vector<double> u = rich_excitation(8000, 0.0, 10.0);
  hc::PiModel model(hystbench::testing::random_pi(rng, 6, 10.0));  // irregular thresholds
  const std::vector<double> y = simulate(model, u);
  hc::FitOptions o = fixed_options(hc::ModelKind::kPi);
  o.operators = 6;
  const hc::FitResult plain = hc::fit_model(times(u.size()), u, y, o);
  o.refine_thresholds = true;
  const hc::FitResult refined = hc::fit_model(times(u.size()), u, y, o);
  EXPECT_LT(refined.heldout.rmse, 0.5 * plain.heldout.rmse);
  EXPECT_NE(refined.method.find("lm"), std::string::npos);
}

TEST(Identification, FitsCreepLagsJointlyWhenTheyHelp) {
  std::mt19937_64 rng(35);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0);
  hc::ActuatorModel truth(
      std::make_unique<hc::PiModel>(hystbench::testing::random_pi(rng, 6, 10.0)));
  const std::vector<double> taus = hc::log_spaced_time_constants(3, 1.0, 8.0);
  truth.set_creep(hc::CreepParameters{taus, {0.05, 0.08, 0.1}});
  const std::vector<double> y = truth.simulate(u, kDt);
  hc::FitOptions o = fixed_options(hc::ModelKind::kPi);
  o.play_thresholds = dynamic_cast<const hc::PiModel&>(truth.hysteresis()).parameters().thresholds;
  const hc::FitResult without = hc::fit_model(times(u.size()), u, y, o);
  o.creep_time_constants_s = taus;
  const hc::FitResult with = hc::fit_model_with_creep(times(u.size()), u, y, o);
  ASSERT_TRUE(with.creep);
  ASSERT_TRUE(with.model.creep().has_value());
  EXPECT_LT(relative_error(with.model.creep()->gains, {0.05, 0.08, 0.1}), 1e-6);
  EXPECT_LT(with.heldout.rmse_percent(), 1e-6);
  EXPECT_GT(without.heldout.rmse_percent(), 0.1);
}

// A bench's history: the creep of earlier runs still settles during the record, a slow
// drift of the output that no hysteresis weight explains. With FitOptions::drift the fit
// fits it with the weights of every candidate and scores each with it (extrapolated over the
// held-out part), and the model is the hysteresis alone; exact for the classical PI, where the
// drift adds to the output.
TEST(Identification, TakesASlowDriftOffTheRecordBeforeFitting) {
  std::mt19937_64 rng(41);
  const std::vector<double> u = rich_excitation(20000, 0.0, 10.0);
  const hc::PiParameters truth = hystbench::testing::random_pi(rng, 8, 10.0);
  hc::PiModel model(truth);
  std::vector<double> y = simulate(model, u);
  const std::vector<double> clean = y;
  const double slope = -0.01;  // per s: 0.2 over the 20 s record
  for (std::size_t k = 0; k < y.size(); ++k) y[k] += slope * static_cast<double>(k) * kDt;

  hc::FitOptions o = fixed_options(hc::ModelKind::kPi);
  o.play_thresholds = truth.thresholds;
  const hc::FitResult plain = hc::fit_model(times(u.size()), u, y, o);
  o.drift = true;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
  EXPECT_NEAR(r.drift_per_s, slope, 1e-9);
  const auto& got = dynamic_cast<const hc::PiModel&>(r.model.hysteresis()).parameters();
  EXPECT_LT(relative_error(got.weights, truth.weights), 1e-6);
  EXPECT_LT(r.heldout.rmse_percent(), 1e-6);
  EXPECT_GT(plain.heldout.rmse_percent(), 100.0 * r.heldout.rmse_percent() + 0.1);
  ASSERT_FALSE(r.notes.empty());
  EXPECT_NE(r.notes.back().find("drift"), std::string::npos) << r.notes.back();

  // A record without drift: nothing is taken off, the truth is recovered as before.
  const hc::FitResult still = hc::fit_model(times(u.size()), u, clean, o);
  EXPECT_NEAR(still.drift_per_s, 0.0, 1e-9);
  EXPECT_LT(still.heldout.rmse_percent(), 1e-6);
}

// The modified PI through the defaults: every candidate fits the drift with its weights, before
// the output dead zone, so to first order.
TEST(Identification, TakesADriftOffAModifiedPiRecord) {
  std::mt19937_64 rng(42);
  // Loops of one amplitude throughout: a decaying one would move an asymmetric loop's mean
  // output in time too, and no record can tell that from a drift.
  std::vector<double> u(20000);
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double phase = kTwoPi * static_cast<double>(k) * kDt;
    u[k] = 5.0 + 5.0 * (0.75 * std::sin(phase) + 0.25 * std::sin(4.3 * phase));
  }
  hc::ModifiedPiModel model(known_mpi(rng, u));
  const std::vector<double> clean = simulate(model, u);
  const auto [lo, hi] = std::minmax_element(clean.begin(), clean.end());
  const double slope = 0.0005 * (*hi - *lo);  // per s: 1 % of the range over 20 s
  std::vector<double> y = clean;
  for (std::size_t k = 0; k < y.size(); ++k) y[k] += slope * static_cast<double>(k) * kDt;
  hc::FitOptions o;
  o.delay_samples = 0;
  const hc::FitResult reference = hc::fit_model(times(u.size()), u, clean, o);
  const hc::FitResult plain = hc::fit_model(times(u.size()), u, y, o);
  o.drift = true;
  const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
  std::cout << "drift " << r.drift_per_s << " of " << slope << "; held-out "
            << r.heldout.rmse_percent() << " %, without the drift option "
            << plain.heldout.rmse_percent() << " %, on the record without drift "
            << reference.heldout.rmse_percent() << " %; fit part " << r.fit.rmse_percent() << " %, "
            << r.operators << "/" << r.dead_zones << " (" << r.method << "), reference "
            << reference.operators << "/" << reference.dead_zones << "\n";
  // First order: the dead zone's slope varies over the range, the drift column's does not
  // (measured: 0.0044 for 0.0038 per s; held-out 0.081 % against 0.51 % without the option).
  EXPECT_NEAR(r.drift_per_s, slope, 0.3 * slope);
  EXPECT_LT(r.heldout.rmse_percent(), 0.25 * plain.heldout.rmse_percent());
}

// A measurement that starts where an earlier one left the actuator: the plays are not relaxed at
// u[0], so the first samples disagree with any model started at u[0]. By default the fit leaves
// out the start until the input has reached both its extremes, says so, and recovers the truth.
TEST(Identification, DefaultsLeaveOutTheStartFromAnUnknownState) {
  std::mt19937_64 rng(43);
  const hc::PiParameters p = hystbench::testing::random_pi(rng, 6, 6.0);
  hc::PiModel truth(p);
  std::vector<double> u = rich_excitation(6000, 0.0, 10.0);
  truth.reset(10.0);  // history: held at the top before the record
  truth.step(1.0);
  truth.step(u.front());
  const std::vector<double> y = truth.simulate(u);
  hc::FitOptions o = fixed_options(hc::ModelKind::kPi);
  o.skip_samples = std::nullopt;  // what `hystbench fit` does
  o.play_thresholds = p.thresholds;
  const hc::FitResult automatic = hc::fit_model(times(u.size()), u, y, o);
  EXPECT_GT(automatic.skipped_samples, 0u);
  EXPECT_LE(automatic.skipped_samples, (u.size() - u.size() / 4) / 4);
  ASSERT_FALSE(automatic.notes.empty());
  EXPECT_NE(automatic.notes.front().find("until the input reached both its extremes"),
            std::string::npos);
  o.skip_samples = 0;
  const hc::FitResult everything = hc::fit_model(times(u.size()), u, y, o);
  EXPECT_EQ(everything.skipped_samples, 0u);
  EXPECT_LT(automatic.fit.rmse_percent(), 0.01);
  EXPECT_GT(everything.fit.rmse_percent(), 10.0 * automatic.fit.rmse_percent());
}

// A richer family is never returned worse on held-out data than the classical PI it contains.
// Coupled plays fitted to a symmetric PI record with strong noise: whatever the asymmetry scales
// pick up of the noise, the result's held-out error is at most the PI's.
TEST(Identification, RicherFamilyIsNeverWorseThanTheClassicalPi) {
  std::mt19937_64 rng(44);
  hc::PiModel truth(hystbench::testing::random_pi(rng, 5, 10.0));
  const std::vector<double> u = rich_excitation(3000, 0.0, 10.0);
  std::vector<double> y = simulate(truth, u);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (double& v : y) v += noise(rng);
  hc::FitOptions o;
  o.kind = hc::ModelKind::kPi;
  const hc::FitResult pi = hc::fit_model(times(u.size()), u, y, o);
  for (const hc::ModelKind kind : {hc::ModelKind::kModifiedPi, hc::ModelKind::kCoupledPlayPi,
                                   hc::ModelKind::kRateDependentPi}) {
    o.kind = kind;
    const hc::FitResult r = hc::fit_model(times(u.size()), u, y, o);
    EXPECT_LE(r.heldout.rmse, pi.heldout.rmse * (1.0 + 1e-9)) << hc::to_string(kind);
    if (r.model.hysteresis().kind() == hc::ModelKind::kPi) {
      ASSERT_FALSE(r.notes.empty()) << hc::to_string(kind);
      EXPECT_NE(r.notes.back().find("fell back to the classical PI"), std::string::npos);
    }
  }
}

// ------------------------------------------------------------------------ reporting

TEST(Identification, ReportsErrorsOnFitAndHeldOutPartsAndModelMetadata) {
  std::mt19937_64 rng(41);
  const std::vector<double> u = rich_excitation(5000, -2.0, 8.0);
  hc::PiModel model(hystbench::testing::random_pi(rng, 5, 10.0));
  std::vector<double> y = simulate(model, u);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (double& v : y) v += noise(rng);
  hc::FitOptions o = fixed_options(hc::ModelKind::kPi);
  o.heldout_fraction = 0.3;
  o.skip_samples = 100;
  o.units = {"V", "nm"};
  std::vector<double> fractions;
  o.progress = [&](double f, const std::string& what) {
    EXPECT_FALSE(what.empty());
    fractions.push_back(f);
  };
  const std::vector<double> t = times(u.size());
  const hc::FitResult r = hc::fit_model(t, u, y, o);

  EXPECT_EQ(r.heldout_samples, 1500u);
  EXPECT_EQ(r.fit_samples, 5000u - 1500u - 100u);
  EXPECT_EQ(r.heldout.samples, 1500u);
  EXPECT_EQ(r.fit.samples, r.fit_samples);
  const hc::ModelScore s = hc::score_model(r.model, t, u, y, 0.3, 100);
  EXPECT_DOUBLE_EQ(s.heldout.rmse, r.heldout.rmse);
  EXPECT_DOUBLE_EQ(s.fit.max_abs, r.fit.max_abs);
  EXPECT_GT(r.heldout.range, 0.0);
  EXPECT_NEAR(r.heldout.rmse_percent(), 100.0 * r.heldout.rmse / r.heldout.range, 1e-12);
  EXPECT_DOUBLE_EQ(r.model.input_min, *std::min_element(u.begin(), u.end()));
  EXPECT_DOUBLE_EQ(r.model.input_max, *std::max_element(u.begin(), u.end()));
  EXPECT_EQ(r.model.units.output, "nm");
  EXPECT_DOUBLE_EQ(r.model.sample_period(), kDt);
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
}

TEST(Identification, RejectsBadRecordsWithClearMessages) {
  const std::vector<double> u = rich_excitation(200, 0.0, 1.0);
  const std::vector<double> t = times(u.size());
  const std::vector<double> y = u;
  auto message = [](auto&& call) -> std::string {
    try {
      call();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no exception)";
  };
  auto fit = [](std::vector<double> t, std::vector<double> u, std::vector<double> y,
                hc::FitOptions o = {}) { return [=] { hc::fit_model(t, u, y, o); }; };
  const std::vector<double> short_u(u.begin(), u.begin() + 49);
  EXPECT_NE(message(fit(times(49), short_u, short_u)).find("at least 50 samples"),
            std::string::npos);
  EXPECT_NE(message(fit(t, std::vector<double>(200, 1.5), y)).find("constant"), std::string::npos);
  EXPECT_NE(message(fit(t, u, std::vector<double>(200, 2.0))).find("constant"), std::string::npos);
  std::vector<double> bad = u;
  bad[17] = std::nan("");
  EXPECT_NE(message(fit(t, bad, y)).find("u[17]"), std::string::npos);
  bad = y;
  bad[3] = std::numeric_limits<double>::infinity();
  EXPECT_NE(message(fit(t, u, bad)).find("y[3]"), std::string::npos);
  EXPECT_NE(message(fit(t, u, std::vector<double>(199, 0.0))).find("same length"),
            std::string::npos);
  std::vector<double> bad_t = t;
  bad_t[50] = bad_t[49];
  EXPECT_NE(message(fit(bad_t, u, y)).find("strictly increasing"), std::string::npos);
  hc::FitOptions o;
  o.heldout_fraction = 1.5;
  EXPECT_NE(message(fit(t, u, y, o)).find("heldout_fraction"), std::string::npos);
  o = {};
  o.min_cumulative_weight = 0.0;
  EXPECT_NE(message(fit(t, u, y, o)).find("min_cumulative_weight"), std::string::npos);
  o = {};
  o.play_thresholds = {0.1, 0.2};
  EXPECT_NE(message(fit(t, u, y, o)).find("play_thresholds[0]"), std::string::npos);
  o = {};
  o.skip_samples = 190;
  EXPECT_NE(message(fit(t, u, y, o)).find("too few samples"), std::string::npos);
}

// ------------------------------------------------------------------------ measured data

namespace {

struct Columns {
  std::vector<double> u, y;
};

// Whitespace-separated, no header: column 1 input [V], column 5 output [um].
Columns read_dat(const std::filesystem::path& path) {
  Columns c;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::vector<double> v;
    double x;
    while (fields >> x) v.push_back(x);
    if (v.size() < 5) continue;
    c.u.push_back(v[0]);
    c.y.push_back(v[4]);
  }
  return c;
}

// RMS of measured - predicted on rows [begin, end) with the per-segment mean removed.
double segment_rms(const std::vector<double>& y, const std::vector<double>& yhat, std::size_t begin,
                   std::size_t end) {
  double mean = 0.0;
  for (std::size_t k = begin; k < end; ++k) mean += y[k] - yhat[k];
  mean /= static_cast<double>(end - begin);
  double sum = 0.0;
  for (std::size_t k = begin; k < end; ++k) sum += std::pow(y[k] - yhat[k] - mean, 2);
  return std::sqrt(sum / static_cast<double>(end - begin));
}

}  // namespace

TEST(IdentificationMeasured, PiezoNtuModelPredictsTheTrackingRun) {
  const std::filesystem::path dir =
      std::filesystem::path(HYSTBENCH_SHARED_DATA_DIR) / "piezo-ntu-dbo";
  if (!std::filesystem::exists(dir / "Model_Vi_Do.dat") ||
      !std::filesystem::exists(dir / "Test_Vi_Do_Di.dat")) {
    GTEST_SKIP() << "measured data not found in " << dir
                 << " (set HYSTBENCH_SHARED_DATA_DIR to the shared data folder)";
  }
  const Columns ident = read_dat(dir / "Model_Vi_Do.dat");
  const Columns test = read_dat(dir / "Test_Vi_Do_Di.dat");
  ASSERT_GT(ident.u.size(), 8000u);
  ASSERT_GT(test.u.size(), 14000u);
  constexpr double kTs = 1.0 / 200.0;  // 200 Hz
  std::vector<double> t(ident.u.size());
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) * kTs;

  hc::FitOptions o;
  o.kind = hc::ModelKind::kModifiedPi;
  o.skip_samples = 200;  // the first 1 Hz cycle starts from an unknown state (README)
  o.creep = true;        // slight drift over the record
  const hc::FitResult r = hc::fit_model(t, ident.u, ident.y, o);
  EXPECT_TRUE(r.model.hysteresis().invertibility().invertible);
  EXPECT_GE(r.delay_samples, 1);  // at least the documented one-sample sensor delay

  hc::ActuatorModel model = r.model;
  const std::vector<double> yhat = model.simulate(test.u, kTs);
  const std::size_t segments[3][2] = {{1200, 2800}, {7600, 9200}, {12400, 14000}};
  std::cout << "piezo-ntu-dbo: " << to_string(r.model.hysteresis().kind()) << " " << r.operators
            << " plays, m = " << r.dead_zones << ", delay " << r.delay_samples << " samples, creep "
            << r.creep << ", " << r.method << "; fit RMS " << r.fit.rmse << " um, held-out RMS "
            << r.heldout.rmse << " um (" << r.heldout.rmse_percent() << " %)\n";
  for (const auto& s : segments) {
    const double rms = segment_rms(test.y, yhat, s[0], s[1]);
    std::cout << "  tracking run rows " << s[0] << "-" << s[1] << ": prediction RMS " << rms
              << " um\n";
    EXPECT_LE(rms, 0.30) << "rows " << s[0] << "-" << s[1];
  }
}

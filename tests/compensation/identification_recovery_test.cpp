// Identification recovers known models exactly from noise-free data: the classical, modified,
// rate-dependent (each rate law) and coupled-play PI, and the classical-PI paper's triangular
// method on one branch.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"
#include "support/identification_records.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;
using hystbench::testing::fixed_options;
using hystbench::testing::known_mpi;
using hystbench::testing::relative_error;
using hystbench::testing::rich_excitation;
using hystbench::testing::simulate;
using hystbench::testing::times;

namespace {

constexpr double kDt = hystbench::testing::kRecordDt;

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
  // The saturation is what plays alone cannot shape: the dead zones take off more than half
  // their error.
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

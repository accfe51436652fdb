// Property tests: model(inverse(y_ref)) == y_ref for random invertible models and signals.
#include "hystbench/compensation/inverse_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>
#include <random>
#include <span>
#include <sstream>

#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;
using hystbench::testing::random_mpi;
using hystbench::testing::random_pi;
using hystbench::testing::random_reversal_signal;

namespace {

// A reachable reference: the model's own response to a random input (from a relaxed state).
std::vector<double> reachable_reference(hc::HysteresisModel& model, std::mt19937_64& rng,
                                        std::size_t n, double lo, double hi) {
  auto copy = model.clone();
  copy->reset(lo);
  return copy->simulate(random_reversal_signal(rng, n, lo, hi));
}

double range_of(const std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

// Returns max |model(inverse(y_ref)) - y_ref| over the signal.
double composition_error(hc::HysteresisModel& model, hc::InverseModel& inverse,
                         const std::vector<double>& y_ref) {
  double worst = 0.0;
  for (const double yr : y_ref) {
    const double u = inverse.step(yr);
    worst = std::max(worst, std::abs(model.step(u) - yr));
  }
  return worst;
}

}  // namespace

TEST(PiInverse, ComposesToIdentityForRandomModelsAndSignals) {
  std::mt19937_64 rng(2024);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 40);
    hc::PiModel model(random_pi(rng, n, 150.0));
    const auto y_ref = reachable_reference(model, rng, 3000, 0.0, 150.0);
    model.reset(0.0);
    hc::PiInverse inverse(model);
    const double err = composition_error(model, inverse, y_ref);
    EXPECT_LE(err, 1e-9 * range_of(y_ref)) << "trial " << trial << " n=" << n;
  }
}

TEST(ModifiedPiInverse, ComposesToIdentityForRandomModelsAndSignals) {
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 30);
    const int m = static_cast<int>(rng() % 6);
    hc::ModifiedPiModel model(random_mpi(rng, n, m, 150.0));
    const auto y_ref = reachable_reference(model, rng, 3000, 0.0, 150.0);
    model.reset(0.0);
    hc::ModifiedPiInverse inverse(model);
    const double err = composition_error(model, inverse, y_ref);
    EXPECT_LE(err, 1e-9 * range_of(y_ref)) << "trial " << trial << " n=" << n << " m=" << m;
  }
}

// The inverse can be started from any model state (not only a relaxed one).
TEST(PiInverse, StartsConsistentlyFromAnArbitraryModelState) {
  std::mt19937_64 rng(5);
  hc::ModifiedPiModel model(random_mpi(rng, 15, 3, 100.0));
  model.reset(0.0);
  for (double u : random_reversal_signal(rng, 777, 0.0, 100.0)) model.step(u);
  hc::ModifiedPiInverse inverse(model);  // built from the current state
  auto probe = model.clone();
  std::vector<double> y_ref = probe->simulate(random_reversal_signal(rng, 2000, 0.0, 100.0));
  EXPECT_LE(composition_error(model, inverse, y_ref), 1e-9 * range_of(y_ref));
}

TEST(MakeInverse, RefusesNonInvertibleModelsNamingTheIndex) {
  hc::ActuatorModel model(std::make_unique<hc::PiModel>(
      hc::PiParameters{{0.0, 1.0, 2.0, 3.0}, {1.0, 0.5, -2.0, 0.2}, 0.0}));
  try {
    (void)hc::make_inverse(model);
    FAIL() << "expected NotInvertibleError";
  } catch (const hc::NotInvertibleError& e) {
    EXPECT_EQ(e.why().index, 2);
    EXPECT_EQ(e.why().block, "play");
    EXPECT_NE(std::string(e.what()).find("W[2]"), std::string::npos);
  }
}

TEST(NumericInverse, ComposesForCoupledPlayModels) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    hc::CoupledPlayParameters p;
    const int n = 8;
    for (int i = 0; i < n; ++i) {
      p.r.push_back(i * 5.0);
      const double rb = i * 5.0 * (0.5 + unit(rng));
      p.ra.push_back(rb * unit(rng));  // ra <= rb
      p.rb.push_back(rb);
      p.rc.push_back(i * 5.0 * (1.0 + unit(rng)));  // rc >= r
      p.weights.push_back(i == 0 ? 0.3 + unit(rng) : 0.1 * unit(rng));
    }
    hc::ActuatorModel model(std::make_unique<hc::CoupledPlayPiModel>(p));
    model.input_min = -100.0;
    model.input_max = 100.0;
    model.configure(1e-4);
    const auto y_ref = reachable_reference(model.hysteresis(), rng, 2000, -80.0, 80.0);
    auto inverse = hc::make_inverse(model);
    model.reset(-80.0);
    inverse->reset(-80.0);
    EXPECT_LE(composition_error(model.hysteresis(), *inverse, y_ref), 1e-7 * range_of(y_ref))
        << "trial " << trial;
  }
}

TEST(CoupledPlayPiModel, NonMonotoneOperatorIsReportedNotInverted) {
  hc::ActuatorModel model(std::make_unique<hc::CoupledPlayPiModel>(
      hc::CoupledPlayParameters{{0, 2}, {0, 1}, {0, 1}, {0, 1}, {1.0, 0.5}, 0.0, {}, 0.0}));
  model.input_min = -10;
  model.input_max = 10;
  try {
    (void)hc::make_inverse(model);
    FAIL() << "expected NotInvertibleError";
  } catch (const hc::NotInvertibleError& e) {
    EXPECT_EQ(e.why().index, 1);  // rc = 1 < r = 2
  }
}

// An operator whose width switches at rc > r jumps up as a rising input crosses rc; with a
// negative weight that jump lowers the output although the cumulative weights stay positive.
TEST(CoupledPlayPiModel, NegativeWeightOnAJumpingOperatorIsReportedNotInverted) {
  const hc::CoupledPlayParameters p{{0, 2}, {0, 2}, {0, 2}, {0, 6}, {1.0, -0.5}, 0.0, {}, 0.0};
  hc::CoupledPlayPiModel model(p);
  model.reset(0.0);
  double before = model.step(5.9);
  EXPECT_LT(model.step(6.1), before);  // the fall the check names
  const hc::Invertibility why = model.invertibility();
  EXPECT_FALSE(why.invertible);
  EXPECT_EQ(why.index, 1);
  hc::CoupledPlayParameters q = p;
  q.rc = {0, 2};  // no jump: a negative increment is fine while the cumulative weight is > 0
  EXPECT_TRUE(hc::CoupledPlayPiModel(q).invertibility().invertible);
}

// An RPI with zero rate coefficients is the modified PI it extends: its numeric inverse composes
// exactly on any reachable reference, however fast (the rate law is covered on a sine below).
TEST(NumericInverse, ComposesForARateFreeRateDependentModel) {
  std::mt19937_64 rng(23);
  auto base = random_mpi(rng, 10, 2, 100.0);
  hc::ActuatorModel model(std::make_unique<hc::RateDependentPiModel>(
      hc::RateDependentPiParameters{base, std::vector<double>(10, 0.0), 1e4, 0.0}, 1e-2));
  model.input_min = -50.0;
  model.input_max = 150.0;
  model.configure(1e-2);
  const auto y_ref = reachable_reference(model.hysteresis(), rng, 3000, 0.0, 100.0);
  auto inverse = hc::make_inverse(model);
  model.reset(0.0);
  inverse->reset(0.0);
  EXPECT_LE(composition_error(model.hysteresis(), *inverse, y_ref), 1e-7 * range_of(y_ref));
}

TEST(NumericInverse, SaturatesAtTheInputBoundForUnreachableTargets) {
  hc::ActuatorModel model(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 1.0}, {0.2, 0.1}, 0.0}));
  model.input_min = 0.0;
  model.input_max = 10.0;
  hc::NumericInverse inverse(model);
  inverse.reset(0.0);
  EXPECT_DOUBLE_EQ(inverse.step(1e6), 10.0);
  EXPECT_DOUBLE_EQ(inverse.step(-1e6), 0.0);
}

// A branch end nearly flat (cumulative weight 1e-4 after 120 V of travel): a target just below
// what 0 V reaches asks the unbounded inverse for hundreds of volts. The analytic inverses of a
// model with an input range give the bound instead, and their memory stays the actuator's:
// back within reach, the model composes to the reference again.
TEST(MakeInverse, AnalyticInversesSaturateAtTheInputRangeWithoutWindingUp) {
  const hc::PiParameters play{{0.0, 20.0, 60.0}, {0.3, 0.1, -0.3999}, 0.0};
  std::vector<std::unique_ptr<hc::HysteresisModel>> families;
  families.push_back(std::make_unique<hc::PiModel>(play));
  families.push_back(std::make_unique<hc::ModifiedPiModel>(
      hc::ModifiedPiParameters{play, {{-5.0, 0.0, 5.0}, {0.1, 1.0, 0.2}}, 20.0}));
  for (auto& family : families) {
    SCOPED_TRACE(std::string(hc::to_string(family->kind())));
    hc::ActuatorModel model(family->clone());
    model.input_min = 0.0;
    model.input_max = 150.0;
    model.reset(150.0);
    for (int k = 0; k <= 150; ++k) model.step(150.0 - k);  // the full sweep down to 0 V
    auto plant = model.hysteresis().clone();               // the actuator, in the same state
    const double y_floor = plant->peek(0.0);
    auto unbounded = family->clone();
    unbounded->reset(150.0);
    for (int k = 0; k <= 150; ++k) unbounded->step(150.0 - k);
    const auto raw = hc::make_inverse(hc::ActuatorModel(std::move(unbounded)));
    EXPECT_LT(raw->clone()->step(y_floor - 0.05), -100.0) << "the flat end's unbounded inverse";

    const auto inverse = hc::make_inverse(model);
    EXPECT_DOUBLE_EQ(inverse->step(y_floor - 0.05), 0.0);
    EXPECT_DOUBLE_EQ(inverse->step(1e6), 150.0);
    EXPECT_DOUBLE_EQ(inverse->step(-1e6), 0.0);
    plant->step(150.0);
    plant->step(0.0);
    std::vector<double> y_ref;
    for (int k = 0; k <= 400; ++k) y_ref.push_back(plant->peek(0.0) + 0.05 * k);  // reachable
    EXPECT_LE(composition_error(*plant, *inverse, y_ref), 1e-9 * range_of(y_ref));
  }
}

namespace {
// A random 15-play PI over 0-150 V, relaxed at 0.
hc::ActuatorModel relaxed_random_pi(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  hc::ActuatorModel model(std::make_unique<hc::PiModel>(random_pi(rng, 15, 150.0)));
  model.input_min = 0.0;
  model.input_max = 150.0;
  model.reset(0.0);
  return model;
}
}  // namespace

TEST(InverseMultiplicativeCompensator, TracksASlowReferenceClosely) {
  hc::ActuatorModel model = relaxed_random_pi(31);
  hc::InverseMultiplicativeCompensator comp(model);
  comp.reset(0.0);
  // 1 Hz sine over most of the range at 10 kHz.
  const double y_lo = model.peek_static(15.0), y_hi = model.peek_static(135.0);
  double worst = 0.0, worst_open_loop = 0.0;
  hc::ActuatorModel open(model);
  open.reset(0.0);
  for (int k = 0; k < 30000; ++k) {
    const double s = 0.5 - 0.5 * std::cos(2.0 * M_PI * k / 10000.0);
    const double yr = y_lo + (y_hi - y_lo) * s;
    const double y = model.step(comp.step(yr));
    const double y_lin = open.step(15.0 + 120.0 * s);  // linear map, no compensation
    if (k > 10000) {
      worst = std::max(worst, std::abs(y - yr));
      worst_open_loop = std::max(worst_open_loop, std::abs(y_lin - yr));
    }
  }
  EXPECT_LT(worst, 0.01 * (y_hi - y_lo));
  EXPECT_LT(worst, 0.2 * worst_open_loop);
}

// The structure's equation is solved within each tick for a rate-independent model: a 200 Hz
// sine (50 samples a period) on the exact model is followed to the solver's tolerance. The
// one-pass, one-tick-delayed loop trailed it (on the loopback: 8.5 % of range at 200 Hz, worse
// than no compensation).
TEST(InverseMultiplicativeCompensator, SolvesItsEquationWithinTheTickAtAFastReference) {
  hc::ActuatorModel model = relaxed_random_pi(32);
  hc::InverseMultiplicativeCompensator comp(model);
  comp.reset(0.0);
  const double y_lo = model.peek_static(15.0), y_hi = model.peek_static(135.0);
  double worst = 0.0;
  for (int k = 0; k < 500; ++k) {
    const double yr = y_lo + (y_hi - y_lo) * (0.5 - 0.5 * std::cos(2.0 * M_PI * k / 50.0));
    const double y = model.step(comp.step(yr));
    if (k >= 50) worst = std::max(worst, std::abs(y - yr));
  }
  EXPECT_LT(worst, 1e-6 * (y_hi - y_lo));
}

// Table 2 of the multilayer-actuator paper, shipped as model files, is invertible and its
// inverse composes to identity.
TEST(SeedTable, MultilayerPaperTable2LoadsAndInverts) {
  for (const char* name : {"multilayer-table2-pi.json", "multilayer-table2-mpi.json"}) {
    std::ifstream in(std::string(HYSTBENCH_SOURCE_DIR) + "/config/models/" + name);
    ASSERT_TRUE(in) << name;
    std::stringstream text;
    text << in.rdbuf();
    hc::ModelFile file = hc::parse_model_file(text.str());
    ASSERT_TRUE(file.model.hysteresis().invertibility().invertible) << name;
    std::mt19937_64 rng(1);
    const auto y_ref = reachable_reference(file.model.hysteresis(), rng, 4000, 0.0, 2.0);
    auto inverse = hc::make_inverse(file.model);
    file.model.reset(0.0);
    inverse->reset(0.0);
    EXPECT_LE(composition_error(file.model.hysteresis(), *inverse, y_ref), 1e-9 * range_of(y_ref))
        << name;
  }
}

// A stack-like rate-dependent modified PI: 10 plays on 0..150 V with positive weights (the first
// steepest), a mild one-sided dead zone, cumulative weights growing with |du/dt| as the loopback
// actuator's do (2e-6 per play per V/s), the rate filtered with time constant tau.
hc::ActuatorModel stack_rpi(double tau, double rate_scale, double dt,
                            hc::RateLaw law = hc::RateLaw::kMagnitude) {
  hc::PiParameters play;
  for (int i = 0; i < 10; ++i) {
    play.thresholds.push_back(7.5 * i);
    play.weights.push_back(i == 0 ? 0.2 : 0.05 * std::exp(-0.2 * i));
  }
  hc::DeadZoneParameters dz{{-5.0, 0.0, 5.0}, {0.1, 1.0, 0.15}};
  std::vector<double> c(10);
  for (int i = 0; i < 10; ++i) c[i] = rate_scale * 2e-6 * (i + 1);
  hc::RateDependentPiParameters p{hc::ModifiedPiParameters{play, dz, 20.0}, c, 5000.0, tau};
  p.rate_law = law;
  hc::ActuatorModel m(std::make_unique<hc::RateDependentPiModel>(p, dt));
  m.input_min = 0.0;
  m.input_max = 150.0;
  m.configure(dt);
  m.reset(0.0);
  return m;
}

// The rate-dependent inverse takes its rate from the reference (|dy_ref/dt| over the model's
// local slope), never from the drive it solves for: its drive is as smooth as the rate-independent
// inverse's over the same reference (it chattered when the candidate input set its own rate),
// and it composes with the model to the reference.
TEST(NumericInverse, RateDependentDriveIsSmoothAndComposesOnASine) {
  const double dt = 1e-4;
  for (const double tau : {0.0, 1e-3}) {
    hc::ActuatorModel rate_model = stack_rpi(tau, 1.0, dt);
    hc::ActuatorModel flat_model = stack_rpi(tau, 0.0, dt);
    auto rate_inverse = hc::make_inverse(rate_model);
    auto flat_inverse = hc::make_inverse(flat_model);
    // The reference: the rate-free model's output for a 10 Hz input sine over 15-135 V at 10 kHz
    // (reachable by construction), 3 periods.
    std::vector<double> reference;
    hc::ActuatorModel shaper = flat_model;
    for (int k = 0; k < 3000; ++k) {
      reference.push_back(
          shaper.step(75.0 - 60.0 * std::cos(2.0 * std::numbers::pi * 10.0 * k * dt)));
    }
    const auto [lo_it, hi_it] = std::minmax_element(reference.begin(), reference.end());
    const double y_lo = *lo_it, y_hi = *hi_it;
    rate_inverse->reset(15.0);
    flat_inverse->reset(15.0);
    rate_model.reset(15.0);
    double u_rate_prev = 15.0, u_flat_prev = 15.0, max_du_rate = 0.0, max_du_flat = 0.0;
    double worst = 0.0, worst_flat_on_rate = 0.0;
    double variation = 0.0, variation_flat = 0.0;  // total variation of the drives
    hc::ActuatorModel flat_driven = rate_model;    // the rate model under the rate-free inverse
    double sum2 = 0.0, sum2_flat = 0.0;
    for (int k = 0; k < 3000; ++k) {
      const double s = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * 10.0 * k * dt);
      const double yr = y_lo + (y_hi - y_lo) * s;
      const double u_rate = rate_inverse->step(yr);
      const double u_flat = flat_inverse->step(yr);
      const double y = rate_model.step(u_rate);
      const double y_flat = flat_driven.step(u_flat);
      if (k > 0) {
        max_du_rate = std::max(max_du_rate, std::abs(u_rate - u_rate_prev));
        max_du_flat = std::max(max_du_flat, std::abs(u_flat - u_flat_prev));
        variation += std::abs(u_rate - u_rate_prev);
        variation_flat += std::abs(u_flat - u_flat_prev);
      }
      if (k > 1000) {
        worst = std::max(worst, std::abs(y - yr));
        worst_flat_on_rate = std::max(worst_flat_on_rate, std::abs(y_flat - yr));
        sum2 += (y - yr) * (y - yr);
        sum2_flat += (y_flat - yr) * (y_flat - yr);
      }
      u_rate_prev = u_rate;
      u_flat_prev = u_flat;
    }
    const double rms = std::sqrt(sum2 / 1999.0), rms_flat = std::sqrt(sum2_flat / 1999.0);
    std::cout << "tau " << tau << ": rate inverse rms " << rms << " max " << worst
              << ", rate-free inverse rms " << rms_flat << " max " << worst_flat_on_rate
              << " (range " << y_hi - y_lo << "); max per-tick drive change " << max_du_rate
              << " vs " << max_du_flat << ", total variation " << variation << " vs "
              << variation_flat << "\n";
    EXPECT_LT(max_du_rate, 2.0 * max_du_flat) << "tau " << tau;
    // A chattering drive (as when the solved input set its own rate) travels many times as far.
    EXPECT_LT(variation, 1.2 * variation_flat) << "tau " << tau;
    // It follows the rate law: well under the rate-free inverse's error on the rate-dependent
    // model (what is left is at the reversals, where the rate changes fastest).
    EXPECT_LT(rms, 0.6 * rms_flat) << "tau " << tau;
  }
}

// The signed rate law whose weights grow with the rate: the output grows with the drive and with
// its own rate on both branches, so step() solves each tick at the drive's own rate, exactly and
// stably. On a 10 and a 19 Hz sine it composes with the model to the reference, and its drive
// is as smooth as the rate-free inverse's.
TEST(NumericInverse, TheSignedRateLawIsInvertedExactlyAtTheDrivesOwnRate) {
  const double dt = 1e-4;
  for (const double tau : {0.0, 1e-3}) {
    for (const double f : {10.0, 19.0}) {
      hc::ActuatorModel model = stack_rpi(tau, 1.0, dt, hc::RateLaw::kSigned);
      hc::ActuatorModel flat_model = stack_rpi(tau, 0.0, dt);
      model.reset(15.0);
      flat_model.reset(15.0);
      auto inverse = hc::make_inverse(model);
      auto flat_inverse = hc::make_inverse(flat_model);
      hc::ActuatorModel plant = model;
      const double y_lo = flat_model.peek_static(15.0), y_hi = y_lo + 30.0;
      double u_prev = 15.0, flat_prev = 15.0, max_du = 0.0, max_du_flat = 0.0, worst = 0.0;
      const int n = static_cast<int>(3.0 / f / dt);
      for (int k = 0; k < n; ++k) {
        const double s = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * f * k * dt);
        const double yr = y_lo + (y_hi - y_lo) * s;
        const double u = inverse->step(yr);
        const double u_flat = flat_inverse->step(yr);
        const double y = plant.step(u);
        if (k > 0) {
          max_du = std::max(max_du, std::abs(u - u_prev));
          max_du_flat = std::max(max_du_flat, std::abs(u_flat - flat_prev));
        }
        worst = std::max(worst, std::abs(y - yr));
        u_prev = u;
        flat_prev = u_flat;
      }
      EXPECT_LT(worst, 1e-6 * (y_hi - y_lo)) << "tau " << tau << " f " << f;
      EXPECT_LT(max_du, 2.0 * max_du_flat) << "tau " << tau << " f " << f;
      EXPECT_EQ(inverse->preview_samples(), 0u);  // no targets ahead needed
    }
  }
}

// model(inverse(y_ref)) = y_ref for every family the bench identifies (PI, modified PI,
// coupled-play, rate-dependent), each without and with creep lags, through make_inverse()
// exactly as `track` builds it: the analytic inverse where one exists, the numeric otherwise.
namespace {

enum class Family { kPi, kMpi, kCpi, kCpiDeadZones, kRpi };

struct FamilyCase {
  Family family;
  bool creep;
};

std::string case_name(const ::testing::TestParamInfo<FamilyCase>& info) {
  static const char* names[] = {"Pi", "Mpi", "Cpi", "CpiDeadZones", "Rpi"};
  return std::string(names[static_cast<int>(info.param.family)]) +
         (info.param.creep ? "WithCreep" : "");
}

// 100 Hz sampling keeps the random signal's rates where the rate-dependent model is invertible.
constexpr double kDt = 1e-2;

hc::ActuatorModel family_model(Family family, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::unique_ptr<hc::HysteresisModel> h;
  switch (family) {
    case Family::kPi:
      h = std::make_unique<hc::PiModel>(random_pi(rng, 12, 150.0));
      break;
    case Family::kMpi:
      h = std::make_unique<hc::ModifiedPiModel>(random_mpi(rng, 10, 2, 150.0));
      break;
    case Family::kCpi:
    case Family::kCpiDeadZones: {
      // As the identification builds them: r uniform, rb = ra = kb r, rc = kc r (kc >= 1),
      // optionally followed by the output dead zones of a modified PI.
      hc::CoupledPlayParameters p;
      const double kb = 0.5 + 1.5 * unit(rng), kc = 1.0 + 5.0 * unit(rng);
      for (int i = 0; i < 10; ++i) {
        const double r = i * 7.5;
        p.r.push_back(r);
        p.ra.push_back(kb * r);
        p.rb.push_back(kb * r);
        p.rc.push_back(kc * r);
        p.weights.push_back(i == 0 ? 0.2 + 0.1 * unit(rng) : 0.03 * unit(rng));
      }
      if (family == Family::kCpiDeadZones) {
        const hc::ModifiedPiParameters mpi = random_mpi(rng, 10, 2, 150.0);
        p.dead_zone = mpi.dead_zone;
        p.center = 20.0 + mpi.center;
      }
      h = std::make_unique<hc::CoupledPlayPiModel>(p);
      break;
    }
    case Family::kRpi: {
      std::vector<double> c(10);
      for (int i = 0; i < 10; ++i) c[i] = 2e-5 * i;
      h = std::make_unique<hc::RateDependentPiModel>(
          hc::RateDependentPiParameters{random_mpi(rng, 10, 2, 150.0), c, 1e4}, kDt);
      break;
    }
  }
  hc::ActuatorModel model(std::move(h));
  return model;
}

class EveryFamilyInverse : public ::testing::TestWithParam<FamilyCase> {};

}  // namespace

TEST_P(EveryFamilyInverse, ComposesToIdentityOnReachableReferences) {
  const FamilyCase fc = GetParam();
  std::mt19937_64 rng(101 + static_cast<int>(fc.family) * 2 + (fc.creep ? 1 : 0));
  for (int trial = 0; trial < 5; ++trial) {
    hc::ActuatorModel model = family_model(fc.family, rng);
    if (fc.creep) {
      // About 2 % of the output range, 0.05 to 50 s, as on the simulated actuator.
      model.set_creep(hc::CreepParameters{{0.05, 0.5, 5.0, 50.0}, {0.002, 0.002, 0.002, 0.002}});
    }
    // The rate-dependent map may need inputs beyond the reference's to hit it exactly.
    model.input_min = fc.family == Family::kRpi ? -50.0 : 0.0;
    model.input_max = fc.family == Family::kRpi ? 200.0 : 150.0;
    model.configure(kDt);
    // A reachable reference: the whole model's own response (creep included) from rest.
    const std::vector<double> u = random_reversal_signal(rng, 3000, 0.0, 150.0);
    hc::ActuatorModel source(model);
    const std::vector<double> y_ref = source.simulate(u, kDt);
    model.reset(u.front());
    hc::ActuatorModel plant(model);
    auto inverse = hc::make_inverse(model);
    double worst = 0.0, sum2 = 0.0;
    for (const double yr : y_ref) {
      const double e = plant.step(inverse->step(yr)) - yr;
      worst = std::max(worst, std::abs(e));
      sum2 += e * e;
    }
    if (fc.family != Family::kRpi) {
      EXPECT_LE(worst, 1e-7 * range_of(y_ref)) << "trial " << trial;
      continue;
    }
    // The rate-dependent inverse solves at a rate predicted from the reference, not from the
    // drive it solves for (that made it chatter), so it is not exact: it must beat the rate-free
    // inverse, which ignores the rate law, on the same plant and reference.
    const auto& rpi = dynamic_cast<const hc::RateDependentPiModel&>(model.hysteresis());
    hc::ActuatorModel rate_free(std::make_unique<hc::ModifiedPiModel>(rpi.parameters().base));
    rate_free.set_creep(model.creep());
    rate_free.input_min = model.input_min;
    rate_free.input_max = model.input_max;
    rate_free.configure(kDt);
    rate_free.reset(u.front());
    auto free_inverse = hc::make_inverse(rate_free);
    hc::ActuatorModel plant2(model);
    plant2.reset(u.front());
    double sum2_free = 0.0;
    for (const double yr : y_ref) {
      const double e = plant2.step(free_inverse->step(yr)) - yr;
      sum2_free += e * e;
    }
    EXPECT_LT(sum2, sum2_free) << "trial " << trial << ": rms " << std::sqrt(sum2 / y_ref.size())
                               << " vs rate-free " << std::sqrt(sum2_free / y_ref.size());
  }
}

INSTANTIATE_TEST_SUITE_P(
    AllFamilies, EveryFamilyInverse,
    ::testing::Values(FamilyCase{Family::kPi, false}, FamilyCase{Family::kPi, true},
                      FamilyCase{Family::kMpi, false}, FamilyCase{Family::kMpi, true},
                      FamilyCase{Family::kCpi, false}, FamilyCase{Family::kCpi, true},
                      FamilyCase{Family::kCpiDeadZones, false},
                      FamilyCase{Family::kCpiDeadZones, true}, FamilyCase{Family::kRpi, false},
                      FamilyCase{Family::kRpi, true}),
    case_name);

TEST(RateDependentPiModel, RateForOutputInvertsTheRateLaw) {
  hc::ActuatorModel model = stack_rpi(0.0, 1.0, 1e-4);
  model.reset(20.0);
  for (const double u : {40.0, 90.0, 130.0}) model.step(u);  // a state with memory
  for (const double u : {60.0, 100.0, 125.0}) {
    for (const double rate : {0.0, 300.0, 2000.0}) {
      const double y = model.peek_static_at_rate(u, rate);
      EXPECT_NEAR(model.rate_for_static_output(u, y), rate, 1e-6 * (1.0 + rate)) << u;
    }
    // Below the output at rest no rate gives y: 0, the closest.
    EXPECT_EQ(model.rate_for_static_output(u, model.peek_static_at_rate(u, 0.0) - 1.0), 0.0);
  }
}

// With the targets ahead, the per-sample rate law is inverted where it is well posed (rising:
// forward at the drive's own rate; falling: backwards from the end of the run): the error on
// the rate-dependent model falls well below the reference-rate prediction's, and the drive
// stays smooth (no chatter, bounded per-tick change).
TEST(NumericInverse, PreviewedRateDependentInverseTracksThePerSampleRateLaw) {
  const double dt = 1e-4;
  for (const double f : {5.0, 10.0}) {
    hc::ActuatorModel rate_model = stack_rpi(0.0, 1.0, dt);
    hc::ActuatorModel flat_model = stack_rpi(0.0, 0.0, dt);
    auto previewed = hc::make_inverse(rate_model);
    auto predicted = hc::make_inverse(rate_model);
    auto flat_inverse = hc::make_inverse(flat_model);
    const std::size_t ahead = previewed->preview_samples();
    ASSERT_GT(ahead, 1u);
    // A reachable reference: the rate-free model's output for an input sine over 15-135 V.
    const int n = static_cast<int>(3.0 / f / dt);
    hc::ActuatorModel shaper = flat_model;
    std::vector<double> reference;
    for (int k = 0; k < n + static_cast<int>(ahead); ++k) {
      reference.push_back(shaper.step(75.0 - 60.0 * std::cos(2.0 * std::numbers::pi * f * k * dt)));
    }
    for (auto* inv : {previewed.get(), predicted.get(), flat_inverse.get()}) inv->reset(15.0);
    hc::ActuatorModel plant_a = rate_model, plant_b = rate_model;
    plant_a.reset(15.0);
    plant_b.reset(15.0);
    double sum2_a = 0.0, sum2_b = 0.0, max_du_a = 0.0, max_du_flat = 0.0;
    double variation_a = 0.0, variation_flat = 0.0, ua_prev = 15.0, uf_prev = 15.0;
    for (int k = 0; k < n; ++k) {
      const double ua = previewed->step_previewed(
          std::span<const double>(reference).subspan(static_cast<std::size_t>(k), ahead));
      const double ub = predicted->step(reference[k]);
      const double uf = flat_inverse->step(reference[k]);
      const double ea = plant_a.step(ua) - reference[k], eb = plant_b.step(ub) - reference[k];
      if (k > 0) {
        max_du_a = std::max(max_du_a, std::abs(ua - ua_prev));
        max_du_flat = std::max(max_du_flat, std::abs(uf - uf_prev));
        variation_a += std::abs(ua - ua_prev);
        variation_flat += std::abs(uf - uf_prev);
      }
      ua_prev = ua;
      uf_prev = uf;
      if (k > n / 3) {
        sum2_a += ea * ea;
        sum2_b += eb * eb;
      }
    }
    std::cout << f << " Hz: previewed rms " << std::sqrt(sum2_a / (n - n / 3)) << ", predicted "
              << std::sqrt(sum2_b / (n - n / 3)) << "; max per-tick change " << max_du_a
              << " vs rate-free " << max_du_flat << "; variation " << variation_a << " vs "
              << variation_flat << "\n";
    EXPECT_LT(sum2_a, 0.25 * sum2_b) << f << " Hz";  // rms at most half
    EXPECT_LT(max_du_a, 2.0 * max_du_flat) << f << " Hz";
    EXPECT_LT(variation_a, 1.2 * variation_flat) << f << " Hz";
  }
}

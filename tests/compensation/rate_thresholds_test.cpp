// The rate-dependent PI's thresholds law: plays whose thresholds widen with |du/dt| (or its
// square root), their model file, their inverse and their fit.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "support/inverse_composition.hpp"
#include "support/random_models.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-3;

hc::RateDependentPiParameters thresholds_law(std::mt19937_64& rng, double widening_s,
                                             double filter_s) {
  hc::RateDependentPiParameters p;
  p.base = hystbench::testing::random_mpi(rng, 8, 1, 10.0);
  p.rate_coefficients.assign(p.base.play.weights.size(), 0.0);
  p.rate_law = hc::RateLaw::kThresholds;
  p.threshold_rate_s = widening_s;
  p.rate_filter_s = filter_s;
  return p;
}

std::vector<double> sine(double hz, double seconds, double lo = 0.0, double hi = 10.0) {
  std::vector<double> u(static_cast<std::size_t>(seconds / kDt));
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double t = static_cast<double>(k) * kDt;
    u[k] = lo + 0.5 * (hi - lo) * (1.0 - std::cos(2.0 * std::numbers::pi * hz * t));
  }
  return u;
}

}  // namespace

// On a ramp of constant rate the model is its rate-free self with every threshold r_i > 0 wider
// by beta * rate (r_0 = 0 is the linear term); a slow input sees the rate-free model.
TEST(RateThresholdsLaw, ARampSeesThresholdsWiderByBetaTimesTheRate) {
  std::mt19937_64 rng(5);
  const hc::RateDependentPiParameters p = thresholds_law(rng, 2e-3, 0.0);
  hc::RateDependentPiModel model(p, kDt);
  hc::RateDependentPiParameters wide = p;
  const double rate = 200.0;  // input unit / s
  wide.rate_law = hc::RateLaw::kMagnitude;
  wide.threshold_rate_s = 0.0;
  ASSERT_EQ(wide.base.play.thresholds.front(), 0.0);
  for (double& r : wide.base.play.thresholds) {
    if (r > 0.0) r += p.threshold_rate_s * rate;  // the linear term (r_0 = 0) does not widen
  }
  hc::ModifiedPiModel widened(wide.base);
  hc::ModifiedPiModel rate_free(p.base);
  model.reset(0.0);
  widened.reset(0.0);
  for (int k = 1; k <= 40; ++k) {
    const double u = rate * kDt * k;
    EXPECT_NEAR(model.step(u), widened.step(u), 1e-12) << k;
  }
  hc::RateDependentPiModel slow(p, kDt);
  slow.reset(0.0);
  rate_free.reset(0.0);
  // A slow input: the widening (beta * rate = 2e-3 * 1 = 0.002) is far below the thresholds.
  for (int k = 1; k <= 200; ++k) {
    const double u = 1e-3 * k;
    EXPECT_NEAR(slow.step(u), rate_free.step(u), 0.01) << k;
  }
}

// The loop's tips stay where the input reverses: at the input's peak the output is at its own
// (a delay would carry it further). At mid-input, where every play follows the input, the loop
// is wider by 2 beta |du/dt| times the plays' weights (the linear term's apart).
TEST(RateThresholdsLaw, TheLoopWidensWithTheRateAndItsTipsStayAtTheReversal) {
  hc::RateDependentPiParameters p;
  p.base.play = {{0.0, 1.0, 2.0, 3.0}, {1.0, 0.5, 0.5, 0.5}, 0.0};
  p.base.dead_zone = {{0.0}, {1.0}};  // identity: a classical PI
  p.rate_coefficients.assign(4, 0.0);
  p.rate_law = hc::RateLaw::kThresholds;
  p.threshold_rate_s = 1e-3;
  const double lo = 0.0, hi = 20.0, mid = 10.0;  // every play follows the input at mid-input
  struct Loop {
    double width = 0.0;          // falling minus rising output at mid-input
    double tip_shortfall = 0.0;  // the output's peak less its value at the input's peak
  };
  auto loop = [&](double hz) {
    hc::RateDependentPiModel m(p, kDt);
    const std::vector<double> u = sine(hz, 3.0 / hz, lo, hi);
    m.reset(u[0]);
    const std::vector<double> y = m.simulate(u);
    const auto period = static_cast<std::size_t>(1.0 / (hz * kDt));
    Loop l;
    double up = NAN, down = NAN, peak = -INFINITY;
    std::size_t input_peak = u.size() - period;
    for (std::size_t k = u.size() - period; k < u.size(); ++k) {
      peak = std::max(peak, y[k]);
      if (u[k] > u[input_peak]) input_peak = k;
      // The branch's output at mid-input, interpolated between the samples around it.
      const bool rising = u[k - 1] < mid && u[k] >= mid, falling = u[k - 1] > mid && u[k] <= mid;
      if (rising || falling) {
        const double a = (mid - u[k - 1]) / (u[k] - u[k - 1]);
        (rising ? up : down) = y[k - 1] + a * (y[k] - y[k - 1]);
      }
    }
    l.width = down - up;
    l.tip_shortfall = peak - y[input_peak];
    return l;
  };
  const Loop slow = loop(0.5), fast = loop(10.0);
  // The rate at mid-input: pi f (hi - lo); plays of weight 0.5 each with r > 0.
  auto widening = [&](double hz) {
    return 2.0 * p.threshold_rate_s * std::numbers::pi * hz * (hi - lo) * 1.5;
  };
  const double rate_free = 2.0 * 0.5 * (1.0 + 2.0 + 3.0);
  EXPECT_NEAR(slow.width - rate_free, widening(0.5), 0.02 * rate_free);
  EXPECT_NEAR(fast.width - rate_free, widening(10.0), 0.1 * widening(10.0));
  EXPECT_LT(fast.tip_shortfall, 1e-9);
  EXPECT_LT(slow.tip_shortfall, 1e-9);
}

// With the exponent 1/2 a ramp sees its thresholds wider by threshold_rate_s * max_rate *
// sqrt(rate / max_rate): at max_rate as the linear law, at a quarter of it half as wide.
TEST(RateThresholdsLaw, ASquareRootLawWidensWithTheSquareRootOfTheRate) {
  std::mt19937_64 rng(5);
  hc::RateDependentPiParameters p = thresholds_law(rng, 2e-3, 0.0);
  p.max_rate = 400.0;
  p.threshold_rate_exponent = 0.5;
  for (const double rate : {400.0, 100.0}) {
    hc::RateDependentPiModel model(p, kDt);
    hc::RateDependentPiParameters wide = p;
    wide.rate_law = hc::RateLaw::kMagnitude;
    wide.threshold_rate_s = 0.0;
    wide.threshold_rate_exponent = 1.0;
    const double widening = p.threshold_rate_s * p.max_rate * std::sqrt(rate / p.max_rate);
    EXPECT_DOUBLE_EQ(hc::threshold_widening(p.threshold_rate_s, 0.5, p.max_rate, rate), widening);
    for (double& r : wide.base.play.thresholds) {
      if (r > 0.0) r += widening;
    }
    hc::ModifiedPiModel widened(wide.base);
    model.reset(0.0);
    widened.reset(0.0);
    for (int k = 1; k <= 20; ++k) {
      const double u = rate * kDt * k;
      EXPECT_NEAR(model.step(u), widened.step(u), 1e-12) << rate << " " << k;
    }
  }
  EXPECT_DOUBLE_EQ(hc::threshold_widening(p.threshold_rate_s, 0.5, p.max_rate, 100.0),
                   0.5 * hc::threshold_widening(p.threshold_rate_s, 0.5, p.max_rate, 400.0));
}

TEST(RateThresholdsLaw, RoundTripsThroughTheModelFileAndOlderFilesStillLoad) {
  std::mt19937_64 rng(3);
  hc::RateDependentPiParameters p = thresholds_law(rng, 1.5e-3, 2e-3);
  p.max_rate = 400.0;
  p.threshold_rate_exponent = 0.5;
  hc::ModelFile f;
  f.model = hc::ActuatorModel(std::make_unique<hc::RateDependentPiModel>(p, kDt));
  nlohmann::json j = hc::to_json(f);
  EXPECT_EQ(j["rate"]["law"], "thresholds");
  EXPECT_EQ(j["rate"]["threshold_exponent"], 0.5);
  const hc::ModelFile back = hc::model_file_from_json(j);
  const auto& got =
      dynamic_cast<const hc::RateDependentPiModel&>(back.model.hysteresis()).parameters();
  EXPECT_EQ(got.rate_law, hc::RateLaw::kThresholds);
  EXPECT_DOUBLE_EQ(got.threshold_rate_s, p.threshold_rate_s);
  EXPECT_DOUBLE_EQ(got.threshold_rate_exponent, p.threshold_rate_exponent);
  EXPECT_DOUBLE_EQ(got.rate_filter_s, p.rate_filter_s);
  // The same outputs on a fast sine.
  hc::ActuatorModel a = f.model, b = back.model;
  a.configure(kDt);
  b.configure(kDt);
  a.reset(0.0);
  b.reset(0.0);
  for (const double u : sine(7.0, 0.5)) ASSERT_DOUBLE_EQ(a.step(u), b.step(u));
  // A thresholds file without the exponent (an older one) is linear in the rate; an exponent out
  // of (0, 1] is refused naming the field.
  nlohmann::json older = j;
  older["rate"].erase("threshold_exponent");
  EXPECT_EQ(dynamic_cast<const hc::RateDependentPiModel&>(
                hc::model_file_from_json(older).model.hysteresis())
                .parameters()
                .threshold_rate_exponent,
            1.0);
  for (const double bad : {0.0, 1.5}) {
    nlohmann::json wrong = j;
    wrong["rate"]["threshold_exponent"] = bad;
    try {
      hc::model_file_from_json(wrong);
      ADD_FAILURE() << "exponent " << bad << " loaded";
    } catch (const hc::ModelFileError& e) {
      EXPECT_NE(std::string(e.what()).find("rate.threshold_exponent"), std::string::npos)
          << e.what();
    }
  }
  // A weight-law file without threshold_s loads as before; a widening on a weight law is refused
  // naming the field.
  j["rate"]["law"] = "magnitude";
  j["rate"].erase("threshold_s");
  j["rate"].erase("threshold_exponent");
  EXPECT_NO_THROW(hc::model_file_from_json(j));
  j["rate"]["threshold_s"] = 1e-3;
  try {
    hc::model_file_from_json(j);
    ADD_FAILURE() << "a widening on the magnitude law loaded";
  } catch (const hc::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("rate.threshold_s"), std::string::npos) << e.what();
  }
}

// The inverse composes with the model on a fast sine, both where the output grows with the
// drive at its own rate (a filtered rate: exact each tick) and where it does not (the per-sample
// rate: solved at the rate the rate-free drive predicts). So does the inverse multiplicative
// structure, iterated within the tick (at the last tick's rate where the own rate does not
// keep the output growing); one pass a tick through the widening chattered.
TEST(RateThresholdsLaw, TheInverseComposesWithTheModel) {
  for (const hc::InverseKind kind : {hc::InverseKind::kAuto, hc::InverseKind::kMultiplicative}) {
    // The square-root law, filtered: its widening's slope is unbounded at rate 0, so it is never
    // solved at the drive's own rate.
    struct Law {
      double filter_s, exponent;
    };
    for (const auto [filter_s, exponent] : {Law{5e-3, 1.0}, Law{0.0, 1.0}, Law{5e-3, 0.5}}) {
      std::mt19937_64 rng(11);
      hc::RateDependentPiParameters p = thresholds_law(rng, 1e-3, filter_s);
      const bool square_root = exponent != 1.0;
      if (square_root) {
        p.max_rate = 300.0;
        p.threshold_rate_exponent = exponent;
      }
      hc::ActuatorModel model(std::make_unique<hc::RateDependentPiModel>(p, kDt));
      model.configure(kDt);
      model.input_min = -2.0;
      model.input_max = 12.0;
      // A reachable reference: the model's own output on a 5 Hz sine.
      hc::ActuatorModel probe = model;
      probe.reset(0.0);
      std::vector<double> ref;
      for (const double u : sine(5.0, 1.0, 1.0, 9.0)) ref.push_back(probe.step(u));
      model.reset(1.0);
      auto inverse = hc::make_inverse(model, kind);
      // Of the reference's span.
      const double worst = hystbench::testing::worst_composed_error(model, *inverse, ref, 1.0);
      const double bound = filter_s > 0.0 && !square_root ? 1e-6 : 0.02;
      std::cout << (kind == hc::InverseKind::kAuto ? "inverse" : "multiplicative")
                << (square_root ? ", square root" : "") << ", filter " << filter_s << " s: worst "
                << worst << " of the span\n";
      EXPECT_LT(worst, bound) << "filter " << filter_s;
    }
  }
}

TEST(RateThresholdsLaw, RefusesRateCoefficientsAndANegativeWidening) {
  std::mt19937_64 rng(1);
  hc::RateDependentPiParameters p = thresholds_law(rng, 1e-3, 0.0);
  p.rate_coefficients[1] = 1e-4;
  EXPECT_THROW(hc::RateDependentPiModel(p, kDt), std::invalid_argument);
  p = thresholds_law(rng, -1e-3, 0.0);
  EXPECT_THROW(hc::RateDependentPiModel(p, kDt), std::invalid_argument);
}

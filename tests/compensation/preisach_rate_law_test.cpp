// The Preisach plane with the thresholds rate law: relays whose thresholds widen with |du/dt|,
// their model file, their inverse and their fit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "hystbench/compensation/rate_estimator.hpp"
#include "support/inverse_composition.hpp"

namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-3;
constexpr double kSpan = 150.0;  // the plane's input range [V]

// Random densities over 10 cells per side, a slope, and the thresholds law: the relays widen by
// 2 V at 1 kV/s.
hc::PreisachParameters plane_with_law(std::mt19937_64& rng, double filter_s = 0.0) {
  constexpr std::size_t kCells = 10;
  std::uniform_real_distribution<double> d(0.0, 0.01);
  hc::PreisachParameters p{
      0.0, kSpan, kCells, std::vector<double>(hc::PreisachModel::cell_count(kCells)), 0.05, 1.5};
  for (double& x : p.densities) x = d(rng);
  p.rate_law.threshold_rate_s = 2e-3;
  p.rate_law.rate_filter_s = filter_s;
  return p;
}

hc::PreisachModel configured(const hc::PreisachParameters& p) {
  hc::PreisachModel m(p);
  m.set_sample_period(kDt);
  return m;
}

// A raised cosine between lo and hi at hz over the given time.
std::vector<double> sine(double hz, double seconds, double lo, double hi) {
  std::vector<double> u(static_cast<std::size_t>(seconds / kDt));
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double t = static_cast<double>(k) * kDt;
    u[k] = lo + 0.5 * (hi - lo) * (1.0 - std::cos(2.0 * std::numbers::pi * hz * t));
  }
  return u;
}

// The loop's width at mid-input over the last full period of a sine at hz: the output rising
// less the output falling where the input crosses the middle.
double width_at_middle(hc::HysteresisModel& m, double hz) {
  const std::vector<double> u = sine(hz, 2.0 / hz, 0.0, kSpan);
  m.reset(0.0);
  double up = 0.0, down = 0.0, y_prev = m.peek(0.0);
  const double mid = 0.5 * kSpan;
  for (std::size_t k = 1; k < u.size(); ++k) {
    const double y = m.step(u[k]);
    // The output where the input crosses the middle, between the samples either side.
    const double at_mid = y_prev + (y - y_prev) * (mid - u[k - 1]) / (u[k] - u[k - 1]);
    y_prev = y;
    if (k < u.size() / 2) continue;
    if (u[k - 1] < mid && u[k] >= mid) up = at_mid;
    if (u[k - 1] > mid && u[k] <= mid) down = at_mid;
  }
  return down - up;
}

// Ramps between random turning points, each at its own rate (0.05-3 V per sample).
std::vector<double> ramps_at_many_rates(std::mt19937_64& rng, std::size_t turns) {
  std::uniform_real_distribution<double> at(0.0, kSpan), per_sample(0.05, 3.0);
  std::vector<double> u{0.0};
  for (std::size_t t = 0; t < turns; ++t) {
    const double target = at(rng), from = u.back();
    const auto steps =
        static_cast<std::size_t>(std::ceil(std::abs(target - from) / per_sample(rng))) + 1;
    for (std::size_t k = 1; k <= steps; ++k) {
      u.push_back(from + (target - from) * static_cast<double>(k) / static_cast<double>(steps));
    }
  }
  return u;
}

}  // namespace

// The relays see the input through a play of half-width w(rate): the loop widens with the rate,
// the rate-free part is the plane at rest, and the reversible slope does not lag.
TEST(PreisachRateLaw, TheLoopWidensWithTheRateAndTheSlopeDoesNotLag) {
  std::mt19937_64 rng(3);
  const hc::PreisachParameters p = plane_with_law(rng);
  hc::PreisachModel law = configured(p);
  const std::unique_ptr<hc::HysteresisModel> free = law.rate_free_part();
  ASSERT_NE(free, nullptr);
  EXPECT_FALSE(free->thresholds_law());
  ASSERT_TRUE(law.thresholds_law());
  EXPECT_EQ(law.thresholds_law()->threshold_rate_s, 2e-3);

  const double still = width_at_middle(*free, 1.0);
  const double slow = width_at_middle(law, 1.0), fast = width_at_middle(law, 10.0);
  std::cout << "width at mid-input: rate-free " << still << ", 1 Hz " << slow << ", 10 Hz " << fast
            << "\n";
  EXPECT_GT(slow, still);
  EXPECT_GT(fast, slow + 0.5 * (slow - still));
  EXPECT_NEAR(width_at_middle(*free, 10.0), still, 0.01 * still);  // the plane alone: rate-free

  // On a ramp of 1 kV/s (1 V per sample) the relays lag the input by w = 2 V, the slope not.
  law.reset(10.0);
  double u = 10.0;
  for (int k = 0; k < 40; ++k) law.step(u += 1.0);
  EXPECT_NEAR(law.front(u, 1000.0), u - 2.0, 1e-12);
  const double y = law.peek_at_rate(u + 1.0, 1000.0);
  const double relays_only = y - p.offset - p.slope * (u + 1.0);
  hc::PreisachParameters no_slope = p;
  no_slope.slope = 0.0;
  no_slope.offset = 0.0;
  no_slope.rate_law = {};
  hc::PreisachModel relays(no_slope);
  relays.reset(10.0);
  for (double v = 11.0; v <= u - 1.0; v += 1.0) relays.step(v);
  EXPECT_NEAR(relays_only, relays.peek(u - 1.0), 1e-9);

  // A non-finite input moves neither the relays nor the front nor the rate.
  const double next = law.peek(u + 1.0);
  law.step(std::nan(""));
  EXPECT_EQ(law.peek(u + 1.0), next);
}

TEST(PreisachRateLaw, RoundTripsThroughAModelFileAndRefusesAnotherLaw) {
  std::mt19937_64 rng(5);
  hc::PreisachParameters p = plane_with_law(rng, 3e-3);
  p.rate_law.exponent = 0.5;
  p.rate_law.max_rate = 2000.0;
  p.rate_law.record_max_rate = 2500.0;
  hc::ActuatorModel a(std::make_unique<hc::PreisachModel>(p));
  a.configure(kDt);
  a.input_min = 0.0;
  a.input_max = kSpan;
  const nlohmann::json j = hc::to_json(hc::ModelFile{a, nlohmann::json::object()});
  EXPECT_EQ(j["preisach"]["rate"]["law"], "thresholds");
  hc::ModelFile back = hc::model_file_from_json(j);
  back.model.configure(kDt);
  ASSERT_TRUE(back.model.hysteresis().thresholds_law());
  EXPECT_EQ(*back.model.hysteresis().thresholds_law(), p.rate_law);
  a.reset(0.0);
  back.model.reset(0.0);
  for (const double u : sine(7.0, 0.5, 0.0, kSpan)) ASSERT_EQ(a.step(u), back.model.step(u));

  nlohmann::json other = j;
  other["preisach"]["rate"]["law"] = "signed";
  EXPECT_THROW(hc::model_file_from_json(other), hc::ModelFileError);
  nlohmann::json rate_free = j;
  rate_free["preisach"].erase("rate");  // files written before the law: rate-free
  EXPECT_FALSE(hc::model_file_from_json(rate_free).model.hysteresis().thresholds_law());
  hc::PreisachParameters bad = p;
  bad.rate_law.exponent = 1.5;
  EXPECT_THROW(hc::PreisachModel{bad}, std::invalid_argument);
}

// Each inverse, composed with the model, gives back a reachable reference on a fast sine; the
// rate-free plane's inverse does not.
TEST(PreisachRateLaw, TheInverseComposesWithTheModel) {
  std::mt19937_64 rng(7);
  const hc::PreisachParameters p = plane_with_law(rng, 5e-3);
  hc::ActuatorModel model(std::make_unique<hc::PreisachModel>(p));
  model.configure(kDt);
  model.input_min = 0.0;
  model.input_max = kSpan;
  hc::ActuatorModel probe = model;
  probe.reset(10.0);
  std::vector<double> ref;
  for (const double u : sine(10.0, 1.0, 10.0, 140.0)) ref.push_back(probe.step(u));
  auto worst_of = [&](hc::InverseModel& inverse) {
    return hystbench::testing::worst_composed_error(model, inverse, ref, 10.0);
  };

  hc::ActuatorModel free_model(model.hysteresis().rate_free_part());
  free_model.configure(kDt);
  free_model.input_min = 0.0;
  free_model.input_max = kSpan;
  auto free_inverse = hc::make_inverse(free_model);
  const double without_law = worst_of(*free_inverse);
  for (const hc::InverseKind kind : {hc::InverseKind::kAuto, hc::InverseKind::kMultiplicative}) {
    model.reset(10.0);
    auto inverse = hc::make_inverse(model, kind);
    const double worst = worst_of(*inverse);
    std::cout << (kind == hc::InverseKind::kAuto ? "numeric" : "multiplicative") << ": worst "
              << worst << " of the span; the rate-free plane's inverse " << without_law << "\n";
    EXPECT_LT(worst, 0.01);
    EXPECT_LT(worst, 0.2 * without_law);
  }
}

// fit --model preisach on the record of a plane with the law: the law is found (its widening
// within 10 %) and the held-out error is a small part of the rate-free plane's. On the record of
// a rate-free plane no law is kept.
TEST(PreisachRateLaw, IsRecoveredFromItsOwnRecordAndNotAddedWhereThereIsNone) {
  std::mt19937_64 rng(9);
  const hc::PreisachParameters truth = plane_with_law(rng, 2.0 * kDt);
  const std::vector<double> u = ramps_at_many_rates(rng, 260);
  std::vector<double> t(u.size());
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) * kDt;
  auto record_of = [&](hc::PreisachModel m) {
    m.reset(u.front());
    return m.simulate(u);
  };
  hc::FitOptions o;
  o.kind = hc::ModelKind::kPreisach;
  o.operators = 10;
  o.delay_samples = 0;
  const std::vector<double> y = record_of(configured(truth));
  const hc::FitResult with = hc::fit_model(t, u, y, o);
  o.preisach_rate_law = false;
  const hc::FitResult without = hc::fit_model(t, u, y, o);
  const auto law = with.model.hysteresis().thresholds_law();
  ASSERT_TRUE(law) << with.method;
  std::cout << "widening " << law->threshold_rate_s << " s (truth "
            << truth.rate_law.threshold_rate_s << "), filter " << law->rate_filter_s
            << " s; held-out " << with.heldout.rmse << " against " << without.heldout.rmse
            << " without the law\n";
  EXPECT_NEAR(law->threshold_rate_s, truth.rate_law.threshold_rate_s,
              0.1 * truth.rate_law.threshold_rate_s);
  EXPECT_LT(with.heldout.rmse, 0.1 * without.heldout.rmse);
  EXPECT_FALSE(without.model.hysteresis().thresholds_law());

  hc::PreisachParameters plain = truth;
  plain.rate_law = {};
  o.preisach_rate_law = true;
  const hc::FitResult none = hc::fit_model(t, u, record_of(configured(plain)), o);
  EXPECT_FALSE(none.model.hysteresis().thresholds_law()) << none.method;
}

// A law given to the fit (identify's neighbour of a plane whose law was found) is refitted on
// the plane as given, without a search over the widening and filter; one that does not lower
// the held-out error is not kept, and a malformed one is refused with its cause.
TEST(PreisachRateLaw, AGivenLawIsRefittedNotSearchedFor) {
  std::mt19937_64 rng(11);
  const hc::PreisachParameters truth = plane_with_law(rng);
  const std::vector<double> u = ramps_at_many_rates(rng, 200);
  std::vector<double> t(u.size());
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) * kDt;
  hc::PreisachModel m = configured(truth);
  m.reset(u.front());
  const std::vector<double> y = m.simulate(u);
  hc::FitOptions o;
  o.kind = hc::ModelKind::kPreisach;
  o.operators = 10;
  o.delay_samples = 0;
  const auto law_trials = [](const hc::FitResult& f) {
    return std::count_if(f.candidates.begin(), f.candidates.end(), [](const auto& c) {
      return c.method.find("rate-thresholds") != std::string::npos;
    });
  };
  const hc::FitResult searched = hc::fit_model(t, u, y, o);
  const auto found = searched.model.hysteresis().thresholds_law();
  ASSERT_TRUE(found) << searched.method;

  hc::ThresholdsRateLaw given = *found;
  given.threshold_rate_s *= 0.8;
  o.preisach_given_rate_law = given;
  const hc::FitResult refitted = hc::fit_model(t, u, y, o);
  const auto kept = refitted.model.hysteresis().thresholds_law();
  ASSERT_TRUE(kept) << refitted.method;
  std::cout << "law trials: " << law_trials(searched) << " searched, " << law_trials(refitted)
            << " given; held-out " << searched.heldout.rmse << " searched, "
            << refitted.heldout.rmse << " given at 0.8x its widening\n";
  EXPECT_EQ(kept->threshold_rate_s, given.threshold_rate_s);
  EXPECT_EQ(kept->rate_filter_s, given.rate_filter_s);
  EXPECT_EQ(law_trials(refitted), 1);
  EXPECT_GT(law_trials(searched), 10);
  EXPECT_GE(refitted.heldout.rmse, searched.heldout.rmse);

  given.threshold_rate_s = 1e3 * found->threshold_rate_s;  // wider than the whole plane
  o.preisach_given_rate_law = given;
  const hc::FitResult wrong = hc::fit_model(t, u, y, o);
  EXPECT_FALSE(wrong.model.hysteresis().thresholds_law()) << wrong.method;

  given.exponent = 0.0;
  o.preisach_given_rate_law = given;
  EXPECT_THROW(hc::fit_model(t, u, y, o), std::invalid_argument);
}

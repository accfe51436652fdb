// The amplitude schedule (weights, estimate, model, model file) and the amplitude-dependence
// diagnosis on a truth whose mode moves with the drive's amplitude, and on one whose does not.
#include "hystbench/compensation/amplitude_dependence.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "hystbench/compensation/mimo_model_file.hpp"
#include "support/periodic_records.hpp"

namespace hc = hystbench::compensation;
namespace ht = hystbench::test;
using cd = std::complex<double>;

namespace {

constexpr double kDt = 2e-4;
constexpr std::size_t kPeriod = 1024, kPeriods = 2, kBins = 300;  // excited up to 1.46 kHz

// Two inputs, two outputs: a mode at f_a [Hz] and one at 600 Hz, each input reaching both.
hc::MimoLinearModel stage(double f_a) {
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(2, 2), a1(2, 2), b1(2, 2), a2(2, 2), b2(2, 2);
  a1 << 0.02, 0.012, 0.008, 0.015;
  b1 << -0.01, 0.004, 0.003, -0.012;
  a2 << 0.01, -0.006, 0.007, 0.02;
  b2 << 0.004, 0.002, -0.002, 0.006;
  return hc::MimoLinearModel(
      {ht::discrete_mode(f_a, 0.05, kDt), ht::discrete_mode(600.0, 0.04, kDt)}, {d, a1, b1, a2, b2},
      Eigen::Vector2d::Zero());
}

hc::HammersteinMimoModel hammerstein(const hc::MimoLinearModel& g) {
  return {std::vector<std::optional<hc::ActuatorModel>>(2), g, kDt};
}

// Records at 1, 2 and 3 times a level (given in an order other than the amplitudes'), the first
// mode at f_of(level) in each: a stage whose dynamics are linear at any one amplitude.
std::vector<hc::PeriodicRecord> records_at(const std::function<double(int)>& f_of) {
  std::vector<hc::PeriodicRecord> records;
  for (const int level : {2, 1, 3}) {
    const auto u = ht::random_multisines(2, 3, kPeriod, kPeriods, kBins, 0.01 * level,
                                         static_cast<unsigned>(10 + level));
    const hc::HammersteinMimoModel truth = hammerstein(stage(f_of(level)));
    records.push_back(ht::periodic_record_of(
        [&](const Eigen::MatrixXd& x) { return truth.simulate(x); }, u, kPeriod, kPeriods, kDt));
  }
  return records;
}

hc::HammersteinFitOptions quick() {
  hc::HammersteinFitOptions o;
  o.linear.orders = {2, 4, 6};
  o.operators = 0;
  return o;
}

// The lowest mode of a linear block [Hz].
double lowest_mode_hz(const hc::MimoLinearModel& g) {
  double f = 1e300;
  for (const cd p : g.poles()) {
    if (p.imag() > 0.0) f = std::min(f, std::abs(std::log(p)) / (2.0 * std::numbers::pi * kDt));
  }
  return f;
}

}  // namespace

TEST(ScheduleWeights, InterpolateBetweenNeighboursAndExtrapolateAtMostOneSpacing) {
  const std::vector<double> a{1.0, 2.0, 4.0};
  EXPECT_TRUE(hc::schedule_weights(a, 2.0).isApprox(Eigen::Vector3d(0.0, 1.0, 0.0)));
  EXPECT_TRUE(hc::schedule_weights(a, 3.0).isApprox(Eigen::Vector3d(0.0, 0.5, 0.5)));
  EXPECT_TRUE(hc::schedule_weights(a, 1.25).isApprox(Eigen::Vector3d(0.75, 0.25, 0.0)));
  // Below the first: extrapolated from the first two, held one spacing below it.
  EXPECT_TRUE(hc::schedule_weights(a, 0.5).isApprox(Eigen::Vector3d(1.5, -0.5, 0.0)));
  EXPECT_TRUE(hc::schedule_weights(a, 0.0).isApprox(Eigen::Vector3d(2.0, -1.0, 0.0)));
  EXPECT_TRUE(hc::schedule_weights(a, -5.0).isApprox(Eigen::Vector3d(2.0, -1.0, 0.0)));
  // Above the last: from the last two, held one spacing (2) above it.
  EXPECT_TRUE(hc::schedule_weights(a, 5.0).isApprox(Eigen::Vector3d(0.0, -0.5, 1.5)));
  EXPECT_TRUE(hc::schedule_weights(a, 100.0).isApprox(Eigen::Vector3d(0.0, -1.0, 2.0)));
  const std::vector<double> one{3.0};
  EXPECT_DOUBLE_EQ(hc::schedule_weights(one, 0.1)(0), 1.0);
}

TEST(AmplitudeEstimate, IsTheStandardDeviationOverTheWindowWhateverTheBias) {
  constexpr Eigen::Index kN = 4000;
  Eigen::MatrixXd u(2, kN);
  for (Eigen::Index t = 0; t < kN; ++t) {
    const double ph = 2.0 * std::numbers::pi * static_cast<double>(t) / 100.0;
    u(0, t) = 50.0 + 2.0 * std::sin(ph);      // a bias the estimate does not count
    u(1, t) = t < 2000 ? 0.0 : std::cos(ph);  // switched on half way
  }
  const Eigen::VectorXd a = hc::amplitude_estimate(u, 1000);
  // Input 1's std is 2 / sqrt(2), input 2's 0 then 1 / sqrt(2): rms over the two.
  EXPECT_NEAR(a(1999), std::sqrt((2.0 + 0.0) / 2.0), 1e-9);
  EXPECT_NEAR(a(3999), std::sqrt((2.0 + 0.5) / 2.0), 1e-9);
  // Before a window has passed, over the samples so far (here whole cycles).
  EXPECT_NEAR(a(499), 1.0, 1e-9);
  EXPECT_NEAR(hc::record_amplitude(u.leftCols(2000)), 1.0, 1e-9);
  EXPECT_THROW((void)hc::amplitude_estimate(u, 0), std::invalid_argument);
}

TEST(AmplitudeScheduledMimoModel, BlendsItsLocalModelsByTheDrivesAmplitude) {
  // Two local models whose outputs differ by a gain of 2: the blend at the amplitude half way
  // between theirs is 1.5 times the first's output.
  const hc::MimoLinearModel g = stage(150.0);
  std::vector<Eigen::MatrixXd> terms = g.terms();
  for (auto& t : terms) t *= 2.0;
  const hc::HammersteinMimoModel one = hammerstein(g);
  const hc::HammersteinMimoModel two =
      hammerstein(hc::MimoLinearModel(g.poles(), terms, g.output_offset()));
  const auto u = ht::random_multisines(2, 1, kPeriod, 3, kBins, 0.01, 5).front();
  const double a = hc::record_amplitude(u);
  const hc::AmplitudeScheduledMimoModel blend({0.5 * a, 1.5 * a}, {one, two}, 0.1);
  EXPECT_EQ(blend.window_samples(), 500u);
  const Eigen::MatrixXd y = blend.simulate(u), y1 = one.simulate(u);
  // After a window the estimate sits at the record's amplitude, within its few percent.
  const Eigen::MatrixXd late = y.rightCols(kPeriod), late1 = y1.rightCols(kPeriod);
  EXPECT_NEAR(late.norm() / late1.norm(), 1.5, 0.05);
  // One local model is that model; a model without one of two is the other.
  EXPECT_TRUE(blend.without(0).simulate(u).isApprox(two.simulate(u)));
  EXPECT_THROW((void)blend.without(0).without(0), std::invalid_argument);
  EXPECT_THROW(hc::AmplitudeScheduledMimoModel({a, a}, {one, two}, 0.1), std::invalid_argument);
  EXPECT_THROW(hc::AmplitudeScheduledMimoModel({a}, {one, two}, 0.1), std::invalid_argument);
  EXPECT_THROW(hc::AmplitudeScheduledMimoModel({a}, {one}, 0.0), std::invalid_argument);
}

TEST(AmplitudeScheduledMimoModel, TravelsThroughItsModelFile) {
  const hc::AmplitudeScheduledMimoModel s(
      {0.1, 0.3}, {hammerstein(stage(150.0)), hammerstein(stage(180.0))}, 0.25);
  hc::MimoModelFile f;
  f.scheduled = s;
  f.model = s.local_models().back();
  f.sample_period_s = kDt;
  f.inputs = {{"u1", "V"}, {"u2", "V"}};
  f.outputs = {{"y1", "um"}, {"y2", "um"}};
  f.local_identification = {{{"order", 4}}, {{"order", 6}}};
  const nlohmann::json j = hc::to_json(f);
  EXPECT_EQ(j["type"], hc::kScheduledMimoModelType);
  EXPECT_TRUE(hc::is_mimo_model_file(j));
  const hc::MimoModelFile back = hc::mimo_model_file_from_json(j);
  ASSERT_TRUE(back.scheduled);
  EXPECT_EQ(back.scheduled->amplitudes(), s.amplitudes());
  EXPECT_EQ(back.local_identification[1]["order"], 6);
  const auto u = ht::random_multisines(2, 1, kPeriod, 2, kBins, 0.015, 9).front();
  EXPECT_TRUE(back.simulate(u).isApprox(f.simulate(u), 1e-12));
  nlohmann::json bad = j;
  bad["local_models"][1]["amplitude"] = 0.05;  // not ascending
  EXPECT_THROW((void)hc::mimo_model_file_from_json(bad), hc::ModelFileError);
  bad = j;
  bad["local_models"][0]["dynamics"]["terms"][1][0] = {1.0};
  try {
    (void)hc::mimo_model_file_from_json(bad);
    FAIL() << "a short row was accepted";
  } catch (const hc::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("local_models[0].dynamics.terms[1][0]"), std::string::npos)
        << e.what();
  }
}

TEST(AmplitudeDependence, AModeThatMovesWithTheAmplitudeIsRecoveredAndNamed) {
  // The first mode at 150, 153 and 156 Hz at 1, 2 and 3 times the level: +4 %, less than its
  // half-power width (+-5 %) per step, as a mode that softens or stiffens with the drive moves.
  const auto records = records_at([](int level) { return 150.0 * (1.0 + 0.02 * (level - 1)); });
  hc::AmplitudeFitOptions o;
  o.local = quick();
  const hc::AmplitudeFit fit = hc::fit_amplitude_schedule(records, o);
  ASSERT_EQ(fit.order, (std::vector<std::size_t>{1, 0, 2}));  // ordered by amplitude
  EXPECT_NEAR(fit.amplitudes[1] / fit.amplitudes[0], 2.0, 0.05);
  for (std::size_t k = 0; k < 3; ++k) {
    // Each local model is the truth at its amplitude, exactly.
    EXPECT_NEAR(lowest_mode_hz(fit.local[k].model.dynamics()), 150.0 * (1.0 + 0.02 * k), 1e-4);
  }
  const hc::AmplitudeDiagnosis d = hc::diagnose_amplitude_dependence(records, fit, quick());
  EXPECT_TRUE(d.named) << d.gain;
  ASSERT_EQ(d.left_out.size(), 3u);
  // Each amplitude left out, the others' schedule beats one model fitted on them both.
  for (const auto& l : d.left_out) EXPECT_GT(l.gain, 1.5) << l.amplitude;
  ASSERT_FALSE(d.modes.empty());
  bool found = false;
  for (const auto& m : d.modes) {
    if (std::abs(m.frequency_hz.front() - 150.0) < 1.0) {
      found = true;
      EXPECT_NEAR(m.shift_percent, 4.0, 0.01);
      EXPECT_NEAR(m.frequency_hz[1], 153.0, 0.01);
    } else {
      EXPECT_NEAR(m.shift_percent, 0.0, 0.1);  // the 600 Hz mode stays
    }
  }
  EXPECT_TRUE(found);
  // The schedule reproduces every record it was fitted on.
  for (std::size_t k = 0; k < 3; ++k) {
    const double y_rms = std::sqrt(records[fit.order[k]].y[0].squaredNorm() /
                                   static_cast<double>(records[fit.order[k]].y[0].size()));
    EXPECT_LT(fit.schedule_rms[k], 0.02 * y_rms);
  }
}

TEST(AmplitudeDependence, IsNotNamedWhereTheDynamicsStayTheSame) {
  const auto records = records_at([](int) { return 150.0; });
  hc::AmplitudeFitOptions o;
  o.local = quick();
  const hc::AmplitudeFit fit = hc::fit_amplitude_schedule(records, o);
  const hc::AmplitudeDiagnosis d = hc::diagnose_amplitude_dependence(records, fit, quick());
  EXPECT_FALSE(d.named) << d.gain;
  EXPECT_LT(d.gain, 1.05);
  for (const auto& e : d.entries) EXPECT_LT(e.change, 1e-5);
}

TEST(AmplitudeDependence, RefusesRecordsAtOneAmplitudeOrOfAnotherShape) {
  auto records = records_at([](int) { return 150.0; });
  std::vector<hc::PeriodicRecord> same{records[0], records[0]};
  try {
    (void)hc::fit_amplitude_schedule(same);
    FAIL() << "two records at one amplitude were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("one amplitude"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)hc::fit_amplitude_schedule({records[0]}), std::invalid_argument);
  records[2].dt *= 2.0;
  EXPECT_THROW((void)hc::fit_amplitude_schedule(records), std::invalid_argument);
}

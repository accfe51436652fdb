#include "hystbench/compensation/mimo_identification.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "hystbench/compensation/mimo_diagnosis.hpp"
#include "hystbench/compensation/mimo_model_file.hpp"

namespace hc = hystbench::compensation;
using cd = std::complex<double>;

namespace {

// Periods of 0.2 s: the slowest mode's transient decays e^-19 over the first, which is dropped.
constexpr std::size_t kPeriod = 2048;
constexpr std::size_t kBins = 800;  // excited: up to 3.9 kHz
constexpr double kDt = 1e-4;

// A lightly damped pair at f [Hz] with damping zeta, as a discrete pole (Im > 0).
cd mode(double f, double zeta) {
  const double wn = 2.0 * std::numbers::pi * f, wd = wn * std::sqrt(1.0 - zeta * zeta);
  return std::exp(cd(-zeta * wn * kDt, wd * kDt));
}

// Two inputs, two outputs: modes at 300 and 1200 Hz, each input reaching both outputs.
hc::MimoLinearModel coupled_truth(double coupling) {
  std::vector<cd> poles{mode(300.0, 0.05), mode(1200.0, 0.03)};
  Eigen::MatrixXd d(2, 2), a1(2, 2), b1(2, 2), a2(2, 2), b2(2, 2);
  d << 0.0, 0.0, 0.0, 0.0;
  a1 << 0.02, 0.02 * coupling, 0.01 * coupling, 0.015;
  b1 << -0.01, 0.005 * coupling, 0.004 * coupling, -0.012;
  a2 << 0.01, -0.006 * coupling, 0.008 * coupling, 0.02;
  b2 << 0.004, 0.003 * coupling, -0.002 * coupling, 0.006;
  return hc::MimoLinearModel(poles, {d, a1, b1, a2, b2}, Eigen::Vector2d(0.5, -0.25));
}

// Random-phase multisines on bins 1..K of each input, independent phases per realization.
std::vector<Eigen::MatrixXd> multisines(std::size_t inputs, std::size_t realizations,
                                        std::size_t periods, std::size_t bins, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  std::vector<Eigen::MatrixXd> u;
  for (std::size_t r = 0; r < realizations; ++r) {
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(inputs),
                                              static_cast<Eigen::Index>(kPeriod * periods));
    for (std::size_t j = 0; j < inputs; ++j) {
      for (std::size_t k = 1; k <= bins; ++k) {
        const double ph = phase(rng);
        for (Eigen::Index t = 0; t < m.cols(); ++t) {
          m(static_cast<Eigen::Index>(j), t) +=
              0.1 * std::cos(2.0 * std::numbers::pi * static_cast<double>(k * t) / kPeriod + ph);
        }
      }
    }
    u.push_back(std::move(m));
  }
  return u;
}

hc::PeriodicRecord record_of(const hc::HammersteinMimoModel& truth,
                             const std::vector<Eigen::MatrixXd>& u, std::size_t periods,
                             double noise = 0.0, unsigned seed = 3) {
  hc::PeriodicRecord rec;
  rec.period = kPeriod;
  rec.periods = periods;
  rec.dt = kDt;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise > 0.0 ? noise : 1.0);
  for (const auto& ur : u) {
    Eigen::MatrixXd y = truth.simulate(ur);
    if (noise > 0.0) y = y.unaryExpr([&](double v) { return v + n(rng); });
    rec.u.push_back(ur);
    rec.y.push_back(std::move(y));
  }
  return rec;
}

hc::HammersteinMimoModel linear(const hc::MimoLinearModel& g) {
  return hc::HammersteinMimoModel(std::vector<std::optional<hc::ActuatorModel>>(g.inputs()), g,
                                  kDt);
}

double max_response_error(const hc::MimoLinearModel& a, const hc::MimoLinearModel& b) {
  double worst = 0.0;
  for (double f = 50.0; f < 4500.0; f += 150.0) {
    const cd z = std::polar(1.0, 2.0 * std::numbers::pi * f * kDt);
    const Eigen::MatrixXcd ga = a.response(z), gb = b.response(z);
    worst = std::max(worst, (ga - gb).cwiseAbs().maxCoeff() / gb.cwiseAbs().maxCoeff());
  }
  return worst;
}

}  // namespace

TEST(PeriodicSpectra, DropsTheFirstPeriodAndFindsTheExcitedBins) {
  const auto truth = linear(coupled_truth(1.0));
  const auto rec = record_of(truth, multisines(2, 2, 3, kBins), 3);
  const hc::PeriodicSpectra s = hc::periodic_spectra(rec);
  EXPECT_EQ(s.transient_periods, 1u);
  EXPECT_EQ(s.periods_used, 2u);
  ASSERT_EQ(s.bins.size(), kBins);
  EXPECT_EQ(s.bins.front(), 1u);
  EXPECT_EQ(s.bins.back(), kBins);
  // The steady state's means: the offset, and the model's DC gain on a zero-mean input.
  EXPECT_NEAR(s.y_mean(0), 0.5, 1e-3);
  EXPECT_NEAR(s.y_mean(1), -0.25, 1e-3);
}

TEST(PeriodicSpectra, TheNoiseComesFromTheDifferencesBetweenPeriods) {
  const auto truth = linear(coupled_truth(1.0));
  const double sigma = 0.01;
  const auto rec = record_of(truth, multisines(2, 4, 5, kBins), 5, sigma);
  const hc::PeriodicSpectra s = hc::periodic_spectra(rec);
  // White noise of sigma per sample: |DFT|^2 has mean N sigma^2, the mean of 4 periods a quarter.
  const double expected = kPeriod * sigma * sigma / 4.0;
  EXPECT_NEAR(s.noise_var.mean() / expected, 1.0, 0.1);
}

TEST(MimoIdentification, RecoversACoupledTwoByTwoSystemExactly) {
  const hc::MimoLinearModel g = coupled_truth(1.0);
  const auto rec = record_of(linear(g), multisines(2, 3, 2, kBins), 2);
  hc::MimoFitOptions o;
  o.orders = {2, 4, 6};
  const hc::MimoFitResult r = hc::identify_mimo_linear(hc::periodic_spectra(rec), o);
  EXPECT_EQ(r.order, 4u);
  EXPECT_EQ(r.heldout, "realization 2");
  EXPECT_LT(max_response_error(r.model, g), 1e-6);
  EXPECT_LT(r.fit_rms.maxCoeff(), 1e-8);
  // Order 2 cannot hold both modes: its held-out error is far above.
  EXPECT_GT(r.scores.front().heldout_rms, 1e3 * r.scores[1].heldout_rms);
  // The cross terms are what they are: the model's off-diagonal response matches at 300 Hz.
  const cd z = std::polar(1.0, 2.0 * std::numbers::pi * 300.0 * kDt);
  EXPECT_NEAR(std::abs(r.model.response(z)(0, 1)), std::abs(g.response(z)(0, 1)),
              1e-6 * std::abs(g.response(z)(0, 1)));
  // Simulated from rest, once the transient has gone, the outputs match the record's.
  const Eigen::MatrixXd y = r.model.simulate(rec.u[0]);
  EXPECT_LT((y - rec.y[0]).rightCols(kPeriod).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(MimoIdentification, OneRealizationIsScoredOnTheOddBins) {
  const hc::MimoLinearModel g = coupled_truth(1.0);
  const auto rec = record_of(linear(g), multisines(2, 1, 2, kBins), 2);
  hc::MimoFitOptions o;
  o.orders = {4};
  const hc::MimoFitResult r = hc::identify_mimo_linear(hc::periodic_spectra(rec), o);
  EXPECT_EQ(r.heldout, "odd bins");
  EXPECT_LT(max_response_error(r.model, g), 1e-5);
}

TEST(MimoIdentification, CouplingSharesNameTheInputsThatReachEachOutput) {
  const auto u = multisines(2, 3, 2, kBins);
  for (const double coupling : {0.0, 1.0}) {
    const auto truth = linear(coupled_truth(coupling));
    const auto rec = record_of(truth, u, 2);
    const Eigen::MatrixXd shares = hc::coupling_shares(truth, rec);
    EXPECT_GT(shares(0, 0), 0.3) << coupling;
    EXPECT_GT(shares(1, 1), 0.3) << coupling;
    if (coupling == 0.0) {
      EXPECT_LT(shares(0, 1), 1e-12);
      EXPECT_LT(shares(1, 0), 1e-12);
    } else {
      EXPECT_GT(shares(0, 1), 0.05);
      EXPECT_GT(shares(1, 0), 0.05);
    }
  }
}

TEST(MimoIdentification, APlayModelOnAnInputIsFoundAndKept) {
  const hc::MimoLinearModel g = coupled_truth(1.0);
  const auto u = multisines(2, 4, 2, kBins);
  // The truth's operator on input 0 uses the thresholds the fit will try.
  double lo = u[0].row(0).minCoeff(), hi = u[0].row(0).maxCoeff();
  for (const auto& m : u)
    lo = std::min(lo, m.row(0).minCoeff()), hi = std::max(hi, m.row(0).maxCoeff());
  hc::PiParameters op{hc::uniform_thresholds(4, 0.5 * (hi - lo)), {0.6, 0.25, 0.1, 0.05}, 0.0};
  const hc::HammersteinMimoModel truth({hc::classical_pi_operator(op), std::nullopt}, g, kDt);
  const auto rec = record_of(truth, u, 2);
  hc::HammersteinFitOptions o;
  o.linear.orders = {4};
  o.operators = 4;
  const hc::HammersteinFitResult r = hc::identify_mimo_hammerstein(rec, o);
  EXPECT_TRUE(r.hysteresis_kept);
  EXPECT_LT(r.heldout_hammerstein, 0.2 * r.heldout_linear);
  ASSERT_TRUE(r.model.operators()[0].has_value());
  // The weights sum to one by construction; their shape is the truth's.
  const auto* pi = dynamic_cast<const hc::PiModel*>(&r.model.operators()[0]->hysteresis());
  ASSERT_NE(pi, nullptr);
  const std::vector<double>& w = pi->parameters().weights;
  EXPECT_NEAR(w[1] / w[0], 0.25 / 0.6, 0.02);
}

TEST(MimoModelFile, RoundTripsAndNamesABadField) {
  hc::MimoModelFile f;
  f.model = linear(coupled_truth(1.0));
  f.sample_period_s = kDt;
  f.inputs = {{"u1", "V"}, {"u2", "V"}};
  f.outputs = {{"y1", "um"}, {"y2", "um"}};
  const nlohmann::json j = hc::to_json(f);
  EXPECT_TRUE(hc::is_mimo_model_file(j));
  const hc::MimoModelFile back = hc::mimo_model_file_from_json(j);
  EXPECT_LT(max_response_error(back.model.dynamics(), f.model.dynamics()), 1e-12);
  EXPECT_EQ(back.outputs[1].name, "y2");
  nlohmann::json bad = j;
  bad["dynamics"]["terms"][1][0] = {1.0};
  try {
    (void)hc::mimo_model_file_from_json(bad);
    FAIL() << "a short row was accepted";
  } catch (const hc::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("dynamics.terms[1][0]"), std::string::npos) << e.what();
  }
  bad = j;
  bad["dynamics"]["poles"][0] = {1.5, 0.1};
  EXPECT_THROW((void)hc::mimo_model_file_from_json(bad), hc::ModelFileError);
}

TEST(MimoDiagnosis, CrossCouplingIsNamedWhereItIsAndNotWhereItIsNot) {
  const auto u = multisines(2, 4, 2, kBins);
  for (const double coupling : {0.0, 1.0}) {
    const auto rec = record_of(linear(coupled_truth(coupling)), u, 2, 1e-3);
    const hc::CouplingDiagnosis d = hc::diagnose_cross_coupling(hc::periodic_spectra(rec), {0, 1});
    ASSERT_EQ(d.outputs.size(), 2u);
    EXPECT_EQ(d.heldout, "realization 3");
    for (const auto& c : d.outputs) {
      EXPECT_EQ(c.left_out_gains.size(), 4u);
      EXPECT_EQ(c.named, coupling > 0.0) << "output " << c.output << " gain " << c.gain;
      if (coupling > 0.0) {
        ASSERT_EQ(c.named_inputs.size(), 1u);
        EXPECT_EQ(c.named_inputs[0], 1 - c.output);  // the other input
        EXPECT_GT(c.gain, 2.0);
      } else {
        EXPECT_TRUE(c.named_inputs.empty());
        EXPECT_LT(c.gain, 1.2);
      }
    }
  }
}

TEST(MimoModelFile, AnOperatorOfAnyPiFamilyTravelsAsItsOwnModelFile) {
  // A modified PI with creep and a delay on input 0 (a model `fit` makes of one axis).
  const nlohmann::json mpi = nlohmann::json::parse(R"({"schema":"hystbench.model/1",
    "type":"mpi","units":{"input":"V","output":"V"},"input_range":[-1,1],
    "play":{"thresholds":[0,0.1,0.2],"weights":[0.8,0.1,0.1],"offset":0},
    "deadzone":{"thresholds":[-0.5,0,0.5],"weights":[0.1,1.0,-0.1],"center":0},
    "creep":{"time_constants_s":[0.01],"gains":[0.02]},"delay_s":0.0002})");
  hc::MimoModelFile f;
  f.model = hc::HammersteinMimoModel({hc::model_file_from_json(mpi).model, std::nullopt},
                                     coupled_truth(1.0), kDt);
  f.sample_period_s = kDt;
  f.inputs = {{"u1", "V"}, {"u2", "V"}};
  f.outputs = {{"y1", "um"}, {"y2", "um"}};
  const nlohmann::json j = hc::to_json(f);
  EXPECT_EQ(j["operators"][0]["model"]["type"], "mpi");
  EXPECT_TRUE(j["operators"][1].is_null());
  const hc::MimoModelFile back = hc::mimo_model_file_from_json(j);
  const Eigen::MatrixXd u = multisines(2, 1, 1, 50)[0];
  const Eigen::MatrixXd y = f.model.simulate(u), y_back = back.model.simulate(u);
  EXPECT_LT((y - y_back).cwiseAbs().maxCoeff(), 1e-12);
  // The operator acts: the same dynamics without it give another output.
  const hc::HammersteinMimoModel plain({std::nullopt, std::nullopt}, coupled_truth(1.0), kDt);
  EXPECT_GT((y - plain.simulate(u)).cwiseAbs().maxCoeff(), 1e-3);
  // A fault inside the operator's own document is named with its place.
  nlohmann::json bad = j;
  bad["operators"][0]["model"]["play"]["weights"] = {1.0};
  try {
    (void)hc::mimo_model_file_from_json(bad);
    FAIL() << "a bad operator was accepted";
  } catch (const hc::ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("operators[0].model"), std::string::npos) << e.what();
  }
}

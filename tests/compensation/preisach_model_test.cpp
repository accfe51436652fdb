#include "hystbench/compensation/preisach_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/preisach_identification.hpp"

namespace hc = hystbench::compensation;

namespace {

hc::PreisachParameters random_parameters(std::mt19937_64& rng, std::size_t n) {
  std::uniform_real_distribution<double> d(0.0, 0.01);
  hc::PreisachParameters p{0.0,  150.0, n, std::vector<double>(hc::PreisachModel::cell_count(n)),
                           0.05, 1.5};
  for (double& x : p.densities) x = d(rng);
  return p;
}

// A drive with reversals of every size inside [lo, hi], ramps of 1 V per sample or less.
std::vector<double> reversals(std::mt19937_64& rng, std::size_t turns, double lo, double hi) {
  std::uniform_real_distribution<double> at(lo, hi);
  std::vector<double> u{lo};
  for (std::size_t t = 0; t < turns; ++t) {
    const double target = at(rng);
    const auto steps = static_cast<std::size_t>(std::ceil(std::abs(target - u.back()))) + 1;
    const double from = u.back();
    for (std::size_t k = 1; k <= steps; ++k) {
      u.push_back(from + (target - from) * static_cast<double>(k) / static_cast<double>(steps));
    }
  }
  return u;
}

}  // namespace

// One diagonal cell of density d over the plane: rising from u_min to u the relays up are the
// triangle u_min <= beta <= alpha <= u, d (u - u_min)^2 / 2; falling back to v from the top takes
// the triangle v <= beta <= alpha <= u_max away.
TEST(PreisachModel, OneCellGivesTheTrianglesArea) {
  hc::PreisachModel m({0.0, 10.0, 1, {0.2}, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(m.step(4.0), 0.2 * 16.0 / 2.0);
  EXPECT_DOUBLE_EQ(m.step(10.0), 0.2 * 100.0 / 2.0);
  EXPECT_DOUBLE_EQ(m.step(7.0), 0.2 * (100.0 - 9.0) / 2.0);
  EXPECT_DOUBLE_EQ(m.everett(10.0, 7.0), 0.2 * 9.0 / 2.0);
  EXPECT_DOUBLE_EQ(m.everett(3.0, 7.0), 0.0);
}

// The Everett function from its prefix tables, against each cell's area in the triangle summed
// by brute force: the output is offset + slope u + sum densities x areas at every sample of a
// drive with minor loops inside minor loops, and the model's output is continuous.
TEST(PreisachModel, TheOutputIsTheDensitiesTimesTheUpAreas) {
  std::mt19937_64 rng(5);
  const hc::PreisachParameters p = random_parameters(rng, 12);
  hc::PreisachModel m(p);
  m.reset(0.0);
  std::vector<double> areas(p.densities.size());
  double y_prev = m.peek(0.0);
  for (const double u : reversals(rng, 300, 0.0, 150.0)) {
    m.cell_areas(u, areas);
    const double y = m.step(u);
    const double sum = std::inner_product(areas.begin(), areas.end(), p.densities.begin(), 0.0);
    ASSERT_NEAR(y, p.offset + p.slope * u + sum, 1e-9 * (1.0 + std::abs(y))) << "u " << u;
    ASSERT_LT(std::abs(y - y_prev), 1.0) << "a jump at u " << u;  // <= 1 V per sample
    y_prev = y;
  }
}

// The identification's row: step_cell_areas(u) gives the areas cell_areas(u) gives and leaves the
// state step(u) leaves, with a rate law's front (its filtered rate stepped once) as without one.
TEST(PreisachModel, StepCellAreasIsCellAreasThenStep) {
  std::mt19937_64 rng(11);
  hc::PreisachParameters p = random_parameters(rng, 12);
  for (const double law_s : {0.0, 2e-4}) {
    p.rate_law.threshold_rate_s = law_s;
    p.rate_law.exponent = 1.0;
    p.rate_law.rate_filter_s = 1e-3;
    hc::PreisachModel stepped(p), twin(p);
    stepped.set_sample_period(1e-4);
    twin.set_sample_period(1e-4);
    stepped.reset(0.0);
    twin.reset(0.0);
    std::vector<double> areas(p.densities.size()), twin_areas(p.densities.size());
    for (const double u : reversals(rng, 300, 0.0, 150.0)) {
      stepped.cell_areas(u, areas);
      (void)stepped.step(u);
      twin.step_cell_areas(u, twin_areas);
      ASSERT_EQ(areas, twin_areas) << "law " << law_s << ", u " << u;
      ASSERT_EQ(stepped.peek(u + 1.0), twin.peek(u + 1.0)) << "law " << law_s << ", u " << u;
    }
  }
}

// Preisach's properties: the output rises with a rising input and falls with a falling one; a
// minor loop closes where it began (return-point memory); the top and bottom of the range
// saturate every relay; peek() is step() without the step.
TEST(PreisachModel, HasReturnPointMemoryAndSaturates) {
  std::mt19937_64 rng(9);
  const hc::PreisachParameters p = random_parameters(rng, 20);
  hc::PreisachModel m(p);
  m.reset(0.0);
  const double total = m.everett(150.0, 0.0);
  EXPECT_NEAR(m.step(150.0), p.offset + p.slope * 150.0 + total, 1e-9);
  EXPECT_NEAR(m.step(0.0), p.offset, 1e-9);
  m.step(120.0);
  const double at_turn = m.step(40.0);  // a reversal at 40 V on the way down from 120 V
  m.step(90.0);
  m.step(60.0);  // a loop inside it
  m.step(80.0);
  EXPECT_NEAR(m.step(40.0), at_turn, 1e-9) << "the minor loops close where they began";
  double last = m.peek(40.0);
  for (double u = 40.0; u <= 150.0; u += 0.5) {
    const double peeked = m.peek(u);
    const double y = m.step(u);
    ASSERT_EQ(peeked, y);
    ASSERT_GE(y, last - 1e-12) << u;
    last = y;
  }
  for (double u = 150.0; u >= -10.0; u -= 0.5) {
    const double y = m.step(u);
    ASSERT_LE(y, last + 1e-12) << u;
    last = y;
  }
  EXPECT_NEAR(last, p.offset + p.slope * -10.0, 1e-9);  // below the plane: the slope alone
}

// A held input returns the output it had: step() keeps it, until anything else moves the relays
// (step_relays(), reset()), after which the same input is stepped again: the same outputs as a
// model stepped through the same moves.
TEST(PreisachModel, AHeldInputKeepsItsOutputUntilTheRelaysMove) {
  std::mt19937_64 rng(11);
  const hc::PreisachParameters p = random_parameters(rng, 10);
  hc::PreisachModel m(p), stepped(p);
  m.reset(0.0);
  stepped.reset(0.0);
  const double at_60 = m.step(60.0);
  EXPECT_EQ(m.step(60.0), at_60);
  EXPECT_EQ(stepped.step(60.0), at_60);
  m.step_relays(140.0);
  stepped.step(140.0);
  const double back = m.step(60.0);
  EXPECT_EQ(back, stepped.step(60.0));
  EXPECT_GT(back, at_60 + 1e-6) << "the loop's descending branch lies above its ascending one";
  m.reset(0.0);
  stepped.reset(0.0);
  EXPECT_EQ(m.step(60.0), stepped.step(60.0));
  EXPECT_EQ(m.step(60.0), at_60);
}

TEST(PreisachModel, NamesWhatIsWrong) {
  EXPECT_THROW(hc::PreisachModel({1.0, 1.0, 2, {0.0, 0.0, 0.0}, 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(hc::PreisachModel({0.0, 1.0, 2, {0.0, 0.0}, 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(hc::PreisachModel({0.0, 1.0, 0, {}, 0.0, 0.0}), std::invalid_argument);
  const hc::PreisachModel negative({0.0, 1.0, 2, {0.1, -0.2, 0.1}, 0.0, 0.5});
  const hc::Invertibility why = negative.invertibility();
  EXPECT_FALSE(why.invertible);
  EXPECT_EQ(why.index, 1);
  EXPECT_NE(why.reason.find("density[1]"), std::string::npos) << why.reason;
  EXPECT_FALSE(hc::PreisachModel({0.0, 1.0, 1, {0.0}, 0.0, 0.0}).invertibility().invertible);
  EXPECT_TRUE(hc::PreisachModel({0.0, 1.0, 1, {0.0}, 0.1, 0.0}).invertibility().invertible);
  hc::PreisachParameters folded{0.0, 1.0, 1, {0.0}, 0.1, 0.0};
  folded.output_map = {{0.0, 0.5}, {1.0, -1.5}};  // the map turns back above 0.5
  const hc::Invertibility map = hc::PreisachModel(folded).invertibility();
  EXPECT_FALSE(map.invertible);
  EXPECT_NE(map.reason.find("output map"), std::string::npos) << map.reason;
}

// A model file keeps the grid, every density bit for bit, the slope and the offset; the loaded
// model steps as the saved one.
TEST(PreisachModel, RoundTripsThroughAModelFile) {
  std::mt19937_64 rng(2);
  hc::PreisachParameters p0 = random_parameters(rng, 7);
  p0.output_map = {{-10.0, 0.0, 10.0}, {0.2, 1.0, -0.3}};  // an output map bends both ends
  p0.center = 20.0;
  hc::ActuatorModel a(std::make_unique<hc::PreisachModel>(p0));
  ASSERT_TRUE(a.hysteresis().invertibility().invertible);
  a.input_min = 0.0;
  a.input_max = 150.0;
  const nlohmann::json j = hc::to_json(hc::ModelFile{a, nlohmann::json::object()});
  EXPECT_EQ(j["type"], "preisach");
  hc::ModelFile back = hc::model_file_from_json(j);
  ASSERT_EQ(back.model.hysteresis().kind(), hc::ModelKind::kPreisach);
  const auto& p = static_cast<const hc::PreisachModel&>(a.hysteresis()).parameters();
  const auto& q = static_cast<const hc::PreisachModel&>(back.model.hysteresis()).parameters();
  EXPECT_EQ(p.densities, q.densities);
  EXPECT_EQ(p.cells, q.cells);
  EXPECT_EQ(q.output_map.weights, p0.output_map.weights);
  EXPECT_EQ(q.center, 20.0);
  a.reset(0.0);
  back.model.reset(0.0);
  for (const double u : reversals(rng, 20, 0.0, 150.0)) ASSERT_EQ(a.step(u), back.model.step(u));
  nlohmann::json bad = j;
  bad["preisach"]["cells"] = 0;
  EXPECT_THROW(hc::model_file_from_json(bad), hc::ModelFileError);
}

// A discrete Preisach model is recovered from its own simulated record, noise-free: every cell's
// density, the slope and the offset within 1e-6 of the truth's (the densities are about 0.005).
TEST(PreisachFit, RecoversADiscreteModelFromItsOwnRecordExactly) {
  std::mt19937_64 rng(17);
  const hc::PreisachParameters truth = random_parameters(rng, 8);
  hc::PreisachModel m(truth);
  const std::vector<double> u = reversals(rng, 600, 0.0, 150.0);
  m.reset(u.front());
  std::vector<double> y;
  y.reserve(u.size());
  for (const double v : u) y.push_back(m.step(v));
  hc::PreisachFitOptions o;
  o.cells = 8;
  o.u_min = 0.0;
  o.u_max = 150.0;
  o.smoothness = {0.0};
  o.output_zones = {0};
  const hc::PreisachFit fit = hc::fit_preisach(u, y, o);
  for (std::size_t i = 0; i < truth.densities.size(); ++i) {
    ASSERT_NEAR(fit.parameters.densities[i], truth.densities[i], 1e-6) << "cell " << i;
  }
  EXPECT_NEAR(fit.parameters.slope, truth.slope, 1e-6);
  EXPECT_NEAR(fit.parameters.offset, truth.offset, 1e-6);
  EXPECT_LT(fit.heldout_rms, 1e-6);
}

#include "hystbench/daemon/identification_fit.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/sim/identification_excitation.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::daemon;

namespace {

constexpr double kDt = 2e-4;       // a 5 kHz loop
constexpr std::size_t kBlock = 5;  // fitted at 1 kHz

struct Record {
  std::vector<double> u, y;
};

/// A noise-free classical PI (10 plays) whose measurement arrives `delay` ticks late, driven by
/// a shortened identification excitation over 0..150 V.
Record delayed_pi_record(std::size_t delay) {
  hc::PiParameters p;
  p.thresholds = hc::uniform_thresholds(10, 75.0);
  for (std::size_t i = 0; i < p.thresholds.size(); ++i) p.weights.push_back(i == 0 ? 0.16 : 0.02);
  hc::PiModel plant(p);
  hystbench::sim::IdentificationExcitationOptions o;
  o.rate_frequencies_hz = {0.5, 5.0};
  o.rate_cycles = {1, 4};
  o.minor_loops = 4;
  o.hold_s = 0.5;
  const auto x = hystbench::sim::identification_excitation(0.0, 150.0, kDt, o);
  plant.reset(x.samples.front());
  Record r;
  r.u = x.samples;
  for (std::size_t k = 0; k < r.u.size(); ++k) {
    r.y.push_back(plant.step(r.u[k >= delay ? k - delay : 0]));
  }
  return r;
}

hc::FitOptions pi_options() {
  hc::FitOptions o;
  o.kind = hc::ModelKind::kPi;
  o.operators = 10;
  o.heldout_fraction = 0.1;
  return o;
}

double heldout_percent(const hc::FitResult& f) { return f.heldout.rmse_percent(); }

}  // namespace

TEST(IdentificationFit, BlockAverageAdvancesTheMeasurementBeforeAveraging) {
  const std::vector<double> u = {0, 1, 2, 3, 4, 5, 6, 7}, y = {10, 11, 12, 13, 14, 15, 16, 17};
  const hd::AveragedRecord r = hd::block_average(u, y, 0.5, 2, 1);
  ASSERT_EQ(r.u.size(), 3u);  // 7 pairs after the shift, 3 whole blocks
  EXPECT_EQ(r.u, (std::vector<double>{0.5, 2.5, 4.5}));
  EXPECT_EQ(r.y, (std::vector<double>{11.5, 13.5, 15.5}));
  EXPECT_EQ(r.t, (std::vector<double>{0.0, 1.0, 2.0}));
}

TEST(IdentificationFit, FindsAWholeTickDelayThatAveragingWouldHide) {
  const Record r = delayed_pi_record(2);
  // Without the delay search the 2-tick delay is 0.4 of a fit sample: the fit cannot see it.
  const hd::IdentificationFit none =
      hd::fit_identification_record(r.u, r.y, kDt, kBlock, pi_options(), 0);
  const hd::IdentificationFit with =
      hd::fit_identification_record(r.u, r.y, kDt, kBlock, pi_options(), 4);
  EXPECT_EQ(none.delay_ticks, 0);
  EXPECT_EQ(with.delay_ticks, 2);
  EXPECT_DOUBLE_EQ(with.fit.model.delay_s(), 2 * kDt);
  EXPECT_EQ(with.delay_heldout_rmse.size(), 5u);
  EXPECT_LE(heldout_percent(with.fit), 0.3);
  EXPECT_LT(heldout_percent(with.fit), 0.5 * heldout_percent(none.fit));
}

TEST(IdentificationFit, NoDelayIsFoundWhereThereIsNone) {
  const Record r = delayed_pi_record(0);
  const hd::IdentificationFit f =
      hd::fit_identification_record(r.u, r.y, kDt, kBlock, pi_options(), 4);
  EXPECT_EQ(f.delay_ticks, 0);
  EXPECT_EQ(f.fit.model.delay_s(), 0.0);
  EXPECT_LE(heldout_percent(f.fit), 0.3);
}

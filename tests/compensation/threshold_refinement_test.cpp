// Threshold refinement (details): the searched thresholds stay a model, however the search runs.
#include "../../compensation/src/details/threshold_refinement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "hystbench/compensation/pi_model.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::compensation::details;

namespace {

// A PI's record over `cycles` rises 0 -> 150 V (401 samples each), each followed by a fall back
// to 0; the fall of cycle `short_cycle` steps down to `fraction` x 150 V first.
std::pair<std::vector<double>, std::vector<double>> full_range_cycles(const hc::PiParameters& p,
                                                                      int cycles, int short_cycle,
                                                                      double fraction) {
  std::vector<double> u, y;
  for (int cycle = 0; cycle < cycles; ++cycle) {
    for (int k = 0; k <= 400; ++k) u.push_back(150.0 * k / 400.0);
    for (int k = 400; k >= 0; --k)
      u.push_back(150.0 * k / 400.0 * (cycle == short_cycle ? fraction : 1.0));
  }
  hc::PiModel truth(p);
  truth.reset(u.front());
  for (const double v : u) y.push_back(truth.step(v));
  return {u, y};
}

}  // namespace

// The search packs thresholds as logarithms of their gaps. A gap it drives towards zero must
// stay a gap: 26.84 + exp(-60) rounds to 26.84, and equal thresholds throw in PiModel (in a
// bench test they did, in the middle of a diagnosis: "play.thresholds[19] = 26.840520 <=
// play.thresholds[18] = 26.840520").
TEST(ThresholdRefinement, AGapDrivenToZeroStaysAGap) {
  const double r = 26.840520;
  ASSERT_EQ(r + std::exp(-60.0), r);  // the hazard
  const double gap = hd::min_threshold_gap(150.0);
  EXPECT_GT(gap, 0.0);
  EXPECT_GT(hd::next_threshold(r, -60.0, gap), r);
  EXPECT_GT(hd::next_threshold(r, -1e300, gap), r);
  EXPECT_NO_THROW(hc::PiModel(
      hc::PiParameters{{0.0, r, hd::next_threshold(r, -60.0, gap)}, {0.3, 0.1, 0.1}, 0.0}));
  // A gap the search keeps is left as it is.
  EXPECT_DOUBLE_EQ(hd::next_threshold(r, std::log(2.5), gap), r + 2.5);
}

// The refinement's result is a model whatever the start: a structure with a play squeezed
// against its neighbour (the truth has plays at 0 and 40 V only) comes back strictly ordered,
// and no worse than it went in.
TEST(ThresholdRefinement, ASqueezedPlayComesBackOrdered) {
  const auto [u, y] = full_range_cycles(hc::PiParameters{{0.0, 40.0}, {0.3, 0.2}, 1.0}, 3, 1, 0.5);
  hd::ModelStructure s;
  s.kind = hc::ModelKind::kPi;
  s.play_thresholds = {0.0, 20.0, 20.0 + 2e-14, 40.0, 60.0};
  const hd::RefinementRecord rec{u, y, 0, u.size(), 1};
  const hd::RefinementResult r = hd::refine_structure(s, rec, hd::RefinementSettings{});
  const std::vector<double>& t = r.structure.play_thresholds;
  ASSERT_EQ(t.size(), s.play_thresholds.size());
  for (std::size_t i = 1; i < t.size(); ++i) EXPECT_GT(t[i], t[i - 1]) << "threshold " << i;
  EXPECT_LE(r.final_rmse, r.initial_rmse);
}

// A play whose threshold is half the fitted rows' input excursion or more never moves within
// them: its column is a constant set by where the record began, and its weight, fitted to
// nothing there, can flatten the model elsewhere. A starting grid that reaches beyond the
// excursion (the top play at 90 V on a 0-150 V record) comes back with every play moving.
TEST(ThresholdRefinement, EveryRefinedPlayMovesWithinTheFittedRows) {
  const auto [u, y] = full_range_cycles(
      hc::PiParameters{{0.0, 20.0, 40.0, 60.0}, {0.3, 0.1, 0.08, 0.05}, 1.0}, 4, 2, 0.4);
  hd::ModelStructure s;
  s.kind = hc::ModelKind::kPi;
  s.play_thresholds = {0.0, 30.0, 60.0, 90.0};
  const hd::RefinementRecord rec{u, y, 401, u.size(), 1};  // the first rise left out
  const hd::RefinementResult r = hd::refine_structure(s, rec, hd::RefinementSettings{});
  ASSERT_LT(r.final_rmse, r.initial_rmse);  // the search ran and kept its result
  const std::vector<double>& t = r.structure.play_thresholds;
  ASSERT_EQ(t.size(), s.play_thresholds.size());
  EXPECT_LT(2.0 * t.back(), 150.0) << "the top play, at " << t.back() << " V";
}

// A modified PI's output depends on the input's path alone: the refinement steps its models on
// sample 0, the residual rows and the input's turning points only. Its errors are bit for bit
// those of every sample stepped, before the search and after it, on a record with holds, a
// dense small sine, a drift column, rows from a later start and a stride.
TEST(ThresholdRefinement, APlayModelSteppedOnItsTurningPointsErrsAsOnEverySample) {
  std::vector<double> u;
  for (int cycle = 0; cycle < 3; ++cycle) {
    for (int k = 0; k <= 300; ++k) u.push_back(140.0 * k / 300.0);
    u.insert(u.end(), 200, 140.0);  // a hold at the top
    for (int k = 300; k >= 0; --k) u.push_back(10.0 + (130.0 - 30.0 * cycle) * k / 300.0);
    for (int k = 0; k < 400; ++k) u.push_back(u.back() + 3.0 * std::sin(0.7 * k));
  }
  hc::PiModel truth(hc::PiParameters{{0.0, 15.0, 35.0, 60.0}, {0.25, 0.1, 0.06, 0.04}, 2.0});
  truth.reset(u.front());
  std::vector<double> y;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double x = truth.step(u[k]);
    y.push_back(x + 2e-4 * x * x + 1e-3 * static_cast<double>(k) + 0.01 * std::sin(1.3 * k));
  }
  hd::ModelStructure s;
  s.kind = hc::ModelKind::kModifiedPi;
  s.dt = 1e-3;
  s.play_thresholds = {0.0, 12.0, 30.0, 50.0, 65.0};
  s.input_reference = 75.0;
  s.center = 25.0;
  s.dead_zone_thresholds = {-20.0, -8.0, 0.0, 10.0, 22.0};
  s.min_play_slope = 1e-3;
  s.min_dead_zone_slope = 1e-3;
  s.drift = true;
  hd::RefinementSettings settings;
  settings.max_rows = 700;  // a stride of 4 over the rows below
  const std::size_t begin = 350;
  const std::size_t stride = (u.size() - begin + settings.max_rows - 1) / settings.max_rows;
  ASSERT_GT(stride, 1U);
  const hd::RefinementRecord rec{u, y, begin, u.size(), stride};
  const hd::RefinementResult r = hd::refine_structure(s, {u, y, begin, u.size(), 1}, settings);
  EXPECT_EQ(r.initial_rmse, hd::structure_rmse(s, rec));
  ASSERT_LT(r.final_rmse, r.initial_rmse);  // the search ran and kept its result
  EXPECT_EQ(r.final_rmse, hd::structure_rmse(r.structure, rec));
}

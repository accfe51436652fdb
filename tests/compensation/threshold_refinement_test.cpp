// Threshold refinement (details): the searched thresholds stay a model, however the search runs.
#include "../../compensation/src/details/threshold_refinement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hystbench/compensation/pi_model.hpp"

namespace hc = hystbench::compensation;
namespace hd = hystbench::compensation::details;

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
  hc::PiModel truth(hc::PiParameters{{0.0, 40.0}, {0.3, 0.2}, 1.0});
  std::vector<double> u, y;
  for (int cycle = 0; cycle < 3; ++cycle) {
    for (int k = 0; k <= 400; ++k) u.push_back(150.0 * k / 400.0);
    for (int k = 400; k >= 0; --k) u.push_back(150.0 * k / 400.0 * (cycle == 1 ? 0.5 : 1.0));
  }
  truth.reset(u.front());
  for (const double v : u) y.push_back(truth.step(v));
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

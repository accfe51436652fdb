#include "hystbench/compensation/stage_interaction.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hc = hystbench::compensation;
using C = std::complex<double>;

namespace {

hc::MeasuredResponse flat(C value, std::vector<double> lines = {1.0, 10.0, 100.0}) {
  hc::MeasuredResponse r;
  r.frequency_hz = lines;
  r.response.assign(lines.size(), value);
  r.noise.assign(lines.size(), 0.0);
  r.coherence.assign(lines.size(), 1.0);
  return r;
}

}  // namespace

// Two axes: E T = [[0, g01 / g11 T1], [g10 / g00 T0, 0]], whose spectral radius is
// sqrt(|g01 g10 T0 T1| / |g00 g11|).
TEST(StageInteraction, TheSpectralRadiusOfTwoCoupledLoops) {
  const std::vector<std::vector<hc::MeasuredResponse>> g = {{flat(2.0), flat(0.4)},
                                                            {flat(0.9), flat(1.0)}};
  // L = 1 at every line: T = 1/2 on both axes.
  const std::vector<std::vector<C>> loops(2, std::vector<C>(3, C(1.0, 0.0)));
  const hc::StageInteraction s = hc::stage_interaction(g, loops);
  ASSERT_EQ(s.frequency_hz.size(), 3u);
  const double expected = std::sqrt(0.4 * 0.9 / 2.0) * 0.5;
  for (const double rho : s.spectral_radius) EXPECT_NEAR(rho, expected, 1e-12);
  EXPECT_NEAR(s.peak, expected, 1e-12);
  EXPECT_TRUE(s.dominant());
}

// A loop near -1 at one line (a peak of |T|) lifts the interaction past 1 there: the loops,
// each stable alone, are no longer proven stable together.
TEST(StageInteraction, APeakOfTheComplementarySensitivityBreaksDominance) {
  const std::vector<std::vector<hc::MeasuredResponse>> g = {{flat(1.0), flat(0.3)},
                                                            {flat(0.3), flat(1.0)}};
  std::vector<std::vector<C>> loops(2, std::vector<C>(3, C(10.0, 0.0)));
  loops[0][2] = loops[1][2] = C(-0.8, 0.1);  // |T| = |L / (1 + L)| about 3.6 at 100 Hz
  const hc::StageInteraction s = hc::stage_interaction(g, loops);
  EXPECT_FALSE(s.dominant());
  EXPECT_EQ(s.peak_hz, 100.0);
  EXPECT_LT(s.spectral_radius[0], 0.3);
}

TEST(StageInteraction, LinesNotEveryResponseSharesAreLeftOutAndBadShapesRefused) {
  const std::vector<std::vector<hc::MeasuredResponse>> g = {{flat(1.0), flat(0.1, {1.0, 100.0})},
                                                            {flat(0.1), flat(1.0)}};
  const std::vector<std::vector<C>> loops(2, std::vector<C>(3, C(1.0, 0.0)));
  EXPECT_EQ(hc::stage_interaction(g, loops).frequency_hz, (std::vector<double>{1.0, 100.0}));
  EXPECT_THROW(hc::stage_interaction({{flat(1.0)}}, {{C(1.0)}}), std::invalid_argument);
  EXPECT_THROW(hc::stage_interaction(g, {loops[0]}), std::invalid_argument);
  const std::vector<std::vector<hc::MeasuredResponse>> apart = {
      {flat(1.0, {2.0}), flat(0.1, {3.0})}, {flat(0.1, {2.0}), flat(1.0, {2.0})}};
  EXPECT_THROW(hc::stage_interaction(apart, loops), std::invalid_argument);
}

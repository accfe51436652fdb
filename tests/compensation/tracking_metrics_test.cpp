#include "hystbench/compensation/tracking_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace hc = hystbench::compensation;

namespace {

// 19 periods of a 500 Hz sine at 10 kHz (20 samples a period), 18 um in amplitude, and the
// output: the same sine `lag` samples later, an offset, a gain error and a loop-shape error in
// its second and fourth harmonics.
struct Track {
  std::vector<double> y_ref, y;
};
Track sine_track(double lag, double gain) {
  Track t;
  const double w = 2.0 * std::numbers::pi / 20.0;
  for (int k = 0; k < 380; ++k) {
    t.y_ref.push_back(20.0 + 18.0 * std::sin(w * k));
    t.y.push_back(20.3 + 18.0 * gain * std::sin(w * (k - lag)) + 0.2 * std::cos(2.0 * w * k) +
                  0.14 * std::sin(4.0 * w * k + 0.3));
  }
  return t;
}

}  // namespace

TEST(OutputLag, IsTheDelayBehindTheReferenceToAFractionOfASample) {
  for (const double lag : {-0.3, -0.05, 0.0, 0.04, 0.5}) {
    for (const double gain : {1.0, 0.99}) {
      const Track t = sine_track(lag, gain);
      // To first order: the shift's second-order term is lag^2 (w^2 / 2) of the amplitude.
      EXPECT_NEAR(hc::output_lag_samples(t.y_ref, t.y), lag * gain, 0.01 + 0.02 * lag * lag)
          << "lag " << lag << " gain " << gain;
    }
  }
}

TEST(OutputLag, NothingWhereTheReferenceHolds) {
  const std::vector<double> y_ref(100, 5.0), y(100, 5.5);
  EXPECT_EQ(hc::output_lag_samples(y_ref, y), 0.0);
  EXPECT_EQ(hc::output_lag_samples(std::vector<double>{1.0, 2.0}, std::vector<double>{1.0, 2.0}),
            0.0);
}

// What the other axes' motion left on each axis of a stage: recovered from errors that hold a
// known share of the other axes' outputs beside an error of their own.
#include "hystbench/compensation/stage_coupling_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace hc = hystbench::compensation;

namespace {

std::string refusal(const Eigen::MatrixXd& e, const Eigen::MatrixXd& y) {
  try {
    (void)hc::coupling_error_left(e, y);
  } catch (const std::invalid_argument& ex) {
    return ex.what();
  }
  return "";
}

}  // namespace

TEST(StageCouplingErrorLeft, RecoversTheShareOfEachOtherAxisBesideAnErrorOfItsOwn) {
  constexpr int kSamples = 20000;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::MatrixXd y(3, kSamples), e(3, kSamples);
  for (int k = 0; k < kSamples; ++k) {
    const double t = k * 1e-4;
    y(0, k) = 20.0 + 15.0 * std::sin(2.0 * M_PI * 10.0 * t);
    y(1, k) = 20.0 + 15.0 * std::sin(2.0 * M_PI * 11.0 * t);
    y(2, k) = 7.0;  // held: explains nothing
    // y's error holds 0.02 of x's motion and an error of its own (a 3 Hz ripple).
    e(0, k) = noise(rng);
    e(1, k) = 0.02 * (y(0, k) - 20.0) + 0.05 * std::sin(2.0 * M_PI * 3.0 * t) + noise(rng);
    e(2, k) = -0.01 * (y(1, k) - 20.0) + noise(rng);
  }
  const hc::CouplingErrorLeft left = hc::coupling_error_left(e, y);
  EXPECT_NEAR(left.gains(1, 0), 0.02, 1e-3);
  EXPECT_NEAR(left.gains(2, 1), -0.01, 1e-3);
  EXPECT_NEAR(left.gains(0, 1), 0.0, 1e-3);
  EXPECT_EQ(left.gains(0, 2), 0.0);  // the held axis
  EXPECT_EQ(left.gains(1, 1), 0.0);
  // 0.02 of a 15 um sine: 0.212 um rms; the axis's own ripple is not counted.
  EXPECT_NEAR(left.rms_um(1), 0.02 * 15.0 / std::sqrt(2.0), 0.005);
  EXPECT_GT(left.error_rms_um(1), left.rms_um(1));
}

TEST(StageCouplingErrorLeft, RefusesWhatItCannotRegress) {
  const Eigen::MatrixXd two = Eigen::MatrixXd::Random(2, 50);
  EXPECT_EQ(refusal(two, Eigen::MatrixXd::Random(2, 40)),
            "coupling error: errors are 2 x 50, outputs 2 x 40");
  EXPECT_EQ(refusal(Eigen::MatrixXd::Random(1, 50), Eigen::MatrixXd::Random(1, 50)),
            "coupling error: a stage has two axes at least");
  EXPECT_EQ(refusal(Eigen::MatrixXd::Random(2, 5), Eigen::MatrixXd::Random(2, 5)),
            "coupling error: fewer than 10 samples");
  Eigen::MatrixXd bad = two;
  bad(1, 3) = NAN;
  EXPECT_EQ(refusal(bad, two), "coupling error: a value is not finite");
}

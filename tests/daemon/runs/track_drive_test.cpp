// The track kind's drive (TrackDrive), stepped by hand: the feedback compares a reading that
// answered late with the reference of the tick it answered, so that a late exchange is not
// corrected as an error of the stage.
#include "hystbench/daemon/runs/track_drive.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/feedback_controller.hpp"
#include "hystbench/sim/signal_generator.hpp"

namespace hd = hystbench::daemon;
namespace hc = hystbench::compensation;

namespace {

constexpr double kDt = 1e-3;

// An integral loop whose first step is its error (ki dt = 1, through a unit linear map) on a
// ramp of 0.5 µm per tick.
hd::TrackDrive integral_drive() {
  hd::TrackDrive drive;
  std::vector<double> ramp(1000);
  for (std::size_t i = 0; i < ramp.size(); ++i) ramp[i] = 0.5 * static_cast<double>(i);
  drive.reference = hystbench::sim::make_uniform_signal(ramp, kDt);
  hc::FeedbackLaw law;
  law.pid.ki = 1.0 / kDt;
  drive.compensator.emplace(hc::CompensatorKind::kPid, nullptr, hc::FeedbackController(law, kDt),
                            hc::LinearMap{.gain = 1.0, .offset = 0.0});
  drive.configure(hd::DriveSetup{kDt, 0.0, 150.0, 0});
  return drive;
}

// The update at tick k after one at tick k - 1: its reading (of tick k - 1) and how late it
// answered; the loop's output.
double feedback_at(std::uint64_t k, double y, std::uint64_t late) {
  hd::TrackDrive drive = integral_drive();
  (void)drive.update(hd::DriveInput{k - 1, 0.5 * static_cast<double>(k - 2), true, 0});
  return drive.update(hd::DriveInput{k, y, true, late}).u_fb;
}

TEST(TrackDrive, AReadingThatAnsweredLateIsComparedWithTheReferenceOfThen) {
  constexpr std::uint64_t k = 100;
  // The stage followed its reference exactly: the reading held at tick k shows the ramp of tick
  // k - 1 on time, of tick k - 4 when it answered 3 ticks late.
  const double on_time = feedback_at(k, 0.5 * (k - 1), 0);
  EXPECT_NEAR(on_time, 0.0, 1e-12);
  EXPECT_NEAR(feedback_at(k, 0.5 * (k - 4), 3), 0.0, 1e-12)
      << "the late reading shows no error of its own";
  // Taken as on time, it would show the ramp's 1.5 µm since then, and the loop correct them.
  EXPECT_NEAR(feedback_at(k, 0.5 * (k - 4), 0), 1.5, 1e-9);
  // A stage 0.2 µm behind shows it either way.
  EXPECT_NEAR(feedback_at(k, 0.5 * (k - 4) - 0.2, 3), 0.2, 1e-9);
}

}  // namespace

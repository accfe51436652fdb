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
const hd::DriveSetup kSetup{kDt, 0.0, 150.0, 0};

// An integral loop whose first step is its error (ki dt = 1, through a unit linear map) on a
// ramp of 0.5 µm per tick.
hd::TrackDrive integral_drive() {
  hd::TrackDrive drive;
  std::vector<double> ramp(1000);
  for (std::size_t i = 0; i < ramp.size(); ++i) ramp[i] = 0.5 * static_cast<double>(i);
  drive.program.reference = hystbench::sim::make_uniform_signal(ramp, kDt);
  hc::FeedbackLaw law;
  law.pid.ki = 1.0 / kDt;
  drive.program.compensator.emplace(hc::CompensatorKind::kPid, nullptr,
                                    hc::FeedbackController(law, kDt),
                                    hc::LinearMap{.gain = 1.0, .offset = 0.0});
  drive.configure(kSetup);
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

// The outputs of ticks 1..n with the stage held at 0 µm (the integral winds up on the ramp).
std::vector<double> outputs_at_rest(hd::TrackDrive& drive, std::uint64_t n) {
  std::vector<double> u;
  for (std::uint64_t k = 1; k <= n; ++k)
    u.push_back(drive.update(hd::DriveInput{k, 0.0, true, 0}).u);
  return u;
}

TEST(TrackDrive, ARunStepsAStateMadeFromTheProgramAndLeavesTheProgramAsBuilt) {
  hd::TrackDrive drive = integral_drive();
  const std::vector<double> first = outputs_at_rest(drive, 50);
  ASSERT_GT(first.back(), first.front()) << "the integral winds up over the run";
  // The run stepped its state's compensator: configured again, the drive starts from the
  // program's, relaxed as built, and plays the same run again.
  drive.configure(kSetup);
  EXPECT_EQ(outputs_at_rest(drive, 50), first);
  // The program's compensator itself was never stepped: its first step is the run's first.
  hc::Compensator built = *drive.program.compensator;
  built.set_drive_range(kSetup.u_min, kSetup.u_max);
  EXPECT_DOUBLE_EQ(built.step(0.5 * 1.0, 0.0, 0.5).u, first.front());
}

}  // namespace

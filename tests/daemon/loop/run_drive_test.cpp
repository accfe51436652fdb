// The loop's contract with a run kind's drive (RunDrive), held with a drive that records what the
// loop asks and tells it: the excitation plays first, then the drive gives each tick's output and
// hears the tick's bound, prediction, fresh readings and score; a drive ends its run or moves its
// scored part through its score. BenchLoop is stepped tick by tick on the test's thread.
#include "hystbench/daemon/loop/run_drive.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "drivers/example_driver.hpp"
#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/loop/sample_record.hpp"
#include "support/stepped_loop.hpp"

namespace hd = hystbench::daemon;
namespace hc = hystbench::compensation;

namespace {

constexpr double kRate = 2000.0;
constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();

// Records every call into buffers reserved before the run (the loop's calls must not allocate).
class RecordingDrive final : public hd::RunDrive {
 public:
  std::uint64_t last_trial_at = kNever;    ///< scored() ends the run here
  std::uint64_t lead_in_ends_at = kNever;  ///< scored() moves the scored part here ...
  std::uint64_t scored_from = kNever;      ///< ... to this tick
  std::uint64_t reference_clipped_at = kNever;

  std::optional<hd::DriveSetup> setup;
  std::vector<hd::DriveInput> updates;
  std::vector<std::uint64_t> predictions, readings, scores;
  std::vector<int> bounds;

  void configure(const hd::DriveSetup& s) override {
    setup = s;
    for (auto* v : {&predictions, &readings, &scores}) v->reserve(1000);
    updates.reserve(1000);
    bounds.reserve(1000);
  }
  hd::DriveCommand update(const hd::DriveInput& in) noexcept override {
    updates.push_back(in);
    hd::DriveCommand c;
    c.y_ref = 3.0;
    c.u_ff = 9.0;
    c.u_fb = 1.0;
    c.u = c.u_ff + c.u_fb;
    if (in.k == reference_clipped_at) c.flags = hd::kSampleReferenceLimited;
    return c;
  }
  void limited(int direction) noexcept override { bounds.push_back(direction); }
  void predicted(std::uint64_t k, double) noexcept override { predictions.push_back(k); }
  void measured(std::uint64_t k, const hystbench::drivers::Measurement&) noexcept override {
    readings.push_back(k);
  }
  hd::DriveScore scored(std::uint64_t k, double y_ref, double, double u_ff) noexcept override {
    scores.push_back(k);
    hd::DriveScore s;
    // Before the drive's first tick the loop scores the excitation: no reference, its drive.
    if (k < setup->first_tick) {
      EXPECT_TRUE(std::isnan(y_ref));
      EXPECT_EQ(u_ff, 2.0);
    }
    s.last_trial = k == last_trial_at;
    if (k == lead_in_ends_at) s.scored_from = scored_from;
    return s;
  }
};

hystbench::test::SteppedLoop stepped_loop() {
  return hystbench::test::stepped_loop(std::make_unique<example::FirstOrderDriver>(), kRate);
}

// 10 ticks of excitation at 2 V, then the drive, 40 ticks in all, every sample kept.
std::unique_ptr<hd::RunProgram> program_with(std::unique_ptr<RecordingDrive> drive) {
  auto p = std::make_unique<hd::RunProgram>();
  p->excitation.assign(10, 2.0);
  p->total_samples = 40;
  p->drive = std::move(drive);
  p->records.capacity = p->total_samples;
  p->records.u.resize(p->total_samples);
  p->records.y.resize(p->total_samples);
  p->records.yr.resize(p->total_samples);
  return p;
}

}  // namespace

TEST(RunDrive, TheExcitationPlaysFirstThenTheDriveGivesEveryTicksOutputAndHearsTheTick) {
  hystbench::test::SteppedLoop s = stepped_loop();
  auto owned = std::make_unique<RecordingDrive>();
  RecordingDrive& drive = *owned;
  drive.reference_clipped_at = 25;
  auto program = program_with(std::move(owned));
  program->feedback_from = 20;
  hc::PiParameters pi;
  pi.thresholds = {0.0};
  pi.weights = {0.2};
  program->model.emplace(std::make_unique<hc::PiModel>(pi));
  ASSERT_EQ(s.loop->submit(std::move(program)), nullptr);
  ASSERT_TRUE(drive.setup.has_value()) << "submit() configures the drive before the run";
  EXPECT_DOUBLE_EQ(drive.setup->dt_s, 1.0 / kRate);
  EXPECT_EQ(drive.setup->first_tick, 10u);
  EXPECT_DOUBLE_EQ(drive.setup->u_max, hd::OutputLimits{}.u_max);
  for (int k = 0; k < 40; ++k) s.loop->step();
  auto done = s.loop->take_finished();
  ASSERT_NE(done, nullptr);
  ASSERT_EQ(done->end, hd::RunEnd::kCompleted) << done->end_reason;

  // update() from the tick after the excitation to the last, each with the last fresh reading
  // and whether the feedback may act.
  ASSERT_EQ(drive.updates.size(), 30u);
  for (std::size_t i = 0; i < drive.updates.size(); ++i) {
    const hd::DriveInput& in = drive.updates[i];
    EXPECT_EQ(in.k, 10 + i);
    EXPECT_EQ(in.feedback_on, in.k >= 20) << in.k;
  }
  // The output: the excitation, then the drive's.
  for (std::size_t k = 0; k < 40; ++k) EXPECT_DOUBLE_EQ(done->records.u[k], k < 10 ? 2.0 : 10.0);
  // Every tick hears its bound, its prediction and its score; the fresh readings only (the
  // example stage answers every second tick).
  EXPECT_EQ(drive.bounds.size(), 40u);
  EXPECT_EQ(drive.predictions.size(), 40u);
  EXPECT_EQ(drive.scores.size(), 40u);
  EXPECT_EQ(drive.readings.size(), 40u - done->counters.stale_reads);
  EXPECT_GT(done->counters.stale_reads, 0u);
  // The loop scores the drive's reference and counts the ticks it flagged.
  EXPECT_EQ(done->error.samples, 30u);
  EXPECT_EQ(done->counters.reference_clips, 1u);
  EXPECT_DOUBLE_EQ(done->records.yr[25], 3.0);
}

TEST(RunDrive, ADrivesLastTrialEndsTheRunAndAnEarlierScoredStartMovesTheWindows) {
  hystbench::test::SteppedLoop s = stepped_loop();
  auto owned = std::make_unique<RecordingDrive>();
  RecordingDrive& drive = *owned;
  drive.lead_in_ends_at = 12;  // a lead-in that ends early: scored from 15, not 18
  drive.scored_from = 15;
  drive.last_trial_at = 30;
  auto program = program_with(std::move(owned));
  program->metrics_from = 18;
  program->feedback_from = 18;  // began with the scored part: moves with it
  ASSERT_EQ(s.loop->submit(std::move(program)), nullptr);
  for (int k = 0; k < 40; ++k) s.loop->step();
  auto done = s.loop->take_finished();
  ASSERT_NE(done, nullptr);
  ASSERT_EQ(done->end, hd::RunEnd::kCompleted) << done->end_reason;
  EXPECT_EQ(done->done.load(), 31u) << "the last trial's tick ends the run";
  EXPECT_EQ(done->metrics_from, 15u);
  EXPECT_EQ(done->feedback_from, 15u);
  EXPECT_EQ(done->error.samples, 31u - 15u);
  for (const hd::DriveInput& in : drive.updates) EXPECT_EQ(in.feedback_on, in.k >= 15) << in.k;
}

TEST(RunDrive, ARunLongerThanItsExcitationWithoutADriveIsRefused) {
  hystbench::test::SteppedLoop s = stepped_loop();
  auto program = program_with(nullptr);
  auto refused = s.loop->submit(std::move(program));
  ASSERT_NE(refused, nullptr) << "nothing would give the output after the excitation";
  refused->total_samples = refused->excitation.size();  // the excitation alone: accepted
  EXPECT_EQ(s.loop->submit(std::move(refused)), nullptr);
}

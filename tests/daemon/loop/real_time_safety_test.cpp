// The loop's whole per-tick path must not allocate (bench_loop.hpp): reference, compensator
// (inverse, previewed inverse, PID), dynamics preview, limiter, model prediction, ring push,
// driver write and read, counted on the test thread (support/allocation_counter.hpp), which
// steps the loop itself.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "hystbench/compensation/pid_controller.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"
#include "hystbench/sim/simulated_actuator.hpp"
#include "support/allocation_counter.hpp"

using hystbench::test::allocations_during;

namespace hc = hystbench::compensation;
namespace hd = hystbench::daemon;
namespace hs = hystbench::sim;

namespace {
constexpr double kRate = 10000.0;

struct Case {
  const char* name;
  bool rate_dependence;  // the truth's rate law: the previewed numeric inverse
  bool dynamics;         // creep and resonance: the dynamics preview
  bool feedback;         // inverse+pid
};

/// Ticks of a whole track run (precondition sweep, then the reference through the compensator)
/// on the loopback actuator (the default truth with the case's effects) with a model of the same
/// effects (the modified-PI truth's: a model the inverse, the plan and the preview can take),
/// logged to a file.
long run_allocations(const Case& c, const std::filesystem::path& dir) {
  hs::SimulatedActuatorConfig plant;
  plant.rate_dependence.enabled = c.rate_dependence;
  plant.creep.enabled = c.dynamics;
  plant.dynamics.enabled = c.dynamics;
  hs::SimulatedActuatorConfig truth_config = hs::SimulatedActuatorConfig::modified_pi_truth();
  truth_config.rate_dependence.enabled = c.rate_dependence;
  truth_config.creep.enabled = c.dynamics;
  truth_config.dynamics.enabled = c.dynamics;
  auto driver = hystbench::drivers::make_driver("loopback");
  EXPECT_TRUE(driver->configure({{"actuator", hs::to_json(plant)}}, kRate).ok);
  EXPECT_TRUE(driver->activate().ok);
  hd::BenchLoopOptions o;
  o.rate_hz = kRate;
  hd::BenchLoop loop(*driver, o);
  loop.step();

  hd::VerificationSpec spec;
  spec.frequency_hz = 10.0;
  spec.periods = 2.0;
  spec.precondition_s = 0.1;
  auto program = hd::make_verification_program(hs::make_truth_model(truth_config, 1.0 / kRate),
                                               spec, loop.last_output(), o.limits, 1.0 / kRate);
  if (c.feedback) {
    // The designed loop's parts: a boost, the integral, a notch and a low-pass, and resonators
    // at the reference's first harmonics.
    hc::FeedbackLaw law{
        {300.0, 10.0},
        {0.0, 2000.0, 0.0, 0.0, -9.0, 9.0, 0.0},
        {{{3000.0, 0.5, 0.1}}, {2500.0, 0.7071}},
        {{{10.0, {1.0, 0.0}, 0.01}, {20.0, {0.0, 1.0}, 0.01}, {30.0, {0.5, 0.5}, 0.02}}, 9.0}};
    // Rebuild the compensator with the same inverse plus feedback.
    auto truth = hs::make_truth_model(truth_config, 1.0 / kRate);
    const hc::ActuatorModel m = hd::model_after(truth, program->excitation, loop.last_output(),
                                                o.limits.u_min, o.limits.u_max, 1.0 / kRate);
    hd::track_drive(*program)->program.compensator.emplace(
        hc::CompensatorKind::kInversePid, hc::make_inverse(m),
        hc::FeedbackController(law, 1.0 / kRate), hc::LinearMap{});
  }
  hd::SampleLogOptions log;
  log.log_dir = dir;
  log.run_id = c.name;
  program->log = std::make_unique<hd::SampleLogWriter>(log);
  const std::uint64_t total = program->total_samples;
  EXPECT_EQ(loop.submit(std::move(program)), nullptr);
  EXPECT_GT(total, 2000u);
  const long n = allocations_during([&] {
    for (std::uint64_t k = 0; k < total; ++k) loop.step();
  });
  auto done = loop.take_finished();
  EXPECT_NE(done, nullptr);
  if (done) {
    EXPECT_EQ(done->end, hd::RunEnd::kCompleted) << done->end_reason;
    EXPECT_EQ(done->counters.log_drops, 0u);
    EXPECT_EQ(done->error.samples, 1000u);  // the second period at 10 kHz
    done->log->close();
  }
  return n;
}
}  // namespace

std::vector<double>* escaped = nullptr;

TEST(RealTimeSafety, TheCounterSeesAnAllocation) {
  EXPECT_EQ(allocations_during([] { escaped = new std::vector<double>(1000); }), 2);
  delete escaped;
}

TEST(RealTimeSafety, TheLoopsPerTickPathDoesNotAllocate) {
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("hystbench-rt-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
       std::to_string(getpid()));
  for (const Case& c : {Case{"static-inverse", false, false, false},
                        Case{"dynamics-preview-pid", false, true, true},
                        Case{"rate-previewed-inverse", true, false, false},
                        Case{"rate-previewed-inverse-pid", true, true, true}}) {
    SCOPED_TRACE(c.name);
    EXPECT_EQ(run_allocations(c, dir), 0);
  }
  std::filesystem::remove_all(dir);
}

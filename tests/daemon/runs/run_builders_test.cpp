// The run builders without a bench, a loop or threads: what a track, identify or excite request
// becomes (reference, prefix, preview, limits, records), and what each refuses.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"
#include "runs/details/excite_program.hpp"
#include "runs/details/identify_program.hpp"
#include "runs/details/response_program.hpp"
#include "runs/details/track_program.hpp"
#include "runs/details/track_request.hpp"
#include "service/details/command_table.hpp"

namespace hd = hystbench::daemon;
namespace common = hystbench::common;
namespace hdd = hystbench::daemon::details;
namespace hc = hystbench::compensation;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::StartsWith;

namespace {

// 1 kHz, outputs 0..150 V, limits.y_min..y_max = 0..45 um, a 0.4 s precondition sweep.
hd::BenchSettings settings() {
  hd::BenchSettings s;
  s.loop.rate_hz = 1000.0;
  s.y_min = 0.0;
  s.y_max = 45.0;
  s.precondition_s = 0.4;
  return s;
}

hc::ModelFile pi_model() {
  hc::ActuatorModel m(
      std::make_unique<hc::PiModel>(hc::PiParameters{{0.0, 20.0}, {0.3, 0.1}, 0.0}));
  m.input_min = 0.0;
  m.input_max = 150.0;
  return hc::ModelFile{std::move(m), json::object()};
}

// The request checked against track's row, as Bench::handle checks it.
hdd::BuiltRun track(const json& params, const hdd::RunContext& ctx,
                    const hd::Upload* up = nullptr) {
  const hdd::Command& c = hdd::find_command("track", params);
  const hdd::RequestParams request(params, c.params);
  return hdd::make_track_program(hdd::parse_track_request(request, ctx), ctx, up);
}

std::string refusal(const json& params, const hdd::RunContext& ctx) {
  try {
    (void)track(params, ctx);
  } catch (const common::CommandError& e) {
    return e.code() + ": " + e.what();
  }
  return "ok";
}

}  // namespace

namespace {

hdd::TrackRequest parsed(const json& params, const hdd::RunContext& ctx) {
  const hdd::Command& c = hdd::find_command("track", params);
  return hdd::parse_track_request(hdd::RequestParams(params, c.params), ctx);
}

}  // namespace

TEST(TrackRequest, EveryKeyIsReadOnceOverTheBenchsDefaults) {
  const hd::BenchSettings s = settings();
  const hc::ModelFile model = pi_model();
  const hdd::TrackRequest none = parsed(json::object(), {s, nullptr, 0.0});
  EXPECT_EQ(none.compensator, "none");  // no model: nothing to invert
  EXPECT_EQ(none.reference.name, "triangle");
  EXPECT_DOUBLE_EQ(none.precondition_s, s.precondition_s);
  EXPECT_FALSE(none.gains.any());
  EXPECT_FALSE(none.learning.any());

  const hdd::TrackRequest r = parsed({{"reference", "sine"},
                                      {"frequency_hz", 4.0},
                                      {"min_um", 5.0},
                                      {"kd", 0.01},
                                      {"learn_trials", 3},
                                      {"precondition_s", 0.1}},
                                     {s, &model, 0.0});
  EXPECT_EQ(r.compensator, "inverse");  // a model: its inverse
  EXPECT_EQ(r.compensator_kind, hc::CompensatorKind::kInverse);
  EXPECT_EQ(r.reference.kind, hystbench::sim::SignalKind::kSine);
  EXPECT_DOUBLE_EQ(r.reference.frequency_hz, 4.0);
  EXPECT_EQ(r.reference.min_um, 5.0);
  EXPECT_FALSE(r.reference.max_um);
  EXPECT_FALSE(r.gains.kp);
  EXPECT_EQ(r.gains.kd, 0.01);
  EXPECT_EQ(r.learning.trials, 3u);
  EXPECT_DOUBLE_EQ(r.precondition_s, 0.1);

  const hdd::TrackRequest up =
      parsed({{"reference_upload", "r"}, {"approach_s", 0.5}}, {s, nullptr, 0.0});
  EXPECT_EQ(up.reference_upload, "r");
  EXPECT_DOUBLE_EQ(up.approach_s, 0.5);
  // Beyond a twentieth of the 1 kHz loop rate, and an upload without a name.
  EXPECT_THROW(parsed({{"frequency_hz", 60.0}}, {s, nullptr, 0.0}), common::CommandError);
  EXPECT_THROW(parsed({{"reference_upload", ""}}, {s, nullptr, 0.0}), common::CommandError);
}

TEST(TrackProgram, ABuiltInTriangleWithoutAModelFollowsTheConfiguredRange) {
  const hd::BenchSettings s = settings();
  const hdd::RunContext ctx{s, nullptr, 10.0};
  const hdd::BuiltRun run =
      track({{"compensator", "none"}, {"frequency_hz", 2.0}, {"periods", 3}}, ctx);
  const hd::RunProgram& p = *run.program;
  ASSERT_NE(hd::track_drive(p), nullptr);
  const hd::TrackProgram& t = hd::track_drive(p)->program;
  EXPECT_EQ(p.kind, hd::RunKind::kTrack);
  EXPECT_TRUE(p.run_id.empty());  // the bench names it
  // The prefix is the precondition sweep from the present output: 0.4 s at 1 kHz.
  EXPECT_EQ(p.excitation, hd::precondition_sweep(10.0, 0.0, 150.0, 0.4, 1e-3));
  const std::uint64_t prefix = p.excitation.size();
  ASSERT_EQ(prefix, 400u);
  // Three periods of 0.5 s; the first is left out of the figures.
  EXPECT_EQ(p.total_samples, prefix + 1500);
  EXPECT_EQ(p.metrics_from, prefix + 500);
  EXPECT_EQ(p.records.capacity, 1000u);
  EXPECT_EQ(p.records.u.size(), 1000u);
  EXPECT_TRUE(p.records.response.empty());
  // 80 % of 0..45 um, starting at the bottom and rising.
  ASSERT_TRUE(t.reference);
  EXPECT_NEAR(t.reference->value(0.0), 4.5, 1e-9);
  EXPECT_NEAR(t.reference->value(0.25), 40.5, 1e-9);
  EXPECT_DOUBLE_EQ(t.y_ref_min, 0.0);
  EXPECT_DOUBLE_EQ(t.y_ref_max, 45.0);
  // No model: nothing to preview or tare; y_model is the range's straight line.
  EXPECT_FALSE(t.preview);
  EXPECT_GE(t.tare.from, p.excitation.size());
  ASSERT_TRUE(p.model);
  ASSERT_TRUE(t.compensator);
  EXPECT_DOUBLE_EQ(run.reply["reference"]["min_um"].get<double>(), 4.5);
  EXPECT_DOUBLE_EQ(run.reply["reference"]["max_um"].get<double>(), 40.5);
  EXPECT_TRUE(run.reply["feedforward"].is_null());
  EXPECT_EQ(run.header["run"]["precondition_samples"], prefix);
  EXPECT_EQ(run.header["y_model"], "linear map of limits.y_min..y_max, stepped with u");
  EXPECT_EQ(p.summary["y_model"], run.header["y_model"]);  // the result says whose error it gives
  EXPECT_EQ(run.status["compensator"], "none");
}

TEST(TrackProgram, AModelsInverseIsPreviewedAndTaredOverTheModelsRange) {
  const hd::BenchSettings s = settings();
  const hc::ModelFile model = pi_model();
  const hdd::RunContext ctx{s, &model, 0.0};
  const hdd::BuiltRun run = track({{"periods", 2}}, ctx);  // "inverse" is the default with a model
  const hd::RunProgram& p = *run.program;
  ASSERT_NE(hd::track_drive(p), nullptr);
  const hd::TrackProgram& t = hd::track_drive(p)->program;
  const hd::ModelOutputRange range = hd::major_loop_range(model.model, 0.0, 150.0, 1e-3);
  EXPECT_DOUBLE_EQ(t.y_ref_min, range.y_bottom);
  EXPECT_DOUBLE_EQ(t.y_ref_max, range.y_top);
  EXPECT_EQ(run.reply["compensator"], "inverse");
  EXPECT_EQ(p.summary["feedforward"]["inverted"], json::array({"hysteresis"}));
  EXPECT_FALSE(p.summary["feedforward"].contains("planned"));  // nothing to plan for a PI
  EXPECT_EQ(run.reply["feedforward"], p.summary["feedforward"]);
  // A static model has no delay or dynamics to preview, but the offset is tared on the sweep.
  EXPECT_FALSE(t.preview);
  EXPECT_LT(t.tare.from, p.excitation.size());
  EXPECT_EQ(run.header["model"], hc::to_json(model));
}

// A rate-dependent model's feedforward is planned over the reference before the run, as the
// run's preparation (the reply says it is being planned): the plan the compensator then plays,
// for the targets the loop will give it, meets them on the model as the result's summary says
// and better than the previewed inverse, with progress on the way; a reference too long to plan
// keeps the previewed inverse, prepares nothing and says why.
TEST(TrackProgram, ARateDependentModelsFeedforwardIsPlannedOverTheReference) {
  hd::BenchSettings s = settings();
  s.loop.rate_hz = 10000.0;
  hc::PiParameters play;
  std::vector<double> c;
  for (int i = 0; i < 10; ++i) {
    play.thresholds.push_back(7.5 * i);
    play.weights.push_back(i == 0 ? 0.18 : 0.02);
    c.push_back(2e-6 * i);
  }
  play.offset = -6.75;
  hc::ActuatorModel rpi(std::make_unique<hc::RateDependentPiModel>(
      hc::RateDependentPiParameters{
          {play, hc::DeadZoneParameters{{-15.0, 0.0, 12.0}, {0.15, 1.0, 0.4}}, 21.0},
          c,
          1e4,
          0.0,
          0.0},
      1e-4));
  rpi.input_min = 0.0;
  rpi.input_max = 150.0;
  const hc::ModelFile model{std::move(rpi), json::object()};
  const hdd::RunContext ctx{s, &model, 0.0};
  const hdd::BuiltRun run =
      track({{"reference", "sine"}, {"frequency_hz", 10.0}, {"periods", 3}}, ctx);
  hd::RunProgram& p = *run.program;
  ASSERT_NE(hd::track_drive(p), nullptr);
  hd::TrackProgram& t = hd::track_drive(p)->program;
  const std::uint64_t prefix = p.excitation.size(), samples = p.total_samples - prefix;
  EXPECT_EQ(run.reply["feedforward"]["planned"], json({{"samples", samples}, {"planning", true}}));
  ASSERT_TRUE(run.preparation.work);
  EXPECT_EQ(run.preparation.stage, "planning the feedforward");
  std::vector<double> fractions;
  run.preparation.work(p, [&](double f) { fractions.push_back(f); });
  ASSERT_FALSE(fractions.empty());
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  const json& planned = p.summary["feedforward"]["planned"];
  ASSERT_EQ(planned["samples"], samples) << p.summary.dump(2);
  EXPECT_LT(planned["model_rms_um"].get<double>(),
            0.7 * planned["previewed_model_rms_um"].get<double>());
  // The compensator's drive through the model, for the loop's own targets.
  hc::ActuatorModel m = model.model;
  m.configure(1e-4);
  m.reset(0.0);
  for (const double u : p.excitation) m.step(u);
  double sum2 = 0.0;
  for (std::uint64_t k = 0; k < samples; ++k) {
    const double target = t.feedforward_target(static_cast<double>(k) * 1e-4, 0.0);
    const double e = m.step(t.compensator->step(target, std::nan(""), target).u) - target;
    sum2 += e * e;
  }
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(samples)), planned["model_rms_um"], 1e-9);

  // 1 Hz: the previewed inverse already meets the targets on the model; it is kept, and the
  // result says why.
  hdd::BuiltRun one_hz = track({{"reference", "sine"}, {"frequency_hz", 1.0}, {"periods", 2}}, ctx);
  ASSERT_TRUE(one_hz.preparation.work);
  one_hz.preparation.work(*one_hz.program, {});
  const json& kept = one_hz.program->summary["feedforward"]["planned"];
  EXPECT_EQ(kept["samples"], 0) << kept.dump();
  EXPECT_THAT(kept["why_not"].get<std::string>(), HasSubstr("already meets the targets"));

  // Longer than the planner takes (10 s): a periodic reference is planned over its first four
  // periods, which repeat from the third on; one whose four periods are too long, or one that
  // does not repeat, keeps the previewed inverse.
  hdd::BuiltRun ten_periods =
      track({{"reference", "sine"}, {"frequency_hz", 10.0}, {"periods", 100}}, ctx);
  ASSERT_TRUE(ten_periods.preparation.work);
  ten_periods.preparation.work(*ten_periods.program, {});
  const json& in_part = ten_periods.program->summary["feedforward"]["planned"];
  EXPECT_EQ(in_part["samples"], 100000) << in_part.dump();
  EXPECT_EQ(in_part["optimised_samples"], 4001) << in_part.dump();
  for (const json& request :
       {json{{"reference", "sine"}, {"frequency_hz", 0.2}, {"periods", 2}},
        json{{"reference", "chirp"}, {"frequency_hz", 1.0}, {"duration_s", 10.0}}}) {
    const hdd::BuiltRun slow = track(request, ctx);
    const json& not_planned = slow.reply["feedforward"]["planned"];
    EXPECT_FALSE(slow.preparation.work) << request;
    EXPECT_EQ(not_planned["samples"], 0) << request;
    EXPECT_THAT(not_planned["why_not"].get<std::string>(),
                HasSubstr("is longer than the planner takes for this model"));
  }
}

namespace {

// The bench's frequency responses of a stage of gain 0.3 um/V with a 120 Hz mode (zeta 0.05),
// measured as frf measures them at 1 kHz (noise-free).
hc::StageResponses stage_responses(const hd::BenchSettings& s) {
  const hdd::RunContext ctx{s, nullptr, 0.0};
  const auto o = hdd::response_options(ctx);
  const auto x = hystbench::sim::make_frequency_response_excitation(o);
  hc::SecondOrderDynamics mode({120.0, 0.05}, 1.0 / s.loop.rate_hz);
  hd::RunProgram run;
  run.run_id = "frf-test";
  run.records.u = x.u;
  for (const double u : x.u) run.records.y.push_back(0.3 * mode.step(u));
  run.records.count = x.u.size();
  return hdd::measure_responses(run, o);
}

}  // namespace

TEST(TrackProgram, TheFeedbackIsDesignedOnTheMeasuredResponsesUnlessGainsAreGiven) {
  const hd::BenchSettings s = settings();
  EXPECT_THAT(refusal({{"compensator", "pid"}}, hdd::RunContext{s, nullptr, 0.0}),
              StartsWith("no_frequency_response: "));
  const hc::StageResponses responses = stage_responses(s);
  hdd::RunContext ctx{s, nullptr, 0.0};
  ctx.responses = &responses;
  const hdd::BuiltRun designed = track({{"compensator", "pid"}}, ctx);
  const json& f = designed.reply["feedback"];
  EXPECT_EQ(f["gains"], "designed");
  EXPECT_EQ(f["responses_from"], "frf-test");
  EXPECT_TRUE(f["meets_targets"].get<bool>());
  EXPECT_EQ(f["margins"].size(), responses.responses.size());
  for (const json& m : f["margins"]) EXPECT_GE(m["gain_margin_db"].get<double>(), 6.0);
  EXPECT_GT(f["bandwidth_hz"].get<double>(), 0.0);
  EXPECT_FALSE(f["limited_by"].get<std::string>().empty());
  // The feedback starts with the reference, after the open-loop prefix.
  EXPECT_EQ(designed.program->feedback_from, designed.program->excitation.size());
  // Gains given: taken at the drive's mean slope (45 um over 150 V), checked, stated.
  const hdd::BuiltRun given = track({{"compensator", "pid"}, {"ki", 100.0}}, ctx);
  EXPECT_EQ(given.reply["feedback"]["gains"], "request");
  EXPECT_DOUBLE_EQ(given.reply["feedback"]["law"]["ki"].get<double>(), 100.0 * 45.0 / 150.0);
  EXPECT_FALSE(given.reply["feedback"]["forced"].get<bool>());
  EXPECT_TRUE(track({{"compensator", "none"}}, ctx).reply["feedback"].is_null());
}

TEST(TrackProgram, GainsThatBreakTheMarginsAreRefusedNamingThemUnlessForced) {
  const hd::BenchSettings s = settings();
  const hc::StageResponses responses = stage_responses(s);
  hdd::RunContext ctx{s, nullptr, 0.0};
  ctx.responses = &responses;
  // Integral alone at a 100 Hz crossover: past the 120 Hz mode's limit, unstable.
  const json fast = {{"compensator", "pid"}, {"ki", 2.0 * M_PI * 100.0 / 0.3}};
  const std::string why = refusal(fast, ctx);
  EXPECT_THAT(why, StartsWith("unsafe_gains: these gains break the loop's targets"));
  EXPECT_THAT(why, HasSubstr("UNSTABLE"));
  EXPECT_THAT(why, HasSubstr("gain margin"));
  json forced = fast;
  forced["force_gains"] = true;
  const hdd::BuiltRun run = track(forced, ctx);
  EXPECT_TRUE(run.reply["feedback"]["forced"].get<bool>());
  EXPECT_FALSE(run.reply["feedback"]["broken"].get<std::string>().empty());
}

TEST(TrackProgram, ResponsesMeasuredAtAnotherLoopRateAreRefused) {
  hd::BenchSettings other = settings();
  other.loop.rate_hz = 2000.0;
  const hc::StageResponses responses = stage_responses(other);
  const hd::BenchSettings s = settings();
  hdd::RunContext ctx{s, nullptr, 0.0};
  ctx.responses = &responses;
  EXPECT_THAT(refusal({{"compensator", "pid"}}, ctx), StartsWith("stale_frequency_response: "));
}

TEST(TrackProgram, RefusalsNameTheCause) {
  hd::BenchSettings s = settings();
  const hdd::RunContext ctx{s, nullptr, 0.0};
  EXPECT_THAT(refusal({{"compensator", "inverse"}}, ctx), StartsWith("no_model: "));
  EXPECT_THAT(refusal({{"compensator", "magic"}}, ctx),
              StartsWith("bad_params: compensator: unknown 'magic'"));
  EXPECT_THAT(refusal({{"min_um", -100.0}, {"max_um", 10.0}}, ctx),
              StartsWith("out_of_range: reference [-100"));
  // A twentieth of the loop rate is the fastest reference.
  EXPECT_THAT(refusal({{"frequency_hz", 60.0}}, ctx),
              StartsWith("bad_params: frequency_hz: 60.000000 is out of range"));
  hd::BenchSettings unbounded = settings();
  unbounded.y_max = 0.0;
  EXPECT_THAT(refusal(json::object(), hdd::RunContext{unbounded, nullptr, 0.0}),
              StartsWith("no_range: "));
}

TEST(TrackProgram, AnUploadedReferenceIsApproachedFromTheBottomOfTheRange) {
  const hd::BenchSettings s = settings();
  const hdd::RunContext ctx{s, nullptr, 0.0};
  hd::Upload up;
  up.name = "r";
  up.rate_hz = 100.0;
  up.values = {20.0, 21.0, 22.0, 23.0, 24.0, 25.0};
  up.samples = up.values.size();
  const hdd::BuiltRun run = track({{"reference_upload", "r"}, {"approach_s", 0.5}}, ctx, &up);
  const hd::RunProgram& p = *run.program;
  ASSERT_NE(hd::track_drive(p), nullptr);
  const hd::TrackProgram& t = hd::track_drive(p)->program;
  EXPECT_NEAR(t.reference->value(0.0), 0.0, 1e-9);  // where the sweep leaves the output
  EXPECT_EQ(run.reply["reference"]["kind"], "upload");
  EXPECT_EQ(p.metrics_from, p.excitation.size() + 500);  // the approach is not scored
  up.values[3] = 50.0;                                   // beyond the 0..45 um range
  try {
    (void)track({{"reference_upload", "r"}}, ctx, &up);
    ADD_FAILURE() << "a reference beyond the range was accepted";
  } catch (const common::CommandError& e) {
    EXPECT_EQ(e.code(), "out_of_range");
    EXPECT_EQ(e.detail()["sample"], 3);
  }
}

TEST(IdentifyProgram, TheRequestOverTheDefaultsWithinTheLimits) {
  hd::BenchSettings s = settings();
  const json params = {{"model", "cpi"}, {"u_max", 120.0}};
  const hdd::RequestParams request(params, hdd::find_command("identify", params).params);
  const hdd::IdentifyRequest r = hdd::parse_identify_request(request, s);
  EXPECT_EQ(r.model, "cpi");
  EXPECT_EQ(r.operators, s.identify.operators);
  EXPECT_DOUBLE_EQ(r.u_min, 0.0);
  EXPECT_DOUBLE_EQ(r.u_max, 120.0);
  const auto refused = [&](const json& bad) {
    try {
      const hdd::RequestParams q(bad, hdd::find_command("identify", bad).params);
      (void)hdd::parse_identify_request(q, s);
    } catch (const common::CommandError& e) {
      return e.code() + ": " + e.what();
    }
    return std::string("ok");
  };
  EXPECT_EQ(refused({{"model", "spline"}}),
            "bad_params: model: unknown 'spline' (pi, mpi, cpi, rpi, preisach, auto)");
  EXPECT_THAT(refused({{"u_max", 200.0}}),
              StartsWith("bad_params: u_max: 200.000000 is out of range"));
  EXPECT_EQ(refused({{"u_min", 100.0}, {"u_max", 50.0}}),
            "bad_params: u_max must be greater than u_min");
}

TEST(IdentifyProgram, RampsFromThePresentOutputAndRecordsEverySampleForTheFit) {
  const hd::BenchSettings s = settings();
  const hdd::RunContext ctx{s, nullptr, 75.0};
  const hdd::IdentifyRequest r{"mpi", 0, -1, 0.0, 150.0};
  const hdd::BuiltRun run = hdd::make_identify_program(r, ctx);
  const hd::RunProgram& p = *run.program;
  EXPECT_EQ(p.kind, hd::RunKind::kIdentify);
  EXPECT_EQ(p.total_samples, p.excitation.size());
  EXPECT_EQ(p.metrics_from, 0u);
  EXPECT_EQ(p.records.capacity, p.total_samples);
  EXPECT_EQ(p.records.response.size(), p.records.capacity);
  // 0.1 s of ramp from 75 V, then the excitation.
  EXPECT_NEAR(p.excitation.front(), 75.0, 2.0);
  EXPECT_EQ(run.fit["model"], "mpi");
  EXPECT_GT(run.fit["skip_samples"].get<std::size_t>(), 100u);
  EXPECT_EQ(run.header["run"]["segments"].front()["begin"], 100);
  // The result's model error is the predictor's over the run, not the identified model's: it
  // says so, with and without a model before.
  EXPECT_EQ(p.summary["y_model"], "linear map of limits.y_min..y_max, stepped with u");
  const hc::ModelFile before = pi_model();
  const hdd::BuiltRun again = hdd::make_identify_program(r, hdd::RunContext{s, &before, 75.0});
  EXPECT_EQ(again.program->summary["y_model"], "the model active before this identification");
}

// A rate law is identified only up to the rates its record holds: rpi and auto add cycles at
// 20 Hz (a 19 Hz sine's rates over 80 % of the range); a rate-free family goes without them.
TEST(IdentifyProgram, ARateDependentFamilyGetsTheFastRateSegment) {
  const hd::BenchSettings s = settings();  // 1 kHz: 20 Hz has 50 samples per cycle
  const hdd::RunContext ctx{s, nullptr, 0.0};
  const auto names = [&](const std::string& model) {
    const hdd::BuiltRun run =
        hdd::make_identify_program(hdd::IdentifyRequest{model, 0, -1, 0.0, 150.0}, ctx);
    std::vector<std::string> out;
    for (const json& seg : run.header["run"]["segments"]) out.push_back(seg["name"]);
    return out;
  };
  EXPECT_THAT(names("rpi"), ::testing::Contains("rate_20hz"));
  EXPECT_THAT(names("auto"), ::testing::Contains("rate_20hz"));
  EXPECT_THAT(names("mpi"), ::testing::Not(::testing::Contains("rate_20hz")));
  EXPECT_THAT(names("mpi"), ::testing::Contains("rate_10hz"));
}

TEST(ExciteProgram, ADriveIsRampedToWithinTheSlewLimitAndRecordedFromItsStart) {
  hd::BenchSettings s = settings();
  s.loop.limits.slew_v_per_s = 100.0;
  const hdd::RunContext ctx{s, nullptr, 0.0};
  hd::Upload up;
  up.kind = hd::UploadKind::kDrive;
  up.rate_hz = 1000.0;
  for (int k = 0; k < 200; ++k) up.values.push_back(50.0 + 0.01 * k);
  up.samples = up.values.size();
  const hdd::BuiltRun run = hdd::make_excite_program(up, ctx);
  const hd::RunProgram& p = *run.program;
  // 50 V at half the slew limit: 1 s of ramp.
  EXPECT_EQ(run.reply["ramp_samples"], 1000);
  EXPECT_EQ(run.reply["drive_samples"], 200);
  EXPECT_EQ(p.metrics_from, 1000u);
  EXPECT_EQ(p.total_samples, 1200u);
  EXPECT_DOUBLE_EQ(p.excitation[999], 50.0);
  up.values[10] = 200.0;
  try {
    (void)hdd::make_excite_program(up, ctx);
    ADD_FAILURE() << "a drive beyond the output range was accepted";
  } catch (const common::CommandError& e) {
    EXPECT_EQ(e.code(), "out_of_range");
    EXPECT_THAT(e.what(), HasSubstr("sample 10"));
  }
}

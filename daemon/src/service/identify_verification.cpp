// identify's verification on the loop: each candidate (and the extension) plays one tracking
// segment through its inverse, a standard triangle or a sine, one after the other; each
// segment's errors go to its candidate (the identify coordinator on the supervisor thread;
// identify_coordinator.hpp).
#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <span>
#include <string>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "hystbench/compensation/tracking_metrics.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "runs/details/response_program.hpp"
#include "service/details/identify_coordinator.hpp"
#include "service/details/identify_session.hpp"
#include "service/details/run_log.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

// The precondition sweep of a short segment [s]: 150 V in 50 ms, still slow against a mode of a
// few hundred Hz and beyond.
constexpr double kShortPreconditionS = 0.1;

}  // namespace

bool details::IdentifyCoordinator::verify_next_candidate() {
  IdentifySession& s = *session_;
  const auto& lim = bench_.settings.loop.limits;
  while (s.next < s.jobs.size()) {
    const VerificationJob job = s.jobs[s.next];
    IdentifyCandidate& c = s.candidates[job.candidate];
    const bool sine = job.sine_hz > 0.0;
    json& slot = sine ? c.sines[job.sine_hz] : c.verification;
    std::unique_ptr<RunProgram> p;
    VerificationSpec spec;
    if (sine) {
      spec.reference = VerificationSpec::Reference::kSine;
      spec.frequency_hz = job.sine_hz;
      spec.periods = 20.0;
    }
    try {
      spec.precondition_s = job.short_precondition
                                ? std::min(bench_.settings.precondition_s, kShortPreconditionS)
                                : bench_.settings.precondition_s;
      spec.feedforward_bandwidth_hz = bench_.settings.feedforward_bandwidth_hz;
      spec.model_exchange_ticks =
          static_cast<std::uint64_t>(std::max(0, s.history.value("exchange_ticks", 0)));
      p = make_verification_program(c.fit.model, spec, bench_.loop.last_output(), lim, dt_);
    } catch (const std::exception& e) {
      slot = {{"end", "not_run"}, {"reason", e.what()}};
      ++s.next;
      continue;
    }
    // Its frequency in the run id to six digits ("500", "200.027"): a mode's quarter (200.027 Hz)
    // and a twentieth of the loop rate (200 Hz) are two segments, two logs.
    const std::string hz = sine ? hc::significant(job.sine_hz, 6) : "";
    const std::string sine_label = sine ? "-sine-" + hz + "hz" : "";
    p->run_id = s.result["run_id"].get<std::string>() + "-verify-" + c.label + sine_label;
    json header = {{"run",
                    {{"kind", "verify"},
                     {"identify_run", s.result["run_id"]},
                     {"reference", sine ? "sine" : "triangle"},
                     {"frequency_hz", spec.frequency_hz},
                     {"compensator", "inverse"},
                     {"precondition_samples", p->excitation.size()},
                     {"metrics_from", p->metrics_from},
                     {"rate_hz", bench_.settings.loop.rate_hz}}},
                   {"driver", bench_.settings.driver_type},
                   {"model", hc::to_json(hc::ModelFile{c.fit.model, json::object()})}};
    try {
      open_run_log(*p, header, bench_.settings);
    } catch (const common::CommandError& e) {
      slot = {{"end", "not_run"}, {"reason", e.what()}};
      s.interrupted = true;
      return false;
    }
    const std::string program_id = p->run_id;
    std::string why;
    std::lock_guard lock(bench_.mutex);
    if (!bench_.runs.submit_segment(std::move(p),
                                    "verify " + c.label + (sine ? " (" + hz + " Hz sine)" : ""),
                                    "verification_log", why)) {
      slot = {{"end", "not_run"}, {"reason", why}};
      s.interrupted = true;
      return false;
    }
    s.program_id = program_id;
    return true;
  }
  return false;
}

void details::IdentifyCoordinator::verification_finished(std::unique_ptr<RunProgram> run) {
  IdentifySession& s = *session_;
  {
    std::lock_guard lock(bench_.mutex);
    bench_.runs.finalizing("choosing the model");
  }
  const VerificationJob job = s.jobs[s.next];
  IdentifyCandidate& c = s.candidates[job.candidate];
  const SampleLogCounts counts = run->log ? run->log->close() : SampleLogCounts{};
  json v = tracking_error_json(*run);
  v["end"] = to_string(run->end);
  v["reason"] = run->end_reason;
  v["log"] = run->log ? run->log->path().string() : "";
  v["dropped"] = counts.dropped + run->counters.log_drops;
  v["clamps"] = run->counters.clamps;
  v["clock"] = run->summary.value("clock", "wall");
  if (job.sine_hz > 0.0) {
    v["reference"] = "sine";
    v["frequency_hz"] = job.sine_hz;
    const std::size_t n = std::min<std::size_t>(run->records.count, run->records.y.size());
    v["lag_samples"] = hc::output_lag_samples(std::span<const double>(run->records.yr.data(), n),
                                              std::span<const double>(run->records.y.data(), n));
    c.sines[job.sine_hz] = std::move(v);
  } else {
    c.verification = std::move(v);
  }
  ++s.next;
  s.interrupted = s.interrupted || run->end != RunEnd::kCompleted;
  if (s.interrupted || quitting()) {
    finish();
  } else {
    continue_identify();
  }
}

void details::IdentifyCoordinator::continue_identify() {
  settle_delay_trim();
  queue_delay_trim();
  queue_parts_alone();
  if (verify_next_candidate()) return;
  IdentifySession& s = *session_;
  const bool go_on = !s.interrupted && !quitting();
  if (go_on && s.extend && s.step == IdentifyStep::kVerifyingCandidates) {
    if (play_while_diagnosing()) return;
    if (extend_identified_model() && verify_next_candidate()) return;
  }
  if (go_on && !s.responses_tried) {
    s.step = IdentifyStep::kMeasuringResponses;
    if (measure_responses()) return;
  }
  finish();
}

bool details::IdentifyCoordinator::measure_responses() {
  IdentifySession& s = *session_;
  s.responses_tried = true;
  std::unique_ptr<RunProgram> p;
  sim::FrequencyResponseExcitationOptions o;
  {
    std::lock_guard lock(bench_.mutex);
    const details::RunContext ctx = hooks_.run_context();
    o = details::response_options(ctx);
    try {
      details::BuiltRun run = details::make_response_program(o, ctx);
      p = std::move(run.program);
      p->run_id = s.result["run_id"].get<std::string>() + "-frf";
      open_run_log(*p, run.header, bench_.settings);
    } catch (const std::exception& e) {
      s.responses_result = {{"error", e.what()}};
      return false;
    }
  }
  const std::string program_id = p->run_id;
  std::string why;
  std::lock_guard lock(bench_.mutex);
  if (!bench_.runs.submit_segment(std::move(p), "measuring the frequency response",
                                  "verification_log", why)) {
    s.responses_result = {{"error", why}};
    return false;
  }
  s.program_id = program_id;
  s.response_options = o;
  return true;
}

void details::IdentifyCoordinator::responses_measured(std::unique_ptr<RunProgram> run) {
  IdentifySession& s = *session_;
  {
    std::lock_guard lock(bench_.mutex);
    bench_.runs.finalizing("designing the feedback");
  }
  const sim::FrequencyResponseExcitationOptions o = *s.response_options;
  s.response_options.reset();
  const std::string log = run->log ? run->log->path().string() : "";
  if (run->log) run->log->close();
  if (run->end == RunEnd::kCompleted) {
    try {
      s.responses = details::measure_responses(*run, o);
      s.responses_result = details::responses_summary(*s.responses, nullptr);
      s.responses_result["log"] = log;
    } catch (const std::exception& e) {
      s.responses_result = {{"error", e.what()}, {"log", log}};
    }
  } else {
    s.interrupted = true;
    s.responses_result = {{"error", std::string("the run did not complete: ") + run->end_reason},
                          {"log", log}};
  }
  // Played while the diagnosis ran, the base's sines and the extension come next; played last,
  // continue_identify() finds nothing left and finishes.
  if (s.interrupted || quitting()) {
    finish();
  } else {
    continue_identify();
  }
}

}  // namespace hystbench::daemon

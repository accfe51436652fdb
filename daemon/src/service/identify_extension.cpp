// identify's extension: the record diagnosed with the best verified candidate, and what the
// diagnosis finds it misses added to that model as one more candidate, with the sines that judge
// it (the identify coordinator on the supervisor thread; identify_coordinator.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hystbench/common/step_timed_model.hpp"
#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/compensation/model_check.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "service/details/identify_coordinator.hpp"
#include "service/details/identify_session.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

// The middle sine that guards an extension: the fast one's frequency over this.
constexpr double kMidFraction = 2.5;
// The steps timed the mode or the delay off what the diagnosis fitted when the delay moved by
// this many samples or more, or the mode's frequency by this fraction.
constexpr double kRetimedDelaySamples = 0.25;
constexpr double kRetimedModeFraction = 0.02;

// The fast sine a delay or dynamics show at [Hz]: a twentieth of the loop rate, the fastest
// `track` plays.
double delay_sine_frequency(double loop_rate_hz) { return loop_rate_hz / 20.0; }

// The fast sine that judges an extension [Hz], 0 for none: a delay or dynamics show at
// delay_sine_frequency() (a quarter of a mode's frequency below it), a rate law at the identify
// record's fastest rate segment; creep and asymmetry show on the standard triangle.
double fast_frequency(const std::vector<std::string>& parts, const hc::ActuatorModel& extended,
                      double loop_rate_hz) {
  const auto has = [&](const char* p) {
    return std::find(parts.begin(), parts.end(), p) != parts.end();
  };
  double f = 0.0;
  if (has("delay") || has("dynamics")) {
    f = delay_sine_frequency(loop_rate_hz);
    if (extended.dynamics()) f = std::min(f, extended.dynamics()->natural_frequency_hz / 4.0);
  }
  if (has("rate_dependence")) f = std::max(f, rate_sine_frequency(loop_rate_hz));
  return f;
}

// The model identify tries as the extension of the model the diagnosis was given: the
// diagnosis's extended model when it names a cause. Otherwise, when the dynamics or the delay
// test is significant and carries over but the record does not show a held-out gain (its
// excitation is slow against them: on a loop whose shape the model misses, that error hides
// theirs), the given model with that resonance and delay grafted on; the fast sine on the
// bench judges what the record cannot.
struct ExtensionDraft {
  hc::ActuatorModel model;
  std::vector<std::string> parts;
  bool named = false;  ///< the diagnosis's extended model (else grafted)
};
std::optional<ExtensionDraft> extension_draft(const hc::Diagnosis& d) {
  if (d.cause != hc::Cause::kNone && !d.extended_parts.empty()) {
    return ExtensionDraft{d.extended, d.extended_parts, true};
  }
  const auto usable = [&d](hc::Cause cause) {
    const hc::CandidateReport* c = d.candidate(cause);
    return c != nullptr && c->significant && c->carries_over ? c : nullptr;
  };
  const hc::CandidateReport* dynamics = usable(hc::Cause::kDynamics);
  const hc::CandidateReport* delay = usable(hc::Cause::kDelay);
  if (dynamics == nullptr && delay == nullptr) return std::nullopt;
  ExtensionDraft draft{d.baseline, {}, false};
  if (dynamics != nullptr && dynamics->model.dynamics()) {
    draft.model.set_dynamics(dynamics->model.dynamics());
    draft.parts.emplace_back("dynamics");
  }
  if (delay != nullptr) {
    draft.model.set_delay(delay->model.delay_s());
    draft.parts.emplace_back("delay");
  }
  if (draft.parts.empty()) return std::nullopt;
  return draft;
}

// Where an extension's parts come from (the result's extension.from).
const char* extension_origin(bool named) {
  return named ? "the diagnosis's extended model (named causes)"
               : "significant tests below the naming gain, grafted on the model for the bench to "
                 "judge";
}

// What the diagnosis of identify's record found: each part added with its held-out gain alone
// on the diagnosis's blocks (the given model's held-out rms / with the part), and the verdict.
json extension_json(const hc::Diagnosis& d, const std::vector<std::string>& added) {
  json parts = json::array();
  for (const std::string& name : added) {
    const auto cause = hc::cause_from_string(name);
    const hc::CandidateReport* c = cause ? d.candidate(*cause) : nullptr;
    parts.push_back({{"cause", name},
                     {"heldout_gain", c != nullptr ? c->gain : 1.0},
                     {"extension", c != nullptr ? c->extension : std::string()}});
  }
  return {{"parts", parts}, {"verdict", d.verdict}};
}

// How identify diagnoses its record with `baseline`.
hc::DiagnosisOptions diagnosis_options(hc::ActuatorModel baseline, bool swap_operator,
                                       const details::DiagnosisAhead::Controls& controls) {
  hc::DiagnosisOptions options;
  options.baseline = std::move(baseline);
  options.units = {"V", "um"};
  options.progress = controls.progress;
  options.cancelled = controls.cancelled;
  options.threads = controls.threads;
  options.swap_operator = swap_operator;
  return options;
}

// Whether the steps timed the mode or the delay off what the diagnosis fitted (timing: the
// time_on_steps() result).
bool timed_off(const json& timing) {
  if (timing.is_null() || !timing.contains("from_record")) return false;
  const json& fitted = timing["from_record"];
  const double f = timing.value("natural_frequency_hz", 0.0);
  const double f0 = fitted.value("natural_frequency_hz", 0.0);
  return std::abs(timing.value("delay_samples", 0.0) - fitted.value("delay_samples", 0.0)) >=
             kRetimedDelaySamples ||
         (f0 > 0.0 && std::abs(f - f0) >= kRetimedModeFraction * f0);
}

// A mode or a delay fitted off the stage's leaves an error on every move that can hide what lies
// beyond them (the loop's shape, creep: named on the same record once the mode and the delay are
// the steps'; BenchFeedforwardTest.DiagnosedAgainOnTheTimedModeTheRecordNamesTheShapeAndCreep).
// Where the steps timed them off and the draft does not swap the operator (where it does, the
// shape was not hidden, and a second diagnosis of a 10 kHz record costs seconds: the timing
// section of design/identify.md), the record is diagnosed again with the timed draft as its
// baseline; the causes it names beyond the draft's parts join them, the draft becomes its
// extended model, and the diagnosis is returned (else empty). `extension` gets `after_timing`
// and the new parts.
std::optional<hc::Diagnosis> diagnose_after_timing(
    ExtensionDraft& draft, const json& timing, std::span<const double> t, std::span<const double> u,
    std::span<const double> y, bool swap_operator,
    const details::DiagnosisAhead::Progress& progress, json& extension) {
  const auto has = [&draft](const std::string& part) {
    return std::find(draft.parts.begin(), draft.parts.end(), part) != draft.parts.end();
  };
  if (!timed_off(timing) || has("loop_shape")) return std::nullopt;
  hc::Diagnosis d =
      hc::diagnose(t, u, y, diagnosis_options(draft.model, swap_operator, {progress, nullptr, 0}));
  std::vector<std::string> added;
  if (d.cause != hc::Cause::kNone) {
    for (const std::string& part : d.extended_parts) {
      if (!has(part)) added.push_back(part);
    }
  }
  extension["after_timing"] = {{"named", added}, {"verdict", d.verdict}};
  if (added.empty()) return std::nullopt;
  const json named = extension_json(d, added);
  for (const json& part : named["parts"]) extension["parts"].push_back(part);
  // The mode and the delay stay the steps' (the diagnosis may fit its own again beside the rest).
  hc::ActuatorModel extended = d.extended;
  extended.set_dynamics(draft.model.dynamics());
  extended.set_delay(draft.model.delay_s());
  draft.model = std::move(extended);
  draft.parts.insert(draft.parts.end(), added.begin(), added.end());
  draft.named = true;
  return d;
}

// identify's record at the loop rate, and how the candidates are scored on it.
struct ScoredRecord {
  std::span<const double> t, u, y;
  double heldout_fraction = 0.0;
  std::size_t unscored = 0;  ///< samples simulated but not scored
};

// The extension as a candidate: the draft's model with the exchange latency back in its delay,
// the base's units and input range, configured for the loop and scored as the candidates are
// (at the loop rate: the dynamics need it). `extension` gets both held-out errors and the gain.
IdentifyCandidate extended_candidate(const IdentifyCandidate& base, hc::ActuatorModel model,
                                     double exchange_s, double dt, const ScoredRecord& record,
                                     json& extension) {
  IdentifyCandidate ext{base.fit, json(), base.label, {}, std::nullopt};
  model.set_delay(model.delay_s() + exchange_s);
  model.units = base.fit.model.units;
  model.input_min = base.fit.model.input_min;
  model.input_max = base.fit.model.input_max;
  model.configure(dt);
  ext.fit.model = std::move(model);
  if (ext.fit.model.hysteresis().kind() == hc::ModelKind::kPreisach) {
    // The operator swapped for a plane: its cells per side and its output map's dead zones.
    const auto& plane = dynamic_cast<const hc::PreisachModel&>(ext.fit.model.hysteresis());
    ext.fit.operators = static_cast<int>(plane.parameters().cells);
    ext.fit.dead_zones = static_cast<int>(plane.parameters().output_map.thresholds.size() / 2);
  }
  ext.fit.delay_samples = static_cast<int>(std::lround(ext.fit.model.delay_s() / dt));
  const hc::ModelScore score = hc::score_model(ext.fit.model, record.t, record.u, record.y,
                                               record.heldout_fraction, record.unscored);
  ext.fit.fit = score.fit;
  ext.fit.heldout = score.heldout;
  hc::ActuatorModel given = base.fit.model;
  given.configure(dt);
  const double before = hc::score_model(std::move(given), record.t, record.u, record.y,
                                        record.heldout_fraction, record.unscored)
                            .heldout.rmse;
  extension["heldout_rms_um"] = {{"model", before}, {"extended", score.heldout.rmse}};
  extension["heldout_gain"] = score.heldout.rmse > 0.0 ? before / score.heldout.rmse : 1.0;
  return ext;
}

// What the extension adds: the diagnosis's extended model's description, or the parts grafted.
std::string extension_added(const hc::Diagnosis& d, bool named, const json& parts) {
  if (named) return d.extended_description;
  std::string added = "grafted";
  for (const json& part : parts) added += "; " + part["extension"].get<std::string>();
  return added;
}

// The candidate the extension extends: the best verified one, a rate law judged against its
// rate-free self on the rate sine.
std::size_t extension_base(const std::vector<IdentifyCandidate>& candidates,
                           std::optional<std::size_t> rate_free, double rate_sine_hz) {
  return best_verified(candidates,
                       left_out_of_choice(candidates, std::nullopt, rate_free, rate_sine_hz));
}

// The times of identify's record at the loop rate [s].
std::vector<double> record_times(std::size_t n, double dt) {
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) * dt;
  return t;
}

// The extended candidate's verification: its triangle, and where a fast sine judges it, that
// sine and a middle one (what the extension gives up below the fast one) for it and its base.
void queue_extension_verification(std::vector<VerificationJob>& jobs,
                                  const std::vector<IdentifyCandidate>& candidates,
                                  std::size_t base, std::size_t extended, double fast_hz,
                                  double mid_hz) {
  jobs.push_back({extended, false});
  if (!(fast_hz > 0.0)) return;
  for (const double hz : {fast_hz, mid_hz}) {
    if (!candidates[base].sines.contains(hz)) jobs.push_back({base, hz});
    jobs.push_back({extended, hz});
  }
}

}  // namespace

// A model whose inverse does not exist over its input range is never played nor written, unless
// it misses no more than its base, which identify keeps without it: refusing it would keep the
// same fault and lose what it adds.
bool passes_check(const hc::ActuatorModel& model, const hc::ModelCheck& own, double dt_s,
                  json& extension) {
  const hc::ModelCheck check = hc::check_model(model, dt_s);
  extension["check"] = to_json(check);
  if (check.passed) return true;
  if (check.part == "inverse") {
    if (!own.passed && own.part == "inverse" &&
        check.inverse_rms_percent <= own.inverse_rms_percent &&
        check.inverse_max_percent <= own.inverse_max_percent) {
      extension["check"]["base"] = to_json(own);
      extension["check"]["accepted"] =
          "its inverse misses no more than its base's, which identify keeps without it";
      return true;
    }
  }
  extension["adopted"] = false;
  extension["why"] = "its check failed: " + check.reason;
  return false;
}

details::DiagnosisAhead::Task identify_diagnosis(const std::vector<IdentifyCandidate>& candidates,
                                                 double exchange_s, std::span<const double> u,
                                                 std::span<const double> y, double dt,
                                                 bool swap_operator) {
  std::vector<hc::ActuatorModel> baselines;
  baselines.reserve(candidates.size());
  for (const IdentifyCandidate& c : candidates) {
    baselines.push_back(c.fit.model);
    baselines.back().set_delay(std::max(0.0, baselines.back().delay_s() - exchange_s));
  }
  return [baselines = std::move(baselines), t = record_times(u.size(), dt),
          u = std::vector<double>(u.begin(), u.end()), y = std::vector<double>(y.begin(), y.end()),
          swap_operator](std::size_t candidate, const details::DiagnosisAhead::Controls& controls) {
    return hc::diagnose(t, u, y,
                        diagnosis_options(baselines.at(candidate), swap_operator, controls));
  };
}

bool details::IdentifyCoordinator::play_while_diagnosing() {
  IdentifySession& s = *session_;
  if (!s.ahead) return false;
  const std::size_t base = extension_base(s.candidates, s.rate_free, s.rate_sine_hz);
  s.ahead->focus(base);
  // Played whether or not the diagnosis is ready, so that the bench's history before the
  // extension's own segments is the same however long the diagnosis takes (on the simulated
  // clock, the outcome of a run would otherwise depend on the machine's load). First the frf run,
  // which does not depend on the model chosen (it would otherwise play last, after the
  // extension); then the base's sines, the extension's yardstick, next to the extension's own.
  if (!s.responses_tried && measure_responses()) return true;
  const double fast = delay_sine_frequency(bench_.settings.loop.rate_hz);
  for (const double hz : {fast, fast / kMidFraction}) {
    if (s.candidates[base].sines.contains(hz)) continue;
    s.jobs.push_back({base, hz});
    s.sines_while_diagnosing.push_back(hz);
    return verify_next_candidate();
  }
  return false;
}

details::DiagnosisAhead::Progress details::IdentifyCoordinator::extension_progress() const {
  return [this, run_id = session_->result["run_id"].get<std::string>()](double f,
                                                                        const std::string& what) {
    emit({{"event", "fit.progress"},
          {"run_id", run_id},
          {"fraction", f},
          {"stage", "extension: " + what}});
  };
}

details::DiagnosisAhead::Taken details::IdentifyCoordinator::take_diagnosis(
    double exchange_s, const details::DiagnosisAhead::Progress& progress) {
  IdentifySession& s = *session_;
  // The worker started with the session's extension; without it, the diagnosis runs here.
  details::DiagnosisAhead::Taken taken =
      s.ahead ? s.ahead->take(s.base, progress)
              : details::DiagnosisAhead::Taken{
                    identify_diagnosis(s.candidates, exchange_s, s.u, s.y, dt_, s.swap_operator)(
                        s.base, {progress, nullptr, 0}),
                    "after the verification"};
  s.ahead.reset();
  return taken;
}

bool details::IdentifyCoordinator::extend_identified_model() {
  IdentifySession& s = *session_;
  s.step = IdentifyStep::kExtending;
  s.base = extension_base(s.candidates, s.rate_free, s.rate_sine_hz);
  const IdentifyCandidate& base = s.candidates[s.base];
  {
    std::lock_guard lock(bench_.mutex);
    bench_.runs.set_stage("diagnosing the record with " + base.label);
  }
  const auto seconds = [started = std::chrono::steady_clock::now()] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
  // The extended model gets the driver's exchange latency back in its delay.
  const double exchange_s = s.history.value("exchange_ticks", 0) * dt_;
  try {
    const std::vector<double> t = record_times(s.u.size(), dt_);
    const details::DiagnosisAhead::Progress progress = extension_progress();
    const details::DiagnosisAhead::Taken taken = take_diagnosis(exchange_s, progress);
    const hc::Diagnosis& d = taken.diagnosis;
    std::optional<ExtensionDraft> draft = extension_draft(d);
    s.extension = extension_json(d, draft ? draft->parts : std::vector<std::string>{});
    s.extension["diagnosis_ran"] = taken.how;
    s.extension["sines_while_diagnosing_hz"] = s.sines_while_diagnosing;
    s.extension["diagnosis_s"] = seconds();
    if (!draft) {
      s.extension.update(
          {{"adopted", false}, {"why", "the diagnosis finds nothing the model misses"}});
      return false;
    }
    s.extension["from"] = extension_origin(draft->named);
    const json timing = common::time_on_steps(draft->model, s.u, s.y, dt_, exchange_s);
    if (!timing.is_null()) s.extension["timing"] = timing;
    const std::optional<hc::Diagnosis> after =
        diagnose_after_timing(*draft, timing, t, s.u, s.y, s.swap_operator, progress, s.extension);
    if (after) s.extension["from"] = extension_origin(true);
    const ScoredRecord record{t, s.u, s.y, bench_.settings.identify.heldout_fraction, s.unscored};
    IdentifyCandidate ext =
        extended_candidate(base, std::move(draft->model), exchange_s, dt_, record, s.extension);
    if (!passes_check(ext.fit.model, check_of(base, dt_), dt_, s.extension)) {
      // A slow part that breaks the inverse (a rate law's weights) need not take a mode or a
      // delay that passes with it: the base with the fast parts alone is the extension then.
      std::optional<IdentifyCandidate> fast = fast_parts_instead(base, ext, dt_, s.extension);
      if (!fast) return false;
      ext = std::move(*fast);
      s.extension_band = PartsBand::kFast;
    }
    const PartsByBand bands = split_parts(s.extension["parts"]);
    std::string added =
        s.extension_band
            ? parts_alone_text(bands, PartsBand::kFast) + " (the whole extension failed its check)"
            : extension_added(after ? *after : d, draft->named, s.extension["parts"]);
    if (!timing.is_null()) added += "; " + common::timing_text(timing);
    ext.fit.notes.push_back("extended by the diagnosis of its record: " + added);
    s.extension["description"] = added;
    ext.label += s.extension_band ? "-fast-parts" : "-extended";
    s.candidates.push_back(std::move(ext));
    s.extended = s.candidates.size() - 1;
    s.fast_hz = fast_frequency(s.extension_band ? bands.fast : draft->parts,
                               s.candidates.back().fit.model, bench_.settings.loop.rate_hz);
    s.trim_delay = s.fast_hz > 0.0 && !bands.fast.empty();
    if (s.fast_hz > 0.0) s.mid_hz = s.fast_hz / kMidFraction;
    queue_extension_verification(s.jobs, s.candidates, s.base, *s.extended, s.fast_hz, s.mid_hz);
    return true;
  } catch (const std::exception& e) {
    s.extension = {{"adopted", false},
                   {"why", std::string("the diagnosis failed: ") + e.what()},
                   {"diagnosis_s", seconds()}};
    return false;
  }
}

}  // namespace hystbench::daemon

// identify's second half: candidates fitted per family, each verified on the loop by one
// tracking segment through its inverse, the model chosen and reported (Bench members, run on
// the supervisor thread; see identify_session.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>

#include "hystbench/common/fit_families.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/daemon/runs/identification_fit.hpp"
#include "hystbench/daemon/runs/inverse_track_program.hpp"
#include "runs/details/identify_session.hpp"
#include "runs/details/run_result.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

std::string type_name(const hc::FitResult& f) {
  return std::string(hc::to_string(f.model.hysteresis().kind()));
}

// Verified max errors within this factor of each other are one figure: two triangles on the
// same model differ by about 1 % with the bench's history (creep, noise) before them.
constexpr double kVerifiedTie = 1.03;

// Verified max error [% of the reference span]; +inf when not verified to the end.
double verified_max(const IdentifyCandidate& c) {
  if (c.verification.is_null() || c.verification.value("end", "") != "completed" ||
      !c.verification.contains("max_error_percent")) {
    return INFINITY;
  }
  return c.verification["max_error_percent"].get<double>();
}

// v[key], or null when v is not an object holding it.
json field(const json& v, const char* key) {
  return v.is_object() && v.contains(key) ? v[key] : json();
}

json candidate_summary(const IdentifyCandidate& c) {
  json j = {{"type", type_name(c.fit)},          {"label", c.label},
            {"operators", c.fit.operators},      {"dead_zones", c.fit.dead_zones},
            {"heldout", to_json(c.fit.heldout)}, {"verification", c.verification}};
  if (!c.sines.empty()) {
    j["sine_verifications"] = json::array();
    for (const auto& [hz, v] : c.sines) j["sine_verifications"].push_back(v);
  }
  return j;
}

// Verified rms error of the sine at hz [% of the reference span]; +inf when it did not complete.
double sine_rms(const IdentifyCandidate& c, double hz) {
  const auto it = c.sines.find(hz);
  if (it == c.sines.end()) return INFINITY;
  const json& v = it->second;
  if (v.value("end", "") != "completed" || !v.contains("rms_error_percent")) return INFINITY;
  return v["rms_error_percent"].get<double>();
}

// v[key] of the sine at hz, or null when it did not run.
json sine_field(const IdentifyCandidate& c, double hz, const char* key) {
  const auto it = c.sines.find(hz);
  return it != c.sines.end() && it->second.contains(key) ? it->second[key] : json();
}

// The sine a rate law is judged on [Hz]: the fastest the rate bench tracks, at most a twentieth
// of the loop rate.
double rate_sine_frequency(double loop_rate_hz) { return std::min(20.0, loop_rate_hz / 20.0); }

// The fast sine that judges an extension [Hz], 0 for none: a delay or dynamics show at a
// twentieth of the loop rate (the fastest `track` plays; a quarter of a mode's frequency below
// it), a rate law at the identify record's fastest rate segment; creep and asymmetry show on the
// standard triangle.
double fast_frequency(const std::vector<std::string>& parts, const hc::ActuatorModel& extended,
                      double loop_rate_hz) {
  const auto has = [&](const char* p) {
    return std::find(parts.begin(), parts.end(), p) != parts.end();
  };
  double f = 0.0;
  if (has("delay") || has("dynamics")) {
    f = loop_rate_hz / 20.0;
    if (extended.dynamics()) f = std::min(f, extended.dynamics()->natural_frequency_hz / 4.0);
  }
  if (has("rate_dependence")) f = std::max(f, rate_sine_frequency(loop_rate_hz));
  return f;
}

// Verified rms error of the standard triangle [% of the reference span]; +inf when not verified.
double triangle_rms(const IdentifyCandidate& c) {
  return std::isfinite(verified_max(c)) ? c.verification.value("rms_error_percent", INFINITY)
                                        : INFINITY;
}

// The extended model is adopted when it tracks better by more than the spread between two runs:
// on the fast sine (when one ran) by at least 5 % without losing more than 10 % + 0.05 % of range
// on the triangle's rms (its max moves by a tenth of itself between runs; 0.05 % is a few times
// the sensor noise, and a delay or a resonance inverted at the triangle's corners costs about
// that), else on the triangle's max by 10 % without a higher rms.
bool extension_tracks_better(const IdentifyCandidate& base, const IdentifyCandidate& ext,
                             double fast_hz) {
  if (!std::isfinite(verified_max(ext))) return false;
  if (!(fast_hz > 0.0)) {
    return verified_max(ext) <= 0.9 * verified_max(base) && triangle_rms(ext) <= triangle_rms(base);
  }
  const double bf = sine_rms(base, fast_hz), ef = sine_rms(ext, fast_hz);
  return std::isfinite(ef) && ef <= 0.95 * bf &&
         triangle_rms(ext) <= 1.1 * triangle_rms(base) + 0.05;
}

// A rate law (candidate 0) against its rate-free self: the law is an extension of it, kept when
// it tracks the rate sine better by the spread between two runs without losing on the triangle
// (extension_tracks_better).
bool rate_law_kept(const std::vector<IdentifyCandidate>& candidates, std::size_t rate_free,
                   double sine_hz) {
  return extension_tracks_better(candidates[rate_free], candidates[0], sine_hz);
}

// The candidates left out of the choice: the extension (judged against its base), and the loser
// of a rate law and its rate-free self; a law that loses takes its dead-zone neighbour along.
std::vector<std::size_t> left_out(const std::vector<IdentifyCandidate>& candidates,
                                  std::optional<std::size_t> extended,
                                  std::optional<std::size_t> rate_free, double sine_hz) {
  std::vector<std::size_t> out;
  if (extended) out.push_back(*extended);
  if (!rate_free) return out;
  if (rate_law_kept(candidates, *rate_free, sine_hz)) {
    out.push_back(*rate_free);
    return out;
  }
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const auto* rpi =
        dynamic_cast<const hc::RateDependentPiModel*>(&candidates[i].fit.model.hysteresis());
    if (i != *rate_free && i != extended && rpi != nullptr && !rpi->rate_free()) out.push_back(i);
  }
  return out;
}

// How the rate law fared against its rate-free self (for the result).
json rate_law_json(const std::vector<IdentifyCandidate>& candidates, std::size_t rate_free,
                   double sine_hz) {
  const IdentifyCandidate &law = candidates[0], &free = candidates[rate_free];
  const bool kept = rate_law_kept(candidates, rate_free, sine_hz);
  return {{"kept", kept},
          {"sine_hz", sine_hz},
          {"sine_rms_percent",
           {{"law", sine_field(law, sine_hz, "rms_error_percent")},
            {"rate_free", sine_field(free, sine_hz, "rms_error_percent")}}},
          {"triangle_rms_percent",
           {{"law", field(law.verification, "rms_error_percent")},
            {"rate_free", field(free.verification, "rms_error_percent")}}},
          {"why", kept ? "it tracks the rate sine better than its rate-free self"
                       : "it does not track the rate sine better than its rate-free self by 5 % "
                         "without losing on the triangle"}};
}

// Largest measurement delay identify looks for [ticks].
constexpr int kMaxDelayTicks = 4;

// What identify did so that the model does not depend on earlier runs (for the result).
json identify_history_json(const json& fit_request) {
  return {{"precondition_sweep_s", fit_request.value("precondition_s", 0.0)},
          {"settle_s", fit_request.value("settle_s", 0.0)},
          {"unscored_samples", fit_request.value("skip_samples", 0)},
          {"note",
           "hold at mid-range (creep), sweep to u_max and u_min (hysteresis memory) before the "
           "excitation; the fit simulates both from the output's last value and scores from "
           "the first major loop on"}};
}

// The fit's options for identify's request (details::BuiltRun::fit), at the fit rate: records
// are block-averaged by `block` ticks.
hc::FitOptions identify_fit_options(const json& fit_request, const BenchSettings& settings,
                                    std::size_t block) {
  hc::FitOptions opt;
  opt.kind = common::parse_fit_family(fit_request.value("model", ""));
  opt.operators = fit_request.value("operators", 0);
  opt.dead_zones = fit_request.value("dead_zones", -1);
  opt.heldout_fraction = settings.identify.heldout_fraction;
  // A bench has a history: the creep of earlier runs still settles during the record (tens of
  // seconds), as a slow drift the fit would otherwise bend the hysteresis to.
  opt.drift = true;
  // The ramp, the settle hold and the precondition sweep are simulated, not scored.
  const std::size_t skip = fit_request.value("skip_samples", std::size_t{0});
  opt.skip_samples = (skip + block - 1) / block;
  return opt;
}

// The options of a neighbour's fit on the identify record: that record is already shifted by the
// delay chosen in ticks, and the neighbour's progress is prefixed with what it leaves out.
// `options` must outlive the result (its progress callback is called through it).
hc::FitOptions neighbour_options(const hc::FitOptions& options, std::string prefix) {
  hc::FitOptions o = options;
  o.delay_samples = 0;
  if (options.progress) {
    o.progress = [&options, prefix = std::move(prefix)](double f, const std::string& what) {
      options.progress(f, prefix + what);
    };
  }
  return o;
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
  IdentifyCandidate ext{base.fit, json(), base.label, {}};
  model.set_delay(model.delay_s() + exchange_s);
  model.units = base.fit.model.units;
  model.input_min = base.fit.model.input_min;
  model.input_max = base.fit.model.input_max;
  model.configure(dt);
  ext.fit.model = std::move(model);
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

// The chosen fit, as the model file's identification and the run's result both describe it.
json fit_description(const hc::FitResult& fit, const json& history, const std::string& chosen_by,
                     const json& extension) {
  return {{"method", fit.method},
          {"operators", fit.operators},
          {"dead_zones", fit.dead_zones},
          {"history", history},
          {"delay_ticks", history.value("delay_ticks", 0)},
          {"exchange_ticks", history.value("exchange_ticks", 0)},
          {"fit", to_json(fit.fit)},
          {"heldout", to_json(fit.heldout)},
          {"drift_um_per_s", fit.drift_per_s},
          {"notes", fit.notes},
          {"chosen_by", chosen_by},
          {"extension", extension}};
}

// The extension's verified gains against the model it extends: the triangle's max error and
// the fast sine's rms error (base / extended; > 1 is better).
json verified_gain_json(const IdentifyCandidate& base, const IdentifyCandidate& ext,
                        double fast_hz) {
  const auto ratio = [](double b, double e) {
    return std::isfinite(b) && std::isfinite(e) && e > 0.0 ? json(b / e) : json();
  };
  json v = {{"triangle_max_percent",
             {{"model", field(base.verification, "max_error_percent")},
              {"extended", field(ext.verification, "max_error_percent")}}},
            {"triangle_rms_percent",
             {{"model", field(base.verification, "rms_error_percent")},
              {"extended", field(ext.verification, "rms_error_percent")}}},
            {"triangle_gain", ratio(verified_max(base), verified_max(ext))}};
  if (fast_hz > 0.0) {
    v["fast_hz"] = fast_hz;
    v["fast_rms_percent"] = {{"model", sine_field(base, fast_hz, "rms_error_percent")},
                             {"extended", sine_field(ext, fast_hz, "rms_error_percent")}};
    v["fast_gain"] = ratio(sine_rms(base, fast_hz), sine_rms(ext, fast_hz));
  }
  return v;
}

}  // namespace

// A choice on the noise of one bench run would follow the bench's history, not the models.
std::size_t best_verified(const std::vector<IdentifyCandidate>& candidates,
                          const std::vector<std::size_t>& left_out) {
  const auto skipped = [&left_out](std::size_t i) {
    return std::find(left_out.begin(), left_out.end(), i) != left_out.end();
  };
  double lowest = INFINITY;
  std::optional<std::size_t> first;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (skipped(i)) continue;
    if (!first) first = i;
    lowest = std::min(lowest, verified_max(candidates[i]));
  }
  if (!std::isfinite(lowest)) return first.value_or(0);
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (!skipped(i) && verified_max(candidates[i]) <= kVerifiedTie * lowest) return i;
  }
  return first.value_or(0);
}

IdentifyCandidate family_candidate(hc::FitResult fit) {
  std::string label = type_name(fit);
  return {std::move(fit), json(), std::move(label), {}};
}

std::vector<IdentifyCandidate> fit_identify_candidates(std::span<const double> t,
                                                       std::span<const double> u,
                                                       std::span<const double> y,
                                                       const hc::FitOptions& options) {
  std::vector<hc::ModelKind> kinds;
  if (options.kind) {
    kinds = {*options.kind};
  } else {
    kinds.assign(common::fit_families().begin(), common::fit_families().end());
  }
  std::vector<IdentifyCandidate> out;
  std::string errors;
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    hc::FitOptions o = options;
    o.kind = kinds[i];
    o.delay_samples = 0;  // the record is already shifted by the delay chosen in ticks
    if (options.progress) {
      const double begin = static_cast<double>(i) / kinds.size(), span = 1.0 / kinds.size();
      o.progress = [&options, begin, span, kind = kinds[i]](double f, const std::string& what) {
        options.progress(begin + span * f, std::string(hc::to_string(kind)) + ": " + what);
      };
    }
    try {
      out.push_back(family_candidate(hc::fit_model(t, u, y, o)));
    } catch (const std::exception& e) {
      if (kinds.size() == 1) throw;
      errors += std::string(errors.empty() ? "" : "; ") + std::string(hc::to_string(kinds[i])) +
                ": " + e.what();
    }
  }
  if (out.empty()) throw std::runtime_error("no family could be fitted: " + errors);
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.fit.heldout.rmse < b.fit.heldout.rmse;
  });
  return out;
}

void add_dead_zone_neighbour(std::vector<IdentifyCandidate>& candidates, std::span<const double> t,
                             std::span<const double> u, std::span<const double> y,
                             const hc::FitOptions& options) {
  if (!options.kind || options.dead_zones >= 0 || candidates.size() != 1) return;
  const hc::FitResult& chosen = candidates.front().fit;
  if (chosen.dead_zones < 1) return;
  hc::FitOptions o =
      neighbour_options(options, std::to_string(chosen.dead_zones - 1) + " dead zones: ");
  o.dead_zones = chosen.dead_zones - 1;
  try {
    hc::FitResult fit = hc::fit_model(t, u, y, o);
    if (fit.dead_zones != o.dead_zones) return;  // e.g. a fall-back to the classical PI
    const std::string label = type_name(fit) + "-" + std::to_string(fit.dead_zones) + "dz";
    candidates.push_back({std::move(fit), json(), label, {}});
  } catch (const std::exception&) {
    // The chosen order stands alone; its own fit succeeded.
  }
}

void add_rate_free_neighbour(std::vector<IdentifyCandidate>& candidates, std::span<const double> t,
                             std::span<const double> u, std::span<const double> y,
                             const hc::FitOptions& options) {
  if (candidates.empty()) return;
  const hc::FitResult& chosen = candidates.front().fit;
  const auto* rpi = dynamic_cast<const hc::RateDependentPiModel*>(&chosen.model.hysteresis());
  if (rpi == nullptr) return;
  const hc::RateDependentPiParameters& law = rpi->parameters();
  if (rpi->rate_free()) return;
  hc::FitOptions o = neighbour_options(options, "without the rate law: ");
  o.kind = hc::ModelKind::kModifiedPi;
  o.play_thresholds = law.base.play.thresholds;
  o.dead_zones = chosen.dead_zones;
  try {
    hc::FitResult fit = hc::fit_model(t, u, y, o);
    const auto* mpi = dynamic_cast<const hc::ModifiedPiModel*>(&fit.model.hysteresis());
    if (mpi == nullptr) return;  // e.g. a fall-back to the classical PI
    hc::RateDependentPiParameters free = law;
    free.base = mpi->parameters();
    free.rate_coefficients.assign(free.base.play.thresholds.size(), 0.0);
    free.threshold_rate_s = 0.0;
    hc::ActuatorModel model(
        std::make_unique<hc::RateDependentPiModel>(std::move(free), fit.model.sample_period()));
    model.set_creep(fit.model.creep());
    model.set_dynamics(fit.model.dynamics());
    model.configure(fit.model.sample_period());
    model.units = fit.model.units;
    model.input_min = fit.model.input_min;
    model.input_max = fit.model.input_max;
    fit.model = std::move(model);
    fit.notes.push_back("the rate law left out: the modified PI it contains, refitted");
    candidates.push_back({std::move(fit), json(), "rpi-rate-free", {}});
  } catch (const std::exception&) {
    // The rate law stands alone; its own fit succeeded.
  }
}

void Bench::fit_identify(const RunProgram& run, details::RunResult result) {
  json fit_request;
  {
    std::lock_guard lock(mutex_);
    fit_request = pending_fit_;
  }
  try {
    session_ = fit_candidates(run, result, fit_request);
    continue_identify();
    return;
  } catch (const std::exception& e) {
    result.report["fit_error"] = e.what();
  }
  deliver_result(std::move(result.report));
}

std::unique_ptr<Bench::IdentifySession> Bench::fit_candidates(const RunProgram& run,
                                                              const details::RunResult& result,
                                                              const json& fit_request) {
  // Block-average down to the fit rate: the hysteresis is rate independent and the fit's
  // cost grows with the sample count. The input delay is chosen in ticks before averaging.
  const std::size_t block = std::max<std::size_t>(
      1, static_cast<std::size_t>(
             std::floor(settings_.loop.rate_hz / settings_.identify.fit_rate_hz)));
  hc::FitOptions opt = identify_fit_options(fit_request, settings_, block);
  opt.progress = [this, run_id = run.run_id](double f, const std::string& what) {
    emit({{"event", "fit.progress"}, {"run_id", run_id}, {"fraction", f}, {"stage", what}});
  };
  // The measurement delay in whole ticks: the driver's exchange latency from the readings,
  // then any further delay by held-out error, chosen with the requested family (mpi for
  // auto). The model keeps it; the feedforward previews the reference by it.
  const std::size_t n = result.recorded;
  const std::span<const double> u_rec(run.records.u.data(), n), y_rec(run.records.y.data(), n);
  const std::span<const std::uint32_t> response(run.records.response.data(),
                                                std::min(n, run.records.response.size()));
  hc::FitOptions delay_opt = opt;
  if (!delay_opt.kind) {
    delay_opt.kind = hc::ModelKind::kModifiedPi;
    delay_opt.progress = nullptr;  // auto: the candidates' fits report progress
  }
  const IdentificationFit id =
      fit_identification_record(u_rec, y_rec, response, dt_, block, delay_opt, kMaxDelayTicks);
  const std::vector<double> aligned = response.empty()
                                          ? std::vector<double>(y_rec.begin(), y_rec.end())
                                          : align_to_outputs(u_rec, y_rec, response);
  const AveragedRecord rec = block_average(
      u_rec, aligned, dt_, block, static_cast<std::size_t>(id.delay_ticks - id.exchange_ticks));
  // Each candidate (one family, or every family for auto) is verified on the loop by a
  // tracking segment through its inverse before one is adopted and run.finished goes out.
  auto session = std::make_unique<IdentifySession>();
  if (opt.kind) {
    // One family: the delay search's fit at the chosen delay is that family's fit.
    session->candidates.push_back(family_candidate(id.fit));
    add_dead_zone_neighbour(session->candidates, rec.t, rec.u, rec.y, opt);
    const std::size_t before = session->candidates.size();
    add_rate_free_neighbour(session->candidates, rec.t, rec.u, rec.y, opt);
    if (session->candidates.size() > before) session->rate_free = before;
  } else {
    session->candidates = fit_identify_candidates(rec.t, rec.u, rec.y, opt);
  }
  for (std::size_t i = 0; i < session->candidates.size(); ++i) {
    IdentifyCandidate& c = session->candidates[i];
    c.fit.delay_samples = id.delay_ticks;
    c.fit.model.set_delay(static_cast<double>(id.delay_ticks) * dt_);
    session->jobs.push_back({i});
  }
  if (session->rate_free) {
    session->rate_sine_hz = rate_sine_frequency(settings_.loop.rate_hz);
    session->jobs.push_back({0, session->rate_sine_hz});
    session->jobs.push_back({*session->rate_free, session->rate_sine_hz});
  }
  session->u.assign(u_rec.begin(), u_rec.end());
  session->y = aligned;
  session->unscored = fit_request.value("skip_samples", std::size_t{0});
  session->extend = fit_request.value("extend", true);
  session->log_path = result.log_path;
  session->samples = n;
  session->fit_sample_period_s = static_cast<double>(block) * dt_;
  session->history = identify_history_json(fit_request);
  session->history["delay_ticks"] = id.delay_ticks;
  session->history["exchange_ticks"] = id.exchange_ticks;
  session->history["delay_note"] = id.delay_note;
  session->result = result.report;
  return session;
}

bool Bench::verify_next_candidate() {
  IdentifySession& s = *session_;
  const auto& lim = settings_.loop.limits;
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
      spec.precondition_s = settings_.precondition_s;
      spec.feedforward_bandwidth_hz = settings_.feedforward_bandwidth_hz;
      spec.model_exchange_ticks =
          static_cast<std::uint64_t>(std::max(0, s.history.value("exchange_ticks", 0)));
      p = make_verification_program(c.fit.model, spec, loop_->last_output(), lim, dt_);
    } catch (const std::exception& e) {
      slot = {{"end", "not_run"}, {"reason", e.what()}};
      ++s.next;
      continue;
    }
    const std::string sine_label =
        sine ? "-sine-" + std::to_string(std::lround(job.sine_hz)) + "hz" : "";
    p->run_id = s.result["run_id"].get<std::string>() + "-verify-" + c.label + sine_label;
    json header = {{"run",
                    {{"kind", "verify"},
                     {"identify_run", s.result["run_id"]},
                     {"reference", sine ? "sine" : "triangle"},
                     {"frequency_hz", spec.frequency_hz},
                     {"compensator", "inverse"},
                     {"precondition_samples", p->excitation.size()},
                     {"metrics_from", p->metrics_from},
                     {"rate_hz", settings_.loop.rate_hz}}},
                   {"driver", settings_.driver_type},
                   {"model", hc::to_json(hc::ModelFile{c.fit.model, json::object()})}};
    try {
      open_log(*p, header);
    } catch (const common::CommandError& e) {
      slot = {{"end", "not_run"}, {"reason", e.what()}};
      s.interrupted = true;
      return false;
    }
    const std::string log = p->log->path().string();
    const std::string program_id = p->run_id;
    const std::uint64_t total = p->total_samples;
    std::lock_guard lock(mutex_);
    if (quit_.load()) {
      p->log->close();
      slot = {{"end", "not_run"}, {"reason", "daemon shutting down"}};
      s.interrupted = true;
      return false;
    }
    if (auto refused = loop_->submit(std::move(p))) {
      refused->log->close();
      slot = {{"end", "not_run"}, {"reason", "the loop did not accept the segment"}};
      s.interrupted = true;
      return false;
    }
    s.program_id = program_id;
    active_run_["stage"] =
        "verify " + c.label +
        (sine ? " (" + std::to_string(std::lround(job.sine_hz)) + " Hz sine)" : "");
    active_run_["total"] = total;
    active_run_["verification_log"] = log;
    phase_ = RunPhase::kRunning;  // stop and abort now act on the verification
    return true;
  }
  return false;
}

void Bench::verification_finished(std::unique_ptr<RunProgram> run) {
  IdentifySession& s = *session_;
  {
    std::lock_guard lock(mutex_);
    phase_ = RunPhase::kFinalizing;
    active_run_["stage"] = "choosing the model";
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
    c.sines[job.sine_hz] = std::move(v);
  } else {
    c.verification = std::move(v);
  }
  ++s.next;
  s.interrupted = s.interrupted || run->end != RunEnd::kCompleted;
  if (s.interrupted || quit_.load()) {
    finish_identify();
  } else {
    continue_identify();
  }
}

void Bench::continue_identify() {
  if (verify_next_candidate()) return;
  IdentifySession& s = *session_;
  if (s.extend && !s.extension_tried && !s.interrupted && !quit_.load() &&
      extend_identified_model() && verify_next_candidate()) {
    return;
  }
  finish_identify();
}

bool Bench::extend_identified_model() {
  IdentifySession& s = *session_;
  s.extension_tried = true;
  s.base = best_verified(s.candidates,
                         left_out(s.candidates, std::nullopt, s.rate_free, s.rate_sine_hz));
  const IdentifyCandidate& base = s.candidates[s.base];
  const std::string run_id = s.result["run_id"].get<std::string>();
  {
    std::lock_guard lock(mutex_);
    active_run_["stage"] = "diagnosing the record with " + base.label;
  }
  const auto started = std::chrono::steady_clock::now();
  const auto seconds = [&started] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  };
  // The record holds the outputs matched to the inputs they answer: the model's delay there is
  // its delay less the driver's exchange latency, which the extended model gets back.
  const double exchange_s = s.history.value("exchange_ticks", 0) * dt_;
  try {
    std::vector<double> t(s.u.size());
    for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) * dt_;
    hc::DiagnosisOptions options;
    hc::ActuatorModel baseline = base.fit.model;
    baseline.set_delay(std::max(0.0, baseline.delay_s() - exchange_s));
    options.baseline = std::move(baseline);
    options.units = {"V", "um"};
    options.progress = [this, &run_id](double f, const std::string& what) {
      emit({{"event", "fit.progress"},
            {"run_id", run_id},
            {"fraction", f},
            {"stage", "extension: " + what}});
    };
    const hc::Diagnosis d = hc::diagnose(t, s.u, s.y, options);
    std::optional<ExtensionDraft> draft = extension_draft(d);
    s.extension = extension_json(d, draft ? draft->parts : std::vector<std::string>{});
    if (!draft) {
      s.extension["adopted"] = false;
      s.extension["why"] = "the diagnosis finds nothing the model misses";
      s.extension["diagnosis_s"] = seconds();
      return false;
    }
    s.extension["from"] = draft->named ? "the diagnosis's extended model (named causes)"
                                       : "significant tests below the naming gain, grafted on the "
                                         "model for the bench to judge";
    const ScoredRecord record{t, s.u, s.y, settings_.identify.heldout_fraction, s.unscored};
    IdentifyCandidate ext =
        extended_candidate(base, std::move(draft->model), exchange_s, dt_, record, s.extension);
    const std::string added = extension_added(d, draft->named, s.extension["parts"]);
    ext.fit.notes.push_back("extended by the diagnosis of its record: " + added);
    s.extension["description"] = added;
    ext.label += "-extended";
    s.candidates.push_back(std::move(ext));
    s.extended = s.candidates.size() - 1;
    s.fast_hz = fast_frequency(draft->parts, s.candidates.back().fit.model, settings_.loop.rate_hz);
    s.jobs.push_back({*s.extended, false});
    if (s.fast_hz > 0.0) {
      if (!s.candidates[s.base].sines.contains(s.fast_hz)) s.jobs.push_back({s.base, s.fast_hz});
      s.jobs.push_back({*s.extended, s.fast_hz});
    }
    s.extension["diagnosis_s"] = seconds();
    return true;
  } catch (const std::exception& e) {
    s.extension = {{"adopted", false},
                   {"why", std::string("the diagnosis failed: ") + e.what()},
                   {"diagnosis_s", seconds()}};
    return false;
  }
}

void Bench::finish_identify() {
  std::unique_ptr<IdentifySession> session = std::move(session_);
  IdentifySession& s = *session;
  json result = std::move(s.result);
  // The verified figure decides when any candidate was verified; else the held-out error.
  std::size_t chosen =
      best_verified(s.candidates, left_out(s.candidates, s.extended, s.rate_free, s.rate_sine_hz));
  bool extended = false;
  if (s.extended) {
    const IdentifyCandidate &base = s.candidates[s.base], &ext = s.candidates[*s.extended];
    extended = chosen == s.base && extension_tracks_better(base, ext, s.fast_hz);
    s.extension["verified"] = verified_gain_json(base, ext, s.fast_hz);
    s.extension["adopted"] = extended;
    s.extension["why"] =
        extended ? "it tracks better on the bench" : "it does not track better on the bench";
    if (extended) chosen = *s.extended;
  } else if (s.extension.is_null()) {
    s.extension = {{"adopted", false},
                   {"why", !s.extend ? "not asked (extend = false)"
                                     : "not tried: the verification did not complete"}};
  }
  try {
    IdentifyCandidate& c = s.candidates[chosen];
    hc::FitResult& fit = c.fit;
    fit.model.units = {"V", "um"};
    json candidates = json::array();
    for (const auto& other : s.candidates) candidates.push_back(candidate_summary(other));
    const json rate_law =
        s.rate_free ? rate_law_json(s.candidates, *s.rate_free, s.rate_sine_hz) : json();
    const std::string chosen_by = extended ? "the extension's verified tracking"
                                  : std::isfinite(verified_max(c)) ? "verified tracking max error"
                                                                   : "held-out error";
    hc::ModelFile file{fit.model, json::object()};
    file.identification = fit_description(fit, s.history, chosen_by, s.extension);
    file.identification.update({{"run_id", result["run_id"]},
                                {"log", s.log_path},
                                {"samples", s.samples},
                                {"fit_sample_period_s", s.fit_sample_period_s},
                                {"verification", c.verification}});
    if (s.candidates.size() > 1) file.identification["candidates"] = candidates;
    if (s.rate_free) file.identification["rate_law"] = rate_law;
    std::filesystem::create_directories(settings_.model_dir);
    const std::string path = (std::filesystem::path(settings_.model_dir) /
                              (result["run_id"].get<std::string>() + ".json"))
                                 .string();
    common::save_model_file(path, file);
    result["model"] = fit_description(fit, s.history, chosen_by, s.extension);
    result["model"].update({{"path", path}, {"type", type_name(fit)}});
    if (s.rate_free) result["model"]["rate_law"] = rate_law;
    result["verification"] = c.verification;
    if (s.candidates.size() > 1) result["candidates"] = candidates;
    std::lock_guard lock(mutex_);
    model_ = std::move(file);
    model_path_ = path;
    ++model_generation_;
  } catch (const std::exception& e) {
    result["fit_error"] = e.what();
  }
  deliver_result(std::move(result));
}

}  // namespace hystbench::daemon

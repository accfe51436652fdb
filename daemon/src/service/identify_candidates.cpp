// identify's candidates: the identify record brought to the fit rate with the measurement delay
// chosen in ticks, one fit per family (every family for auto), the neighbours the verification
// judges (one dead zone fewer, a rate law without its law), and the jobs that verify them
// (the identify coordinator on the supervisor thread; identify_coordinator.hpp).
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hystbench/common/fit_families.hpp"
#include "hystbench/compensation/model_check.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/preisach_identification.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"
#include "hystbench/daemon/runs/identification_fit.hpp"
#include "runs/details/run_result.hpp"
#include "service/details/identify_coordinator.hpp"
#include "service/details/identify_session.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

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

// The settle hold and the precondition sweep leave creep moving. The Preisach plane chooses its
// output map with creep lags beside its cells, which lower its held-out error on the loopback's
// identify record; the modified PI alternates several fits of the record for them and gains
// nothing on the triangle there, at several times the cost (docs/measurements.md, "The Preisach
// family through identify"). Kept only where they lower the held-out error.
bool tries_creep(std::optional<hc::ModelKind> kind) { return kind == hc::ModelKind::kPreisach; }

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
  opt.creep = tries_creep(opt.kind);
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

}  // namespace

std::string model_type_name(const hc::FitResult& f) {
  return std::string(hc::to_string(f.model.hysteresis().kind()));
}

IdentifyCandidate family_candidate(hc::FitResult fit) {
  std::string label = model_type_name(fit);
  return {std::move(fit), json(), std::move(label), {}, std::nullopt};
}

hc::ModelCheck check_of(const IdentifyCandidate& c, double dt_s) {
  return c.check ? *c.check : hc::check_model(c.fit.model, dt_s);
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
    o.creep = tries_creep(o.kind);
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

namespace {

// The neighbour of `chosen`'s dead zones per side: one fewer; for a plane that kept the identity
// as its output map, the other map its fit tries (a few dead zones per side).
std::optional<int> neighbour_dead_zones(const hc::FitResult& chosen) {
  if (chosen.dead_zones >= 1) return chosen.dead_zones - 1;
  if (chosen.model.hysteresis().kind() != hc::ModelKind::kPreisach) return std::nullopt;
  const std::vector<std::size_t> maps = hc::PreisachFitOptions{}.output_zones;
  const std::size_t most = *std::max_element(maps.begin(), maps.end());
  if (most == 0) return std::nullopt;
  return static_cast<int>(most);
}

}  // namespace

void add_dead_zone_neighbour(std::vector<IdentifyCandidate>& candidates, std::span<const double> t,
                             std::span<const double> u, std::span<const double> y,
                             const hc::FitOptions& options) {
  if (!options.kind || options.dead_zones >= 0 || candidates.size() != 1) return;
  const hc::FitResult& chosen = candidates.front().fit;
  const std::optional<int> zones = neighbour_dead_zones(chosen);
  if (!zones) return;
  hc::FitOptions o = neighbour_options(options, std::to_string(*zones) + " dead zones: ");
  o.dead_zones = *zones;
  // A plane's rate law, searched for on the chosen plane, is refitted on its neighbour rather
  // than searched for again (the search is most of a plane's fit).
  if (chosen.model.hysteresis().kind() == hc::ModelKind::kPreisach) {
    o.preisach_given_rate_law = chosen.model.hysteresis().thresholds_law();
  }
  try {
    hc::FitResult fit = hc::fit_model(t, u, y, o);
    if (fit.dead_zones != o.dead_zones) return;  // e.g. a fall-back to the classical PI
    const std::string label = model_type_name(fit) + "-" + std::to_string(fit.dead_zones) + "dz";
    candidates.push_back({std::move(fit), json(), label, {}, std::nullopt});
  } catch (const std::exception&) {
    // The chosen order stands alone; its own fit succeeded.
  }
}

void add_rate_free_neighbour(std::vector<IdentifyCandidate>& candidates, std::span<const double> t,
                             std::span<const double> u, std::span<const double> y,
                             const hc::FitOptions& options) {
  if (candidates.empty()) return;
  const hc::FitResult& chosen = candidates.front().fit;
  if (chosen.model.hysteresis().kind() == hc::ModelKind::kPreisach) {
    // The plane's relays widening with the rate: the plane fitted without the law beside it.
    if (!chosen.model.hysteresis().thresholds_law()) return;
    hc::FitOptions o = neighbour_options(options, "without the rate law: ");
    o.preisach_rate_law = false;
    // Its output map as the chosen plane's: the law alone is what the bench judges (and the
    // map's search is half the plane's fit).
    o.dead_zones = chosen.dead_zones;
    try {
      hc::FitResult fit = hc::fit_model(t, u, y, o);
      if (fit.model.hysteresis().kind() != hc::ModelKind::kPreisach) return;
      fit.notes.push_back("the rate law left out: the plane refitted without it");
      candidates.push_back({std::move(fit), json(), "preisach-rate-free", {}, std::nullopt});
    } catch (const std::exception&) {
      // The rate law stands alone; its own fit succeeded.
    }
    return;
  }
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
    free.threshold_rate_exponent = 1.0;
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
    candidates.push_back({std::move(fit), json(), "rpi-rate-free", {}, std::nullopt});
  } catch (const std::exception&) {
    // The rate law stands alone; its own fit succeeded.
  }
}

void details::IdentifyCoordinator::diagnose_candidates_ahead(IdentifySession& s) const {
  if (!s.extend) return;
  // Every candidate may become the base: diagnosed in the order the choice prefers them until
  // the verification has chosen.
  std::vector<std::size_t> order(s.candidates.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  details::DiagnosisAhead::Task task = identify_diagnosis(
      s.candidates, s.history.value("exchange_ticks", 0) * dt_, s.u, s.y, dt_, s.swap_operator);
  if (s.ahead) {
    s.ahead->queue_more(std::move(task), order);
  } else {
    s.ahead = std::make_unique<details::DiagnosisAhead>(std::move(task), std::move(order));
  }
}

std::unique_ptr<IdentifySession> details::IdentifyCoordinator::fit_candidates(
    const RunProgram& run, const details::RunResult& result, const json& fit_request) {
  // Block-average down to the fit rate: the hysteresis is rate independent and the fit's
  // cost grows with the sample count. The input delay is chosen in ticks before averaging.
  const std::size_t block = std::max<std::size_t>(
      1, static_cast<std::size_t>(
             std::floor(bench_.settings.loop.rate_hz / bench_.settings.identify.fit_rate_hz)));
  hc::FitOptions opt = identify_fit_options(fit_request, bench_.settings, block);
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
  session->u.assign(u_rec.begin(), u_rec.end());
  session->y = aligned;
  session->unscored = fit_request.value("skip_samples", std::size_t{0});
  session->extend = fit_request.value("extend", true);
  session->swap_operator = !fit_request.value("family_fixed", false);
  session->log_path = result.log_path;
  session->samples = n;
  session->fit_sample_period_s = static_cast<double>(block) * dt_;
  session->history = identify_history_json(fit_request);
  session->history["delay_ticks"] = id.delay_ticks;
  session->history["exchange_ticks"] = id.exchange_ticks;
  session->history["delay_note"] = id.delay_note;
  session->result = result.report;
  const auto timed = [&](IdentifyCandidate& c) {
    c.fit.delay_samples = id.delay_ticks;
    c.fit.model.set_delay(static_cast<double>(id.delay_ticks) * dt_);
  };
  if (opt.kind) {
    // One family: the delay search's fit at the chosen delay is that family's fit. Its
    // diagnosis starts now, on the second core beside its neighbours' fits.
    session->candidates.push_back(family_candidate(id.fit));
    timed(session->candidates.front());
    diagnose_candidates_ahead(*session);
    add_dead_zone_neighbour(session->candidates, rec.t, rec.u, rec.y, opt);
    const std::size_t before = session->candidates.size();
    add_rate_free_neighbour(session->candidates, rec.t, rec.u, rec.y, opt);
    if (session->candidates.size() > before) session->rate_free = before;
  } else {
    session->candidates = fit_identify_candidates(rec.t, rec.u, rec.y, opt);
  }
  for (std::size_t i = 0; i < session->candidates.size(); ++i) {
    IdentifyCandidate& c = session->candidates[i];
    timed(c);
    c.check = hc::check_model(c.fit.model, dt_);
    session->jobs.push_back({i});
  }
  if (session->rate_free) {
    session->rate_sine_hz = rate_sine_frequency(bench_.settings.loop.rate_hz);
    session->jobs.push_back({0, session->rate_sine_hz});
    session->jobs.push_back({*session->rate_free, session->rate_sine_hz});
  }
  return session;
}

}  // namespace hystbench::daemon

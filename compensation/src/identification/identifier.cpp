#include "details/identifier.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "details/parallel_tasks.hpp"
#include "details/threshold_refinement.hpp"
#include "details/validate.hpp"
#include "hystbench/compensation/dead_zone.hpp"

namespace hystbench::compensation::details::identification {

namespace {

constexpr int kOperatorGrid[] = {4, 6, 8, 10, 12, 15, 20, 25, 30};
constexpr int kMaxDeadZones = 5;
constexpr std::size_t kRowsPerUnknown = 10;  // order search: at least this many rows per unknown

}  // namespace

Identifier::Identifier(std::span<const double> t, std::span<const double> u,
                       std::span<const double> y, const FitOptions& options)
    : o_(options), r_(make_record(t, u, y, options)) {
  center_ = o_.center.value_or(0.5 * (r_.y_lo + r_.y_hi));
}

FitResult Identifier::run() {
  progress(0.0, "checking the record");
  int delay = choose_delay(o_.kind.value_or(ModelKind::kModifiedPi));
  r_.set_delay(delay);
  memo_.clear();
  plane_law_.reset();
  if (o_.preisach_given_rate_law && o_.preisach_given_rate_law->active()) {
    plane_law_.emplace(*o_.preisach_given_rate_law);
  }
  Candidate best = search_families();
  if (o_.refine_thresholds) {
    progress(0.7, "refining thresholds (Levenberg-Marquardt)");
    refine(best);
  }
  if (o_.creep) {
    progress(0.9, "fitting creep");
    add_creep(best);
  }
  check_nesting(best);
  std::vector<std::string> notes;
  fall_back_to_pi(best, delay, notes);
  progress(0.97, "scoring");
  return scored_result(best, delay, std::move(notes));
}

Candidate Identifier::search_families() {
  std::vector<ModelKind> kinds;
  if (o_.kind) {
    kinds.push_back(*o_.kind);
  } else {
    for (const Family& f : families()) {
      if (f.in_auto) kinds.push_back(f.kind);
    }
  }
  std::optional<Candidate> best;
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    stage_span_ = 0.6 / static_cast<double>(kinds.size());
    stage_begin_ = 0.1 + stage_span_ * static_cast<double>(i);
    const Family* f = family(kinds[i]);
    const std::string skip = !o_.kind && f->auto_skip ? (this->*f->auto_skip)() : std::string();
    if (!skip.empty()) {
      stage_progress(0.0, "skipping " + std::string(to_string(kinds[i])) + ": " + skip);
      continue;
    }
    stage_progress(0.0, "fitting " + std::string(to_string(kinds[i])));
    Candidate c = search(kinds[i]);
    if (!best || c.score() < best->score()) best = std::move(c);
  }
  if (!std::isfinite(best->score())) {
    throw std::logic_error("identification found no invertible model: " + best->method);
  }
  return std::move(*best);
}

void Identifier::check_nesting(Candidate& best) {
  // The nesting checks hold for a family's fit whether it was asked for or won `auto`; in
  // `auto` the nested model is returned as its own family.
  const Family* f = family(best.structure.kind);
  if (f && f->check_nesting) (this->*f->check_nesting)(best);
}

void Identifier::fall_back_to_pi(Candidate& best, int& delay, std::vector<std::string>& notes) {
  if (!o_.kind || *o_.kind == ModelKind::kPi || !o_.play_thresholds.empty()) return;
  // The classical PI is contained in every richer family (no dead zones, unit coupling, zero
  // rate coefficients): a richer fit that does worse on held-out data than it has fitted the
  // record's noise or transients, not the device, and the PI is returned in its place.
  progress(0.95, "checking against the classical PI it contains");
  // At the delay a classical PI fit would choose itself, so that `--model pi` on the same
  // record is never better than what this returns.
  const int pi_delay = choose_delay(ModelKind::kPi);
  if (pi_delay != delay) r_.set_delay(pi_delay), memo_.clear(), plane_law_.reset();
  Candidate pi = search_pi();
  finish(pi);
  if (pi.score() < best.score()) {
    const std::string unit = " " + o_.units.output;
    notes.push_back("fell back to the classical PI: the " + std::string(to_string(*o_.kind)) +
                    " fit's held-out rms was " + fmt(best.score()) + unit +
                    ", the classical PI's " + fmt(pi.score()) + unit +
                    " (a richer family is never returned worse than the PI it contains)");
    pi.method += " (fall-back: better than " + std::string(to_string(*o_.kind)) + ")";
    best = std::move(pi);
    delay = pi_delay;
  }
}

FitResult Identifier::scored_result(Candidate& best, int delay, std::vector<std::string> notes) {
  FitResult out;
  out.model = std::move(*best.model);
  out.drift_per_s = best.drift;
  std::vector<double> y_without_drift;
  if (o_.drift) {
    const double duration = static_cast<double>(r_.n - 1) * r_.dt;
    notes.push_back("fitted a drift of " + fmt(best.drift) + " " + o_.units.output + "/s (" +
                    fmt(best.drift * duration) + " " + o_.units.output +
                    " over the record) with the weights: the record's, not the model's (the "
                    "errors are of the record without it)");
    y_without_drift.assign(r_.y.begin(), r_.y.end());
    details::add_drift(best.structure, -best.drift, y_without_drift);
    r_.y = y_without_drift;
  }
  out.model.configure(r_.dt);
  out.model.set_delay(delay * r_.dt);
  out.model.units = o_.units;
  const auto [ulo, uhi] = std::minmax_element(r_.u.begin(), r_.u.end());
  out.model.input_min = *ulo;
  out.model.input_max = *uhi;
  const ModelScore s = score_model(out.model, r_.t, r_.u, r_.y, o_.heldout_fraction, r_.begin);
  out.fit = s.fit;
  out.heldout = s.heldout;
  out.fit_samples = r_.fit_end - r_.begin;
  out.heldout_samples = r_.n - r_.fit_end;
  out.operators = operators_of(best.structure);
  out.dead_zones = dead_zones_of(best.structure);
  out.method = best.method;
  out.delay_samples = delay;
  out.creep = !best.structure.creep_time_constants.empty();
  out.skipped_samples = r_.begin;
  if (!o_.skip_samples && r_.begin > 0) {
    notes.insert(notes.begin(),
                 "left out the first " + fmt(static_cast<double>(r_.begin) * r_.dt) + " s (" +
                     std::to_string(r_.begin) +
                     " samples, until the input reached both its extremes: the state before the "
                     "record is unknown); simulated, neither fitted nor scored");
  }
  if (o_.creep && !o_.creep_always) {
    notes.push_back(out.creep ? "creep lags kept: they lowered the held-out error"
                              : "no creep lags: they did not lower the held-out error");
  }
  out.notes = std::move(notes);
  out.candidates = std::move(log_);
  progress(1.0, "done");
  return out;
}

ModelStructure Identifier::structure(ModelKind kind, int plays, int dead_zones) const {
  ModelStructure s;
  s.kind = kind;
  s.dt = r_.dt;
  const double u_span = r_.u_hi - r_.u_lo;
  const double y_span = r_.y_hi - r_.y_lo;
  s.play_thresholds = o_.play_thresholds.empty()
                          ? uniform_thresholds(static_cast<std::size_t>(plays), 0.5 * u_span)
                          : o_.play_thresholds;
  s.input_reference = 0.5 * (r_.u_lo + r_.u_hi);
  s.min_play_slope = o_.min_cumulative_weight * y_span / u_span;
  s.min_dead_zone_slope = o_.min_cumulative_weight;
  s.center = center_;
  s.drift = o_.drift;
  s.drift_t0_s = r_.drift_t0_s;
  if (s.has_dead_zones() || (kind == ModelKind::kCoupledPlayPi && dead_zones > 0)) {
    if (!o_.dead_zone_thresholds.empty()) {
      s.dead_zone_thresholds = o_.dead_zone_thresholds;
    } else {
      // Uniform on the fitted output range about the center, 2m+1 thresholds in all.
      const double above = r_.y_hi - center_;
      const double below = center_ - r_.y_lo;
      s.dead_zone_thresholds =
          uniform_dead_zone_thresholds(static_cast<std::size_t>(dead_zones), below, above);
    }
  }
  return s;
}

namespace {

// The structure fitted on every stride-th row of the record's fitted part and scored on it; reads
// the record only (several at once on the machine's cores).
Candidate fitted(const ModelStructure& s, std::string method, std::size_t stride, const Record& r) {
  Candidate c;
  c.structure = s;
  c.method = std::move(method);
  Design design(s);
  const details::BoundedLsqResult fit =
      details::fit_design(design, r.ud, r.y, r.begin, r.fit_end, stride);
  c.x = fit.x;
  c.model = design.build(fit.x);
  if (s.drift) c.drift = fit.x[design.drift_column()];
  score(c, r);
  return c;
}

}  // namespace

void Identifier::log_fit(const Candidate& c) {
  const ModelStructure& s = c.structure;
  log_.push_back(
      {s.kind, operators_of(s), dead_zones_of(s), r_.delay, c.fit.rmse, c.heldout.rmse, c.method});
}

Candidate Identifier::evaluate(const ModelStructure& s, std::string method, std::size_t stride) {
  Candidate c = fitted(s, std::move(method), stride, r_);
  log_fit(c);
  return c;
}

std::vector<Candidate> Identifier::evaluate_each(const std::vector<ModelStructure>& structures,
                                                 const std::string& method, std::size_t stride) {
  std::vector<Candidate> out(structures.size());
  details::run_parallel(structures.size(),
                        [&](std::size_t i) { out[i] = fitted(structures[i], method, stride, r_); });
  for (const Candidate& c : out) log_fit(c);
  return out;
}

Candidate& Identifier::memo(ModelKind kind, int plays, int dead_zones, std::array<double, 3> cp) {
  const auto key = std::make_tuple(kind, plays, dead_zones, cp);
  auto it = memo_.find(key);
  if (it == memo_.end()) {
    ModelStructure s = structure(kind, plays, dead_zones);
    s.cp_scale = cp;
    it = memo_.emplace(key, evaluate(s, "constrained-lsq")).first;
  }
  return it->second;
}

std::vector<int> Identifier::operator_grid(int extra_unknowns) const {
  if (!o_.play_thresholds.empty()) return {static_cast<int>(o_.play_thresholds.size())};
  if (o_.operators > 0) return {o_.operators};
  const std::size_t rows = r_.fit_end - r_.begin;
  std::vector<int> grid;
  for (const int n : kOperatorGrid) {
    if (static_cast<std::size_t>(n + 1 + extra_unknowns) * kRowsPerUnknown <= rows)
      grid.push_back(n);
  }
  if (grid.empty()) grid.push_back(std::max<int>(1, static_cast<int>(rows / kRowsPerUnknown) - 1));
  return grid;
}

std::vector<int> Identifier::dead_zone_grid() const {
  if (!o_.dead_zone_thresholds.empty()) {
    return {static_cast<int>(o_.dead_zone_thresholds.size() / 2)};
  }
  if (o_.dead_zones >= 0) return {o_.dead_zones};
  std::vector<int> grid;
  for (int m = 0; m <= kMaxDeadZones; ++m) grid.push_back(m);
  return grid;
}

int Identifier::choose_delay(ModelKind family) {
  if (o_.delay_samples >= 0) return o_.delay_samples;
  // A mid-size model of the family (MPI for every family with dead zones or more) at each delay.
  const ModelKind kind = family == ModelKind::kPi ? ModelKind::kPi : ModelKind::kModifiedPi;
  const std::vector<int> ns = operator_grid(2 * kDefaultDeadZones);
  const int plays = o_.operators > 0 ? ns.front() : ns[ns.size() / 2];
  const int m = o_.dead_zones >= 0 ? o_.dead_zones : kDefaultDeadZones;
  int best = 0;
  double best_score = std::numeric_limits<double>::infinity();
  for (int d = 0; d <= o_.max_delay_samples; ++d) {
    progress(0.1 * d / (o_.max_delay_samples + 1), "delay " + std::to_string(d) + " samples");
    r_.set_delay(d);
    const double s = evaluate(structure(kind, plays, m), "delay-search").score();
    if (s < best_score) best_score = s, best = d;
  }
  return best;
}

Candidate Identifier::search(ModelKind kind) {
  if (const Family* f = family(kind)) return (this->*f->search)();
  throw std::invalid_argument("identify: no play-operator search for model kind " +
                              std::string(to_string(kind)));
}

void Identifier::finish(Candidate& c) {
  if (o_.refine_thresholds) refine(c);
  if (o_.creep) add_creep(c);
}

void Identifier::finish_nested(Candidate& c, ActuatorModel m, const Candidate& base,
                               const char* note) {
  m.set_creep(base.model->creep());
  c.model = std::move(m);
  c.method = base.method + note;
  score(c, r_);
  log_.push_back({c.structure.kind, static_cast<int>(c.structure.plays()),
                  dead_zones_of(c.structure), r_.delay, c.fit.rmse, c.heldout.rmse, c.method});
}

void Identifier::refine(Candidate& c) {
  if (c.structure.kind == ModelKind::kPreisach) return;  // no thresholds: its cells are a grid
  details::RefinementSettings settings;
  settings.plays = o_.play_thresholds.empty();
  settings.dead_zones = o_.dead_zone_thresholds.empty();
  const details::RefinementRecord rec{r_.ud, r_.y, r_.begin, r_.fit_end};
  const details::RefinementResult refined = details::refine_structure(c.structure, rec, settings);
  if (refined.final_rmse >= refined.initial_rmse) return;
  Candidate next = evaluate(refined.structure, c.method + "+lm");
  if (next.score() < c.score()) c = std::move(next);
}

}  // namespace hystbench::compensation::details::identification

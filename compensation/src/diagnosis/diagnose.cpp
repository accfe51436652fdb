// The diagnosis (diagnose, diagnosis.hpp): the record checked, the baseline fitted, its residual
// profiled, every candidate tested (and, for several records, scored on each record left out),
// then the decision (naming/decide.hpp). The result's look-ups by cause and by variable.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/cancel_point.hpp"
#include "diagnosis/details/candidate_reports.hpp"
#include "diagnosis/details/candidates.hpp"
#include "diagnosis/details/left_out.hpp"
#include "diagnosis/details/naming/decide.hpp"
#include "diagnosis/details/number_text.hpp"
#include "diagnosis/details/progress.hpp"
#include "diagnosis/details/record.hpp"
#include "diagnosis/details/record_set.hpp"
#include "diagnosis/details/reference.hpp"
#include "diagnosis/details/residual_profiles.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation {

using details::num;

const CandidateReport* Diagnosis::candidate(Cause c) const noexcept {
  for (const CandidateReport& r : candidates) {
    if (r.cause == c) return &r;
  }
  return nullptr;
}

const ResidualProfile* Diagnosis::profile(std::string_view variable) const noexcept {
  for (const ResidualProfile& p : profiles) {
    if (p.variable == variable) return &p;
  }
  return nullptr;
}

namespace details::diagnosis {

namespace {

Diagnosis run_diagnosis(std::span<const double> t, std::span<const double> u,
                        std::span<const double> y, const DiagnosisOptions& options,
                        const std::vector<details::RecordPart>& parts) {
  const CancelScope cancellable(options);
  report(options, 0.0, "checking the record");
  const std::vector<std::size_t> starts = details::starts_of(parts);
  const details::DiagnosisRecord r = details::make_diagnosis_record(t, u, y, options, starts);
  Diagnosis d;
  for (const details::RecordPart& p : parts) d.records.push_back(p.name);
  d.record_starts = starts;
  d.samples = r.n;
  d.sample_period_s = r.dt;
  d.split = r.split;

  report(options, 0.05, "baseline");
  const Baseline base = fit_baseline(d, r, options);

  // What the baseline gets wrong.
  report(options, 0.2, "residual structure");
  std::vector<double> e = residual_and_noise(d, r);
  const details::InputEvents ev = details::find_input_events(r.u, r.dt);
  d.profiles = residual_profiles(r, e, ev);
  d.frequency_response = details::frequency_response(d.baseline_prediction, r.y, r.dt, d.noise_rms);
  set_coherent_share(d);

  // The candidates: their statistics read the residual of the reference the gains are judged
  // against.
  const Reference ref = reference_of(d, r, base.fit, ev, std::move(e), options);
  details::CandidateContext ctx{r,  base.spec,    base.fit,     ref.prediction, ref.residual,
                                ev, ref.profiles, ref.response, d.noise_rms};
  ctx.swap_operator = options.baseline.has_value() && options.swap_operator;
  const std::vector<details::ExtensionFit> fits = test_candidates(d, ctx, options);
  if (parts.size() > 1) {
    report(options, 0.93, "leaving each record out");
    details::score_left_out(d, r, parts, base.spec, fits, options);
  }

  decide(d, {r, fits, ev, ref, base.spec.delay_samples}, options);
  report(options, 1.0, "done");
  return d;
}

}  // namespace

}  // namespace details::diagnosis

Diagnosis diagnose(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                   const DiagnosisOptions& options) {
  return details::diagnosis::run_diagnosis(t, u, y, options, {{"record", 0, u.size()}});
}

Diagnosis diagnose(std::span<const RecordView> records, const DiagnosisOptions& options) {
  if (records.empty()) throw std::invalid_argument("no record to diagnose");
  if (records.size() == 1) {
    const RecordView& rec = records[0];
    Diagnosis d;
    try {
      d = diagnose(rec.t, rec.u, rec.y, options);
    } catch (const std::invalid_argument& e) {
      if (rec.name.empty()) throw;
      throw std::invalid_argument(rec.name + ": " + e.what());
    }
    if (!rec.name.empty()) d.records = {rec.name};
    return d;
  }
  std::vector<details::RecordPart> parts;
  std::vector<double> t, u, y;
  double dt0 = 0.0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const RecordView& rec = records[i];
    const std::string name = rec.name.empty() ? "record " + std::to_string(i + 1) : rec.name;
    try {
      // Each record on its own must be a record the diagnosis takes.
      details::make_diagnosis_record(rec.t, rec.u, rec.y, options);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(name + ": " + e.what());
    }
    const double dt = (rec.t.back() - rec.t.front()) / static_cast<double>(rec.t.size() - 1);
    if (i == 0) dt0 = dt;
    if (std::abs(dt - dt0) > 0.01 * dt0) {
      throw std::invalid_argument(name + ": sample period " + num(dt * 1e3) + " ms differs from " +
                                  parts.front().name + "'s " + num(dt0 * 1e3) +
                                  " ms; records diagnosed together need one sample rate");
    }
    parts.push_back({name, u.size(), u.size() + rec.u.size()});
    u.insert(u.end(), rec.u.begin(), rec.u.end());
    y.insert(y.end(), rec.y.begin(), rec.y.end());
  }
  t.resize(u.size());
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) * dt0;
  const std::vector<double> offsets = details::align_offsets(t, u, y, options, parts);
  Diagnosis d = details::diagnosis::run_diagnosis(t, u, y, options, parts);
  d.record_offsets = offsets;
  std::string shifted;
  for (std::size_t i = 1; i < parts.size(); ++i) {
    if (std::abs(offsets[i]) <= 3.0 * d.noise_rms) continue;
    shifted += (shifted.empty() ? "" : ", ") + parts[i].name + " by " + num(-offsets[i]) + " " +
               options.units.output;
  }
  if (!shifted.empty()) {
    d.notes.push_back(
        "output offsets differ between the records (a sensor offset of the run, "
        "not a property of the device): aligned to " +
        parts.front().name + "'s, " + shifted);
  }
  return d;
}

}  // namespace hystbench::compensation

#include "diagnosis/details/left_out.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <utility>

#include "diagnosis/details/number_text.hpp"

namespace hystbench::compensation::details {

namespace {

// Several records: an extension carries over when its geometric-mean gain on the records left
// out whole is at least half the named gain's margin (1.1 with min_gain 1.2) and it loses on no
// left-out record by more than this.
constexpr double kMaxLeftOutLoss = 0.95;
// The baseline family "does not fit the device" when, fitted on the others, it predicts some
// record this many times worse than it predicts its own held-out blocks.
constexpr double kFamilyMismatch = 3.0;

}  // namespace

LeftOutScorer::LeftOutScorer(const DiagnosisRecord& r, std::vector<RecordPart> parts,
                             const DiagnosisOptions& options)
    : r_(r), parts_(std::move(parts)) {
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    auto o = std::make_unique<Others>();
    std::vector<std::size_t> starts;
    for (std::size_t j = 0; j < parts_.size(); ++j) {
      if (j == i) continue;
      starts.push_back(o->u.size());
      const RecordPart& p = parts_[j];
      o->u.insert(o->u.end(), r.u.begin() + p.begin, r.u.begin() + p.end);
      o->y.insert(o->y.end(), r.y.begin() + p.begin, r.y.begin() + p.end);
    }
    o->t.resize(o->u.size());
    for (std::size_t k = 0; k < o->t.size(); ++k) o->t[k] = static_cast<double>(k) * r.dt;
    DiagnosisOptions others_options;
    others_options.blocks = options.blocks;
    others_options.heldout_every = options.heldout_every;
    others_options.units = options.units;
    o->record = make_diagnosis_record(o->t, o->u, o->y, others_options, starts);
    others_.push_back(std::move(o));
  }
}

std::optional<std::vector<double>> LeftOutScorer::rms(const ExtensionSpec& spec) const {
  std::vector<double> out;
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    const RecordPart& p = parts_[i];
    ActuatorModel model;
    try {
      model = fit_extension(others_[i]->record, spec, FitRows::kAll, false).model;
    } catch (const DiagnosisCancelled&) {
      throw;
    } catch (const std::exception&) {
      return std::nullopt;  // a structure the others cannot support (too few rows, ...)
    }
    const std::span<const double> u = r_.u.subspan(p.begin, p.end - p.begin);
    const std::span<const double> y = r_.y.subspan(p.begin, p.end - p.begin);
    out.push_back(validate_model(std::move(model), u, y, r_.dt).rmse);
  }
  return out;
}

void score_left_out(Diagnosis& d, const DiagnosisRecord& r, const std::vector<RecordPart>& parts,
                    const ExtensionSpec& base, const std::vector<ExtensionFit>& fits,
                    const DiagnosisOptions& options) {
  const LeftOutScorer scorer(r, parts, options);
  const auto base_rms = scorer.rms(base);
  if (!base_rms) {
    d.notes.push_back(
        "the baseline could not be fitted with a record left out; no candidate "
        "is judged across records");
    return;
  }
  const double carry = 1.0 + 0.5 * (options.min_gain - 1.0);
  for (std::size_t i = 0; i < d.candidates.size(); ++i) {
    CandidateReport& c = d.candidates[i];
    const auto rms = scorer.rms(fits[i].spec);
    if (!rms) {
      c.carries_over = false;
      c.left_out_gain = 0.0;
      continue;
    }
    double log_sum = 0.0;
    bool loses = false;
    for (std::size_t j = 0; j < parts.size(); ++j) {
      const double gain = (*rms)[j] > 0.0 ? (*base_rms)[j] / (*rms)[j] : 1.0;
      c.left_out.push_back({parts[j].name, (*base_rms)[j], (*rms)[j], gain});
      log_sum += std::log(std::max(gain, 1e-12));
      loses = loses || gain < kMaxLeftOutLoss;
    }
    c.left_out_gain = std::exp(log_sum / static_cast<double>(parts.size()));
    c.carries_over = !loses && c.left_out_gain >= carry;
  }
  std::string worst;
  double worst_ratio = 0.0;
  for (std::size_t j = 0; j < parts.size(); ++j) {
    const double ratio =
        d.baseline_heldout.rmse > 0.0 ? (*base_rms)[j] / d.baseline_heldout.rmse : 0.0;
    if (ratio > worst_ratio) worst_ratio = ratio, worst = parts[j].name;
  }
  if (worst_ratio >= kFamilyMismatch) {
    bool any = false;
    for (const CandidateReport& c : d.candidates) any = any || (c.carries_over && c.gain > 1.0);
    d.notes.push_back(
        "across records: fitted on the others, the baseline predicts " + worst + " " +
        num(worst_ratio) + "x worse than its own held-out blocks" +
        (any ? "; an extension that carries over is needed"
             : "; no candidate carries over either: the model family does not fit this device "
               "across records (its hysteresis or the effect changes from record to record)"));
  }
}

}  // namespace hystbench::compensation::details

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "details/diagnosis_signals.hpp"
#include "details/record_startup.hpp"
#include "diagnosis/details/after_reversals.hpp"
#include "diagnosis/details/baseline.hpp"
#include "diagnosis/details/candidates.hpp"
#include "diagnosis/details/extension_fit.hpp"
#include "diagnosis/details/left_out.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation {

namespace {

using details::num;

constexpr std::array<Cause, 7> kCandidates{
    Cause::kAsymmetry, Cause::kLoopShape, Cause::kRateDependence, Cause::kCreep,
    Cause::kDynamics,  Cause::kDelay,     Cause::kDrift};
// The causes that change the loop's shape: the play family's own extension (asymmetry) and the
// operator swapped for a Preisach plane (loop_shape).
bool is_shape(Cause c) { return c == Cause::kAsymmetry || c == Cause::kLoopShape; }
// The plane is named as the shape only where it predicts the held-out blocks this much better
// than the play family's own shape extension: a plane's hundreds of cells stand for a few plays
// and dead zones no better than they do themselves.
constexpr double kPlaneOverPlays = 1.1;
// A runner-up this close to the named cause's gain makes the verdict ambiguous.
constexpr double kMinCoherentShare = 0.5;
constexpr double kOneLoopBand = 0.03;  // of the input span: a reversal this close is at the end
constexpr double kAmbiguity = 0.9;
// Fewest held-out samples after the input's reversals that can tell a delay from a rate law.
constexpr std::size_t kMinReversalSamples = 10;
// Bins of the residual profiles.
constexpr std::size_t kTimeBins = 32, kLevelBins = 24, kRateBins = 24, kSinceBins = 16;
// Several records: an extension carries over when its geometric-mean gain on the records left
// out whole is at least half the named gain's margin (1.1 with min_gain 1.2) and it loses on no
// left-out record by more than this.
constexpr double kMaxLeftOutLoss = 0.95;
// A significant extension joins the named one when it lowers the joint model's held-out rms by
// at least 2 %.
constexpr double kMinJoinGain = 1.02;
// A cause after stronger ones is named when, added to them, it gains this much (or min_gain
// when lower): an effect beside a larger one gains little over the baseline on its own, and one
// whose own gain was mostly theirs (a rate law widening the loop as a delay does) adds little.
constexpr double kMinAddedGain = 1.1;
// What a cause after the first must add: kMinAddedGain, or min_gain when lower.
double added_gain_needed(const DiagnosisOptions& options) {
  return std::min(options.min_gain, kMinAddedGain);
}
// The baseline family "does not fit the device" when, fitted on the others, it predicts some
// record this many times worse than it predicts its own held-out blocks.
constexpr double kFamilyMismatch = 3.0;

using TestFunction = details::CandidateOutcome (*)(const details::CandidateContext&);

TestFunction test_of(Cause c) {
  switch (c) {
    case Cause::kAsymmetry:
      return details::test_asymmetry;
    case Cause::kLoopShape:
      return details::test_loop_shape;
    case Cause::kRateDependence:
      return details::test_rate_dependence;
    case Cause::kCreep:
      return details::test_creep;
    case Cause::kDynamics:
      return details::test_dynamics;
    case Cause::kDelay:
      return details::test_delay;
    case Cause::kDrift:
      return details::test_drift;
    case Cause::kNone:
      break;
  }
  return nullptr;
}

std::vector<ResidualProfile> residual_profiles(const details::DiagnosisRecord& r,
                                               std::span<const double> e,
                                               const details::InputEvents& ev) {
  std::vector<ResidualProfile> out;
  std::vector<unsigned char> scored(r.n);
  for (std::size_t k = 0; k < r.n; ++k) scored[k] = r.part[k] != details::kSkippedPart;
  out.push_back(details::binned_profile("time", "time [s]", r.t, e, scored,
                                        details::linear_edges(r.t.front(), r.t.back(), kTimeBins)));
  out.push_back(details::binned_profile("input", "input [" + r.units.input + "]", r.u, e, scored,
                                        details::linear_edges(r.u_lo, r.u_hi, kLevelBins)));
  std::vector<double> direction(r.n);
  std::vector<unsigned char> moving(r.n), smooth(r.n), after(r.n);
  std::vector<double> signed_e(r.n);
  double longest = 0.0;
  for (std::size_t k = 0; k < r.n; ++k) {
    direction[k] = ev.direction[k];
    moving[k] = scored[k] && ev.direction[k] != 0;
    smooth[k] = moving[k] && !ev.step[k] && !(k + 1 < r.n && ev.step[k + 1]);
    after[k] = scored[k] && ev.last_move[k] != 0 && ev.since_event_s[k] > 0.0;
    signed_e[k] = e[k] * ev.last_move[k];
    if (after[k]) longest = std::max(longest, ev.since_event_s[k]);
  }
  out.push_back(details::binned_profile("direction", "direction (-1 falling, +1 rising)", direction,
                                        e, moving, {-1.5, 0.0, 1.5}));
  out.push_back(details::binned_profile("rate", "input rate [" + r.units.input + "/s]", ev.rate, e,
                                        smooth,
                                        details::quantile_edges(ev.rate, smooth, kRateBins)));
  const double first = r.dt;
  out.push_back(details::binned_profile(
      "since_event",
      "time since the last reversal or step [s] (residual signed by the last input change)",
      ev.since_event_s, signed_e, after,
      details::log_edges(first, std::max(2.0 * first, longest), kSinceBins)));
  return out;
}

}  // namespace

std::string_view to_string(Cause cause) noexcept {
  switch (cause) {
    case Cause::kNone:
      return "none";
    case Cause::kAsymmetry:
      return "asymmetry";
    case Cause::kRateDependence:
      return "rate_dependence";
    case Cause::kCreep:
      return "creep";
    case Cause::kDynamics:
      return "dynamics";
    case Cause::kDelay:
      return "delay";
    case Cause::kDrift:
      return "drift";
    case Cause::kLoopShape:
      return "loop_shape";
  }
  return "none";
}

std::optional<Cause> cause_from_string(std::string_view name) noexcept {
  if (name == "none") return Cause::kNone;
  for (const Cause c : kCandidates) {
    if (to_string(c) == name) return c;
  }
  return std::nullopt;
}

std::span<const Cause> candidate_causes() noexcept { return kCandidates; }

bool DataSplit::is_heldout(std::size_t k) const noexcept {
  for (const auto& [b, e] : heldout) {
    if (k < b) return false;
    if (k < e) return true;
  }
  return false;
}

bool DataSplit::is_skipped(std::size_t k) const noexcept {
  for (const auto& [b, e] : skipped_ranges) {
    if (k < b) return false;
    if (k < e) return true;
  }
  return false;
}

ValidationScore validate_model(ActuatorModel model, std::span<const double> u,
                               std::span<const double> y, double dt) {
  if (u.size() != y.size() || u.size() < 2 || !(dt > 0.0)) {
    throw std::invalid_argument("validate_model: u and y need equal lengths >= 2 and dt > 0");
  }
  const std::vector<double> yhat = model.simulate(u, dt);
  ValidationScore v;
  v.skipped = details::startup_samples(u, u.size() / 4);
  v.samples = u.size() - v.skipped;
  const auto n = static_cast<double>(v.samples);
  for (std::size_t k = v.skipped; k < u.size(); ++k) v.offset += (y[k] - yhat[k]) / n;
  double square = 0.0;
  for (std::size_t k = v.skipped; k < u.size(); ++k) {
    const double e = y[k] - yhat[k] - v.offset;
    square += e * e;
    v.max_abs = std::max(v.max_abs, std::abs(e));
  }
  v.rmse = std::sqrt(square / n);
  return v;
}

std::string DataSplit::describe(double sample_period_s) const {
  std::string s = "record cut into " + std::to_string(blocks) + " equal blocks, " +
                  std::to_string(heldout.size()) + " interleaved ones held out (" +
                  num(100.0 * static_cast<double>(heldout_samples) / static_cast<double>(samples)) +
                  " % of " + std::to_string(samples) + " samples): t =";
  for (std::size_t i = 0; i < heldout.size(); ++i) {
    s += (i ? ", " : " ") + num(static_cast<double>(heldout[i].first) * sample_period_s) + "-" +
         num(static_cast<double>(heldout[i].second) * sample_period_s) + " s";
  }
  if (skipped > 0 && records > 1) {
    s += "; the start of each of the " + std::to_string(records) + " records (" +
         num(static_cast<double>(skipped) * sample_period_s) +
         " s in all, until its input has reached both its extremes) neither fitted nor scored";
  } else if (skipped > 0) {
    s += "; the first " + num(static_cast<double>(skipped) * sample_period_s) +
         " s (until the input has reached both its extremes) neither fitted nor scored";
  }
  return s + "; every model is fitted on the other blocks and simulated through the whole record";
}

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

namespace {

// Leave-one-record-out scores of every candidate's structure against the baseline's (several
// records only); marks the candidates that do not carry over and notes what the set shows.
void score_left_out(Diagnosis& d, const details::DiagnosisRecord& r,
                    const std::vector<details::RecordPart>& parts,
                    const details::ExtensionSpec& base,
                    const std::vector<details::ExtensionFit>& fits,
                    const DiagnosisOptions& options) {
  const details::LeftOutScorer scorer(r, parts, options);
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

std::string left_out_summary(const CandidateReport& c) {
  std::string s;
  for (const LeftOutScore& l : c.left_out) {
    s += (s.empty() ? "" : ", ") + l.record + " " + num(l.gain);
  }
  return s;
}

std::vector<std::size_t> starts_of(const std::vector<details::RecordPart>& parts) {
  std::vector<std::size_t> starts;
  starts.reserve(parts.size());
  for (const details::RecordPart& p : parts) starts.push_back(p.begin);
  return starts;
}

// Sensor offsets differ between runs: each record's output is shifted onto the first's by its
// mean residual against the baseline fitted on all (twice: the fit moves with the shifts).
// Returns the shift of each record (0 for the first) [output unit]; y is shifted in place.
std::vector<double> align_offsets(std::span<const double> t, std::span<const double> u,
                                  std::vector<double>& y, const DiagnosisOptions& options,
                                  const std::vector<details::RecordPart>& parts) {
  const std::vector<std::size_t> starts = starts_of(parts);
  std::vector<double> total(parts.size(), 0.0);
  for (int iteration = 0; iteration < 2; ++iteration) {
    const details::DiagnosisRecord r = details::make_diagnosis_record(t, u, y, options, starts);
    std::vector<double> prediction;
    if (options.baseline && options.baseline->valid()) {
      prediction = ActuatorModel(*options.baseline).simulate(u, r.dt);
    } else {
      prediction = details::fit_pi_baseline(r).fit.prediction;
    }
    std::vector<double> mean(parts.size(), 0.0);
    for (std::size_t i = 0; i < parts.size(); ++i) {
      std::size_t n = 0;
      for (std::size_t k = parts[i].begin; k < parts[i].end; ++k) {
        if (r.part[k] == details::kSkippedPart) continue;
        mean[i] += y[k] - prediction[k], ++n;
      }
      mean[i] /= static_cast<double>(std::max<std::size_t>(n, 1));
    }
    for (std::size_t i = 1; i < parts.size(); ++i) {
      const double shift = mean[i] - mean[0];
      for (std::size_t k = parts[i].begin; k < parts[i].end; ++k) y[k] -= shift;
      total[i] += shift;
    }
  }
  return total;
}

/// The order causes are named in: by gain, but creep before drift and before rate dependence.
/// Creep and drift both explain a slow change of the output; creep is the part the input
/// explains, the drift what is left, and a drift's pieces, fitted across the held-out blocks
/// between them, follow a slow creep at least as well as the creep lags that predict it. A rate
/// law's widening, where the filtered rate decays after a change, trails it as creep does; its
/// own gain beside a stronger cause (a delay) is mostly that cause's, so it would be tried
/// first and take the creep's share.
bool ranks_before(Cause a, double gain_a, Cause b, double gain_b) {
  for (const Cause later : {Cause::kDrift, Cause::kRateDependence}) {
    if (a == Cause::kCreep && b == later) return true;
    if (a == later && b == Cause::kCreep) return false;
  }
  return gain_a > gain_b;
}

/// A cause tested again on top of the loop's shape (the asymmetry extension).
struct OnTopOfShape {
  Cause cause = Cause::kNone;
  details::CandidateOutcome outcome;  ///< its fit holds the shape and the cause
  double gain = 0.0;                  ///< shape's held-out rms / this held-out rms
  bool significant = false;           ///< its statistic, read from the shape's residual

  bool counts(const DiagnosisOptions& options) const {
    return significant && gain >= options.min_gain;
  }
};

/// y - prediction over the record [output unit].
std::vector<double> residual_of(const details::DiagnosisRecord& r,
                                std::span<const double> prediction) {
  std::vector<double> e(r.n);
  for (std::size_t k = 0; k < r.n; ++k) e[k] = r.y[k] - prediction[k];
  return e;
}

// What the other causes are judged against when the first is named beyond the shape.
std::string shape_name(Cause shape) {
  return "the loop's shape (" + std::string(to_string(shape)) + ")";
}

/// Every other candidate that carries over (the other shape aside), tested again with the shape
/// extension's fit as its baseline (its statistic read from that fit's residual), in candidate
/// order; a candidate the designs cannot fit together with the shape is left out.
std::vector<OnTopOfShape> beyond_shape(const Diagnosis& d, const details::DiagnosisRecord& r,
                                       const std::vector<details::ExtensionFit>& fits,
                                       const details::InputEvents& ev, Cause shape_cause,
                                       std::vector<std::string>& notes) {
  std::size_t shape = 0;
  while (d.candidates[shape].cause != shape_cause) ++shape;
  const details::ExtensionFit& base = fits[shape];
  const std::vector<double> residual = residual_of(r, base.prediction);
  const std::vector<ResidualProfile> profiles = residual_profiles(r, residual, ev);
  const FrequencyResponse response =
      details::frequency_response(base.prediction, r.y, r.dt, d.noise_rms);
  const details::CandidateContext ctx{r,  base.spec, base,     base.prediction, residual,
                                      ev, profiles,  response, d.noise_rms};
  std::vector<OnTopOfShape> out;
  std::string tried;
  for (const CandidateReport& c : d.candidates) {
    if (is_shape(c.cause) || !c.carries_over) continue;
    try {
      details::CandidateOutcome o = test_of(c.cause)(ctx);
      if (!(o.fit.heldout.rmse > 0.0)) continue;
      const double gain = base.heldout.rmse / o.fit.heldout.rmse;
      const bool significant = o.statistic >= o.threshold;
      tried += std::string(tried.empty() ? "" : ", ") + std::string(to_string(c.cause)) + " " +
               num(gain) + (significant ? "" : " (not significant)");
      out.push_back(OnTopOfShape{c.cause, std::move(o), gain, significant});
    } catch (const std::exception&) {
      // A combination the designs cannot fit is left out.
    }
  }
  if (!tried.empty()) {
    notes.push_back("on top of " + shape_name(shape_cause) + ", the other causes gain: " + tried);
  }
  return out;
}

/// What naming the causes beyond the first and joining their extensions need.
struct Naming {
  const details::DiagnosisRecord& r;
  const std::vector<details::ExtensionFit>& fits;  ///< each candidate's, in candidate order
  const details::InputEvents& ev;
  const std::vector<ResidualProfile>& profiles;  ///< of the reference residual
  const FrequencyResponse& response;             ///< of the reference prediction
  const DiagnosisOptions& options;
  double reference = 0.0;      ///< held-out rms the candidates' gains are judged against
  std::string reference_name;  ///< what that is: the baseline, or the given model refitted
  const std::vector<OnTopOfShape>& on_shape;
  const OnTopOfShape* beyond = nullptr;  ///< the first cause, named beyond the shape
  double reference_delay_samples = 0.0;  ///< the reference's own input delay [samples]
  Cause shape = Cause::kAsymmetry;       ///< the shape cause `on_shape` was tested on
};

/// The extended model as the causes after the first join it.
struct Joint {
  details::ExtensionFit fit;       ///< the joint model so far, predicted and scored
  std::string named_extension;     ///< what the first cause's extension (and the shape's) adds
  std::vector<std::string> added;  ///< what each part joined after it adds
};

/// The statistic of a cause that is read again on a joint model's residual (drift: the time
/// profile; creep: the hold profile; the shape: the level profile), without its fit.
double retest_statistic(Cause cause, const details::CandidateContext& c) {
  if (cause == Cause::kAsymmetry) return c.profile("input").explained;
  return cause == Cause::kCreep ? details::creep_statistic(c) : c.profile("time").explained;
}

/// A cause after the first, tried on top of the joint model.
struct Next {
  std::size_t index;  ///< in Diagnosis::candidates
  double gain;        ///< over the reference (or the shape): the gain it is ranked by
  bool contender;     ///< it may be named; else it may only join the extended model
  /// Not significant on the reference's residual: its statistic is read again on the joint
  /// model's, and it is a contender when significant there.
  bool retest = false;
};

double quadrature_difference(double before, double after) {
  return std::sqrt(std::max(0.0, before * before - after * after));
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) {
    s += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  }
  return s;
}

/// Why a candidate is not named: what it adds to the model holding `before` is within the noise.
std::string within_noise(const std::string& before, double added_rms, double allowance,
                         const std::string& unit) {
  return "within the noise of " + before + ": added to the model holding " + before +
         ", it explains " + num(added_rms) + " " + unit +
         " rms more of the held-out error, less than the " + num(allowance) + " " + unit +
         " the noise allows";
}

// Calls the options' progress callback, when there is one.
void report(const DiagnosisOptions& options, double fraction, const std::string& what) {
  if (options.progress) options.progress(fraction, what);
}

// The plane and the play family's own shape extension both significant, and the plane not
// kPlaneOverPlays better on the held-out blocks.
bool plane_outdone(const Diagnosis& d) {
  const CandidateReport* plane = d.candidate(Cause::kLoopShape);
  const CandidateReport* plays = d.candidate(Cause::kAsymmetry);
  return plane != nullptr && plays != nullptr && plane->significant && plays->significant &&
         plane->heldout.rmse * kPlaneOverPlays > plays->heldout.rmse;
}

// Where cause c stands in d.candidates (it is there).
std::size_t index_of(const Diagnosis& d, Cause c) {
  std::size_t i = 0;
  while (d.candidates[i].cause != c) ++i;
  return i;
}

// Cause c tested on top of the shape, or nullptr when it was not.
const OnTopOfShape* on_shape_of(const Naming& x, Cause c) {
  for (const OnTopOfShape& o : x.on_shape) {
    if (o.cause == c) return &o;
  }
  return nullptr;
}

// The extended model's model, errors and prediction from a joint fit (not its description).
void set_extended(Diagnosis& d, const details::ExtensionFit& joint) {
  d.extended = joint.model;
  d.extended_fit = joint.fit;
  d.extended_heldout = joint.heldout;
  d.extended_prediction = joint.prediction;
}

// Names d.cause and makes its extension (on top of the shape when it is named beyond it) the
// extended model so far.
Joint name_first_cause(Diagnosis& d, const Naming& x) {
  CandidateReport& w = d.candidates[index_of(d, d.cause)];
  w.named = true;
  w.not_named.clear();
  Joint joint;
  joint.named_extension = w.extension;
  if (x.beyond) {
    // The named cause on top of the shape: both are parts of the extended model.
    joint.fit = x.beyond->outcome.fit;
    joint.named_extension = x.beyond->outcome.extension + "; " + d.candidate(x.shape)->extension;
    d.extended_parts = {std::string(to_string(d.cause)), std::string(to_string(x.shape))};
    const double shape_rms = d.candidate(x.shape)->heldout.rmse;
    d.causes = {{d.cause, x.beyond->gain, joint.fit.heldout.rmse, shape_name(x.shape),
                 x.beyond->gain, quadrature_difference(shape_rms, joint.fit.heldout.rmse),
                 x.beyond->outcome.evidence, x.beyond->outcome.extension}};
  } else {
    joint.fit = x.fits[index_of(d, d.cause)];
    d.extended_parts = {std::string(to_string(d.cause))};
    const double gain = x.reference / w.heldout.rmse;
    d.causes = {{d.cause, gain, w.heldout.rmse, x.reference_name, gain,
                 quadrature_difference(x.reference, w.heldout.rmse), w.evidence, w.extension}};
  }
  set_extended(d, joint.fit);
  d.extended_description =
      details::describe_model(joint.fit.model) + " (" + joint.named_extension + ")";
  return joint;
}

// The others, the shape first, then strongest first. A contender may be named: significant and
// carrying over (when the first is named beyond the shape, significant on top of the shape). Every
// significant extension that carries over (drift aside: never extrapolated) may join the extended
// model. Says why a candidate that carries over is no contender beyond the shape.
std::vector<Next> next_causes(Diagnosis& d, const Naming& x) {
  std::vector<Next> order;
  const auto in_parts = [&d](Cause c) {
    return std::find(d.extended_parts.begin(), d.extended_parts.end(), to_string(c)) !=
           d.extended_parts.end();
  };
  // One shape at a time: the plane's search chose its output map, and the plays' dead zones are
  // not swapped for a plane that did not gain over them.
  const bool shape_held = in_parts(Cause::kAsymmetry) || in_parts(Cause::kLoopShape);
  for (std::size_t i = 0; i < d.candidates.size(); ++i) {
    CandidateReport& c = d.candidates[i];
    if (in_parts(c.cause)) continue;
    if (shape_held && is_shape(c.cause)) {
      // Eligible (no other reason given): the shape it would add is held already.
      if (c.not_named.empty()) {
        c.not_named = "the extended model holds the loop's shape by " +
                      std::string(in_parts(Cause::kLoopShape) ? "the plane (loop_shape)"
                                                              : "its plays (asymmetry)");
      }
      continue;
    }
    if (c.cause == Cause::kLoopShape && plane_outdone(d)) continue;
    const OnTopOfShape* s = x.beyond ? on_shape_of(x, c.cause) : nullptr;
    const bool contender = c.carries_over && (x.beyond ? s && s->significant : c.significant);
    if (x.beyond && c.carries_over && !contender) {
      c.not_named = !s ? "it could not be fitted on top of " + shape_name(x.shape)
                       : "on top of " + shape_name(x.shape) +
                             " its statistic is not significant (gain " + num(s->gain) + ")";
    }
    const bool joins = c.significant && c.carries_over && c.cause != Cause::kDrift;
    // A drift's and a creep's statistics (the residual's time and hold profiles) are swamped by a
    // stronger cause the reference (or the shape) misses, a delay or a resonance erring on every
    // move: read again on what the causes before them leave. So is the shape's (the level
    // profile) behind a delay or a resonance named first. Behind a rate law it is not read again:
    // on top of both, a creep or a drift took the law's misfit (1.12-1.19x added, none hidden).
    const bool lag_first = d.cause == Cause::kDelay || d.cause == Cause::kDynamics;
    const bool swamped = c.cause == Cause::kDrift || c.cause == Cause::kCreep ||
                         (c.cause == Cause::kAsymmetry && lag_first);
    const bool retest = swamped && c.carries_over && !contender && (!x.beyond || s != nullptr);
    const double gain = s ? s->gain : c.heldout.rmse > 0.0 ? x.reference / c.heldout.rmse : 0.0;
    if (contender || joins || retest) order.push_back({i, gain, contender, retest});
  }
  // The shape first: it is the base's own, and what a later cause adds is judged on top of it
  // (beside a delay, the shape's error left in both dilutes a rate law's gain to 1.07x). Then the
  // causes significant on the reference's residual, and those read again last: a creep read again
  // before a rate law takes the law's filtered tail.
  std::sort(order.begin(), order.end(), [&d](const Next& a, const Next& b) {
    const bool shape_a = is_shape(d.candidates[a.index].cause);
    const bool shape_b = is_shape(d.candidates[b.index].cause);
    if (shape_a != shape_b) return shape_a;
    if (a.retest != b.retest) return b.retest;
    return ranks_before(d.candidates[a.index].cause, a.gain, d.candidates[b.index].cause, b.gain);
  });
  return order;
}

// Names a contender whose outcome `o` on top of the joint model (held-out rms joint_rms, holding
// `before`) gains kMinAddedGain (or min_gain when lower) added to the stronger causes and is not
// within their noise; else says why not.
void judge_contender(Diagnosis& d, const Naming& x, const Next& next,
                     const details::CandidateOutcome& o, double joint_rms,
                     const std::string& before) {
  CandidateReport& c = d.candidates[next.index];
  const DiagnosisOptions& options = x.options;
  const std::string unit = x.r.units.output;
  const double rms = o.fit.heldout.rmse;
  const double added_rms = quadrature_difference(joint_rms, rms);
  const double added_gain = rms > 0.0 ? joint_rms / rms : 0.0;
  const double needed = added_gain_needed(options);
  const OnTopOfShape* s = x.beyond ? on_shape_of(x, c.cause) : nullptr;
  if (added_rms < d.noise_allowance_rms) {
    c.not_named = within_noise(before, added_rms, d.noise_allowance_rms, unit);
  } else if (next.gain < options.min_gain && added_gain < needed) {
    c.not_named = "its held-out gain " + num(next.gain) + (s ? " over the shape" : "") +
                  " is below " + num(options.min_gain) + ", and added to the model holding " +
                  before + " it gains " + num(added_gain) + ", below " + num(needed);
  } else if (added_gain < needed) {
    // Its own gain was mostly the stronger causes' (a rate law widening the loop as a delay
    // does): added to them it explains little.
    c.not_named = "its held-out gain " + num(next.gain) + (s ? " over the shape" : "") +
                  " is mostly that of " + before + ": added to the model holding it, " +
                  num(added_gain) + ", below " + num(needed);
  } else {
    d.causes.push_back({c.cause, next.gain, s ? s->outcome.fit.heldout.rmse : c.heldout.rmse,
                        s ? shape_name(x.shape) : x.reference_name, added_gain, added_rms,
                        // A retested cause's evidence is read on the joint model's residual.
                        s && !next.retest ? s->outcome.evidence : c.evidence,
                        s ? s->outcome.extension : c.extension});
    c.named = true;
    c.not_named.clear();
  }
}

// A test's context with the joint model so far as its baseline: `residual` is y - its
// prediction, `profiles` the residual profiles the statistic is read from.
details::CandidateContext on_joint(const Diagnosis& d, const Naming& x, const Joint& joint,
                                   std::span<const double> residual,
                                   const std::vector<ResidualProfile>& profiles) {
  return {x.r,
          joint.fit.spec,
          joint.fit,
          joint.fit.prediction,
          residual,
          x.ev,
          profiles,
          x.response,
          d.noise_rms,
          x.reference_delay_samples,
          added_gain_needed(x.options)};
}

// The next cause's test again, its baseline the joint model so far (its parameters, a
// resonance, a delay, are found on what the joint model leaves): a contender is judged for
// naming, and its part joins the joint model when it lowers the held-out rms by kMinJoinGain.
// True when it joined.
bool try_next_cause(Diagnosis& d, const Naming& x, const Next& next, Joint& joint) {
  CandidateReport& c = d.candidates[next.index];
  const std::string before = joined(d.extended_parts);
  const std::vector<double> joint_residual = residual_of(x.r, joint.fit.prediction);
  const std::vector<ResidualProfile> joint_profiles =
      next.retest ? residual_profiles(x.r, joint_residual, x.ev) : std::vector<ResidualProfile>{};
  const details::CandidateContext jc =
      on_joint(d, x, joint, joint_residual, next.retest ? joint_profiles : x.profiles);
  // A retested statistic, read before the fit: not significant there either, it is not tried.
  if (next.retest && retest_statistic(c.cause, jc) < c.threshold) return false;
  try {
    details::CandidateOutcome o = test_of(c.cause)(jc);
    if (next.retest) {
      if (o.statistic < o.threshold) return false;
      // The shape read again changes the family every later cause is judged in: it must gain
      // min_gain on what the first leaves, as the first must over the reference (beside a creep
      // and a delay on a symmetric PI, a level profile of 0.17 gained 1.12x, and a rate law then
      // added 1.26x on top of it).
      const double added =
          o.fit.heldout.rmse > 0.0 ? joint.fit.heldout.rmse / o.fit.heldout.rmse : 0.0;
      if (c.cause == Cause::kAsymmetry && added < x.options.min_gain) {
        c.not_named = "read again on what the model holding " + before + " leaves, its statistic " +
                      num(o.statistic) + " is significant, but it gains " + num(added) +
                      " added to it, below " + num(x.options.min_gain);
        return false;
      }
      // Significant on what the causes before it leave: judged on that statistic.
      c.statistic = o.statistic;
      c.significant = true;
      c.evidence = o.evidence + ", on what the model holding " + before + " leaves";
      judge_contender(d, x, {next.index, next.gain, true, true}, o, joint.fit.heldout.rmse, before);
    } else if (next.contender) {
      judge_contender(d, x, next, o, joint.fit.heldout.rmse, before);
    }
    // Less than kMinJoinGain only adds parameters, which the inverse extrapolates (a rate law
    // beyond the record's rates).
    if (c.cause != Cause::kDrift && o.fit.heldout.rmse * kMinJoinGain < joint.fit.heldout.rmse) {
      joint.fit = std::move(o.fit);
      joint.added.push_back(o.extension);
      d.extended_parts.push_back(std::string(to_string(c.cause)));
      return true;
    }
  } catch (const std::exception&) {
    // A combination the designs cannot fit is left out.
    if (next.contender) c.not_named = "it could not be fitted on top of " + before;
  }
  return false;
}

// A delay named first was found on the baseline, which misses the loop's shape: off by a
// sample at 20 kHz, the lag left is what a rate law then takes (1.46x added, none hidden). With
// the shape joined, the delay is found again on top of both and kept where it predicts better.
void find_delay_again(const Diagnosis& d, const Naming& x, Joint& joint) {
  const std::vector<double> residual = residual_of(x.r, joint.fit.prediction);
  try {
    details::CandidateOutcome o = details::test_delay(on_joint(d, x, joint, residual, x.profiles));
    if (o.statistic < o.threshold || !(o.fit.heldout.rmse < joint.fit.heldout.rmse)) return;
    joint.fit = std::move(o.fit);
    joint.added.push_back(o.extension + ", found again on top of the loop's shape");
  } catch (const std::exception&) {
    // The delay found first stays.
  }
}

// The shape, judged on top of the first cause: the first alone against both together.
void judge_shape(Diagnosis& d, const Naming& x) {
  CandidateReport& shape = d.candidates[index_of(d, x.shape)];
  const double alone = d.candidate(d.cause)->heldout.rmse;
  const double both = x.beyond->outcome.fit.heldout.rmse;
  const double added_rms = quadrature_difference(alone, both);
  if (added_rms >= d.noise_allowance_rms) {
    d.causes.push_back({x.shape, x.reference / shape.heldout.rmse, shape.heldout.rmse,
                        x.reference_name, alone / both, added_rms, shape.evidence,
                        shape.extension});
    shape.named = true;
  } else {
    shape.not_named = within_noise(std::string(to_string(d.cause)), added_rms,
                                   d.noise_allowance_rms, x.r.units.output);
  }
}

// The causes named after the first, each with what it adds, appended to the verdict.
void append_also_named(Diagnosis& d, Cause shape, const std::string& unit) {
  d.verdict += ". Also named, each adding more than the noise allows (" +
               num(d.noise_allowance_rms) + " " + unit + " rms) to the causes before it: ";
  for (std::size_t i = 1; i < d.causes.size(); ++i) {
    const NamedCause& n = d.causes[i];
    // The shape, last, is judged on top of the first cause alone.
    const std::string to = is_shape(n.cause) && i > 1
                               ? std::string(to_string(d.causes.front().cause))
                               : std::string("those");
    d.verdict += (i > 1 ? ", " : "") + std::string(to_string(n.cause)) + " (gain " + num(n.gain) +
                 (n.against == shape_name(shape) ? " over the shape" : "") + ", " +
                 num(n.added_gain) + " added to ";
    d.verdict += to;
    d.verdict += ", " + num(n.added_rms) + " " + unit + " rms)";
  }
}

/// d.cause (not none) and the candidates' not_named set for the candidates that cannot be named:
/// names every other cause (Diagnosis::causes) and builds the extended model, the named cause's
/// extension joined by every other significant one that lowers the held-out error on top of it
/// (Diagnosis::extended_parts).
void name_causes_and_extend(Diagnosis& d, const Naming& x) {
  Joint joint = name_first_cause(d, x);
  const std::vector<Next> order = next_causes(d, x);
  report(x.options, 0.97, "naming the other causes and joining the significant extensions");
  for (const Next& next : order) {
    const bool part_joined = try_next_cause(d, x, next, joint);
    if (part_joined && is_shape(d.candidates[next.index].cause) && d.cause == Cause::kDelay) {
      find_delay_again(d, x, joint);
    }
  }
  // The shape read again joined first, on top of the first cause alone; it is listed last, as
  // when the first cause is named beyond it (alone, beside the cause that hid it, it gains little
  // over the baseline: its own gain does not rank it).
  const auto shape = std::find_if(d.causes.begin() + 1, d.causes.end(),
                                  [](const NamedCause& n) { return is_shape(n.cause); });
  if (shape != d.causes.end()) std::rotate(shape, shape + 1, d.causes.end());
  if (!joint.added.empty()) {
    set_extended(d, joint.fit);
    d.extended_description =
        details::describe_model(joint.fit.model) + " (" + joint.named_extension;
    for (const std::string& a : joint.added) d.extended_description += "; " + a;
    d.extended_description += ", refitted jointly)";
  }
  // The parts joined on the plane were fitted with its cells' shape fixed: the cells are refitted
  // beside them.
  const bool on_plane = std::find(d.extended_parts.begin(), d.extended_parts.end(),
                                  to_string(Cause::kLoopShape)) != d.extended_parts.end();
  if (on_plane && (x.beyond || !joint.added.empty())) {
    if (auto free = details::refit_plane_cells(x.r, joint.fit)) {
      const std::size_t model_part = details::describe_model(joint.fit.model).size();
      d.extended_description =
          details::describe_model(free->model) + d.extended_description.substr(model_part);
      set_extended(d, *free);
    }
  }
  if (x.beyond) judge_shape(d, x);
  if (d.causes.size() > 1) append_also_named(d, x.shape, x.r.units.output);
}

/// The baseline structure every extension starts from, and that structure fitted here.
struct Baseline {
  details::ExtensionSpec spec;
  details::ExtensionFit fit;
};

// The baseline (the given model, or a classical PI identified here) into d: its description,
// prediction and errors; with a given model also the refit's held-out error.
Baseline fit_baseline(Diagnosis& d, const details::DiagnosisRecord& r,
                      const DiagnosisOptions& options) {
  Baseline base;
  if (options.baseline) {
    if (!options.baseline->valid())
      throw std::invalid_argument("the given baseline model is empty");
    d.baseline_given = true;
    d.baseline = *options.baseline;
    ActuatorModel sim(d.baseline);
    d.baseline_prediction = sim.simulate(r.u, r.dt);
    d.baseline_description = "given model: " + details::describe_model(d.baseline);
    base.spec = details::spec_of_model(d.baseline, r);
    base.fit = details::fit_extension(r, base.spec);
    d.refit_heldout = base.fit.heldout;
  } else {
    details::PiBaseline b = details::fit_pi_baseline(r);
    d.baseline = b.fit.model;
    d.baseline_prediction = std::move(b.fit.prediction);
    d.baseline_description = b.description;
    base.spec = b.finest_spec;
    base.fit = std::move(b.finest_fit);
  }
  const details::SplitErrors be = details::split_errors(r, d.baseline_prediction);
  d.baseline_fit = be.fit;
  d.baseline_heldout = be.heldout;
  return base;
}

// The baseline's residual y - prediction [output unit]; sets d's noise rms, how it was
// estimated and the input's period.
std::vector<double> residual_and_noise(Diagnosis& d, const details::DiagnosisRecord& r) {
  std::vector<double> e = residual_of(r, d.baseline_prediction);
  d.noise_rms = details::noise_rms(e);
  d.noise_source = "second differences of the baseline residual";
  d.input_period = details::input_period(r.u);
  if (d.input_period > 0) {
    const double periodic = details::periodic_noise_rms(r.y, d.input_period);
    if (periodic > 0.0 && periodic < d.noise_rms) {
      d.noise_rms = periodic;
      d.noise_source = "period-to-period difference of the output (the input repeats every " +
                       std::to_string(d.input_period) + " samples)";
    }
  }
  return e;
}

// d.coherent_share from d.frequency_response (left as it is when the output has no power).
void set_coherent_share(Diagnosis& d) {
  const FrequencyResponse& fr = d.frequency_response;
  double coherent = 0.0, total = 0.0;
  for (std::size_t i = 0; i < fr.coherence.size(); ++i) {
    coherent += fr.coherence[i] * fr.output_psd[i];
    total += fr.output_psd[i];
  }
  if (total > 0.0) d.coherent_share = coherent / total;
}

// A given model whose structure, refitted here, gains min_gain: its parameters do not match.
bool given_model_stale(const Diagnosis& d, const DiagnosisOptions& options) {
  return d.refit_heldout && d.refit_heldout->rmse > 0.0 &&
         d.baseline_heldout.rmse / d.refit_heldout->rmse >= options.min_gain;
}

/// The prediction whose residual the candidates' statistics read.
struct Reference {
  std::vector<double> residual;  ///< y - prediction [output unit]
  std::vector<ResidualProfile> profiles;
  FrequencyResponse response;
  std::span<const double> prediction;
};

// The baseline's (its residual e, profiles and response), or the refit's when a given model no
// longer matches this record.
Reference reference_of(const Diagnosis& d, const details::DiagnosisRecord& r,
                       const details::ExtensionFit& base_fit, const details::InputEvents& ev,
                       std::vector<double> e, const DiagnosisOptions& options) {
  Reference ref{std::move(e), d.profiles, d.frequency_response, d.baseline_prediction};
  if (given_model_stale(d, options)) {
    ref.residual = residual_of(r, base_fit.prediction);
    ref.profiles = residual_profiles(r, ref.residual, ev);
    ref.response = details::frequency_response(base_fit.prediction, r.y, r.dt, d.noise_rms);
    ref.prediction = base_fit.prediction;
  }
  return ref;
}

// Tests every candidate against the context's reference into d.candidates; returns each one's
// extension fit, in candidate order (for the joint extended model).
std::vector<details::ExtensionFit> test_candidates(Diagnosis& d,
                                                   const details::CandidateContext& ctx,
                                                   const DiagnosisOptions& options) {
  std::vector<details::ExtensionFit> fits;
  for (std::size_t i = 0; i < kCandidates.size(); ++i) {
    const Cause c = kCandidates[i];
    report(options, 0.25 + 0.7 * static_cast<double>(i) / kCandidates.size(),
           "testing " + std::string(to_string(c)));
    details::CandidateOutcome o = test_of(c)(ctx);
    fits.push_back(o.fit);
    CandidateReport rep;
    rep.cause = c;
    rep.statistic = o.statistic;
    rep.threshold = o.threshold;
    rep.significant = o.statistic >= o.threshold;
    rep.evidence = std::move(o.evidence);
    rep.extension = std::move(o.extension);
    rep.model = std::move(o.fit.model);
    rep.fit = o.fit.fit;
    rep.heldout = o.fit.heldout;
    rep.gain = rep.heldout.rmse > 0.0 ? d.baseline_heldout.rmse / rep.heldout.rmse : 0.0;
    rep.drift = std::move(o.fit.drift);
    rep.prediction = std::move(o.fit.prediction);
    d.candidates.push_back(std::move(rep));
  }
  return fits;
}

/// What the verdict and the notes are decided on.
struct Decision {
  double reference = 0.0;  ///< held-out rms the gains are judged against: baseline or refit
  bool at_floor = false;   ///< the baseline's held-out error is at the noise floor
  std::vector<const CandidateReport*> eligible;  ///< may be named, largest gain first
  std::vector<OnTopOfShape> on_shape;            ///< the other causes on top of the shape
  const OnTopOfShape* beyond = nullptr;          ///< the strongest of those that counts
  Cause shape = Cause::kAsymmetry;               ///< the eligible shape cause on_shape holds
  const CandidateReport* best_any = nullptr;     ///< the largest gain of all
};

// The candidates that may be named (significant, min_gain over the reference, carrying over),
// largest gain first; says why each other one is not.
std::vector<const CandidateReport*> eligible_candidates(Diagnosis& d, const Decision& decision,
                                                        const DiagnosisOptions& options) {
  std::vector<const CandidateReport*> eligible;
  for (CandidateReport& c : d.candidates) {
    const double gain = c.heldout.rmse > 0.0 ? decision.reference / c.heldout.rmse : 0.0;
    if (!c.significant) {
      c.not_named =
          "its statistic " + num(c.statistic) + " is below its threshold " + num(c.threshold);
    } else if (gain < options.min_gain) {
      c.not_named = "its held-out gain " + num(gain) + " is below " + num(options.min_gain);
    } else if (c.carries_over) {
      eligible.push_back(&c);
    } else {
      c.not_named =
          "it does not carry over to the records left out whole (gain " + left_out_summary(c) + ")";
      d.notes.push_back(std::string(to_string(c.cause)) + " does not carry over: it gains " +
                        num(c.gain) +
                        "x on the held-out blocks, but fitted on the other records it "
                        "predicts each record left out whole at gain " +
                        left_out_summary(c) + "; not named");
    }
    if (decision.at_floor) c.not_named = "the baseline's held-out error is at the noise floor";
  }
  std::sort(eligible.begin(), eligible.end(),
            [](const CandidateReport* a, const CandidateReport* b) { return a->gain > b->gain; });
  return eligible;
}

// The plane, eligible beside the play family's own shape extension (asymmetry), is left out
// unless it predicts the held-out blocks kPlaneOverPlays better; it is not tried later either.
void prefer_the_plays_shape(Diagnosis& d, Decision& decision) {
  if (!plane_outdone(d)) return;
  auto& eligible = decision.eligible;
  const auto plane = std::find_if(eligible.begin(), eligible.end(), [](const CandidateReport* r) {
    return r->cause == Cause::kLoopShape;
  });
  if (plane == eligible.end()) return;
  CandidateReport& c = d.candidates[index_of(d, Cause::kLoopShape)];
  c.not_named = "the play family's own shape (asymmetry, held-out rms " +
                num(d.candidate(Cause::kAsymmetry)->heldout.rmse) +
                ") holds the loop about as well (" + num(c.heldout.rmse) +
                "); the plane must gain " + num(kPlaneOverPlays) + "x over it";
  eligible.erase(plane);
}

// A delay and a rate law both lag a ramp, and on a coarse record gain about as much (a 1-sample
// delay at 100 Hz: the delay 1.79x, a thresholds law 1.80x). Right after a reversal they differ:
// for its length a delay carries the output on in the old direction, a rate law's widened
// thresholds hold it. When a rate law is eligible first and a delay within kAmbiguity of it
// predicts the held-out samples there better (by more than the noise allows), the delay is named
// first. Only that way: a law named first takes a delay's lag into its widening, and the delay
// then adds nothing, while on top of a delay the rate candidate tries the delay a sample less.
void order_rate_and_delay(Diagnosis& d, Decision& decision, const details::DiagnosisRecord& r,
                          const details::InputEvents& ev) {
  std::vector<const CandidateReport*>& eligible = decision.eligible;
  if (eligible.size() < 2 || eligible[0]->cause != Cause::kRateDependence ||
      eligible[1]->cause != Cause::kDelay || eligible[1]->gain < kAmbiguity * eligible[0]->gain) {
    return;
  }
  const CandidateReport& law = *eligible[0];
  const CandidateReport& delay = *eligible[1];
  const std::size_t window = std::max<std::size_t>(1, delay.model.delay_samples());
  const details::WindowError law_error =
      details::after_reversals_error(r, ev, law.prediction, window);
  const details::WindowError delay_error =
      details::after_reversals_error(r, ev, delay.prediction, window);
  if (law_error.samples < kMinReversalSamples) return;
  const bool delay_first =
      delay_error.rms < law_error.rms &&
      quadrature_difference(law_error.rms, delay_error.rms) >= d.noise_allowance_rms;
  const std::string unit = r.units.output;
  d.notes.push_back(
      "rate_dependence and delay gain about as much (" + num(law.gain) + " and " + num(delay.gain) +
      "); they differ after the input's reversals, where a delay carries the "
      "output on in the old direction and a rate law holds it: over the " +
      std::to_string(window) + (window == 1 ? " sample" : " samples") + " after each (" +
      std::to_string(law_error.samples) + " held out), the delay predicts them to " +
      num(delay_error.rms) + " " + unit + " rms, the rate law to " + num(law_error.rms) + " " +
      unit + (delay_first ? ": the delay is named first" : ": the rate law stays first"));
  if (delay_first) std::swap(eligible[0], eligible[1]);
}

// The loop's shape first. A classical PI follows neither a bent loop (a Preisach density, a
// saturating top) nor an asymmetric one, and what it misses there inflates every other
// candidate's gain: when the shape (asymmetry) is eligible, the other causes are tested again
// on top of it (on_shape) and the strongest that counts is named beyond it (beyond).
void test_on_shape(Diagnosis& d, const details::DiagnosisRecord& r,
                   const std::vector<details::ExtensionFit>& fits, const details::InputEvents& ev,
                   const DiagnosisOptions& options, Decision& decision) {
  const auto shape = std::find_if(decision.eligible.begin(), decision.eligible.end(),
                                  [](const CandidateReport* c) { return is_shape(c->cause); });
  if (shape == decision.eligible.end() || decision.at_floor) return;
  decision.shape = (*shape)->cause;
  report(options, 0.955, "testing the other causes on top of the loop's shape");
  decision.on_shape = beyond_shape(d, r, fits, ev, decision.shape, d.notes);
  for (const OnTopOfShape& o : decision.on_shape) {
    if (o.counts(options) &&
        (!decision.beyond ||
         ranks_before(o.cause, o.gain, decision.beyond->cause, decision.beyond->gain))) {
      decision.beyond = &o;
    }
  }
}

// d.cause and the verdict: none at the noise floor or without an eligible candidate, else the
// cause named beyond the shape, else the eligible one of the largest gain.
void decide_cause(Diagnosis& d, const Decision& decision, const DiagnosisOptions& options,
                  const std::string& unit) {
  const CandidateReport* best_any = decision.best_any;
  if (decision.at_floor) {
    d.cause = Cause::kNone;
    d.verdict = "none: the baseline's held-out rms error " + num(d.baseline_heldout.rmse) + " " +
                unit + " is at the noise floor (noise rms " + num(d.noise_rms) + " " + unit +
                "); there is nothing left to explain";
  } else if (decision.eligible.empty()) {
    d.cause = Cause::kNone;
    d.verdict = "none: no candidate lowers the held-out error by " + num(options.min_gain) +
                "x with a significant statistic (best: " + std::string(to_string(best_any->cause)) +
                ", gain " + num(best_any->gain) +
                (best_any->significant ? "" : ", not significant") +
                "); the baseline explains the data as far as these effects go";
  } else if (decision.beyond) {
    const OnTopOfShape* beyond = decision.beyond;
    const CandidateReport& shape_report = *d.candidate(decision.shape);
    d.cause = beyond->cause;
    d.verdict = std::string(to_string(beyond->cause)) + ": " + beyond->outcome.evidence + ". " +
                beyond->outcome.extension + ", on top of " + shape_name(decision.shape) + " (" +
                shape_report.extension + ", gain " + num(shape_report.gain) +
                "), lowers the held-out rms error from " + num(shape_report.heldout.rmse) + " to " +
                num(beyond->outcome.fit.heldout.rmse) + " " + unit + " (gain " + num(beyond->gain) +
                "; " + num(d.baseline_heldout.rmse / beyond->outcome.fit.heldout.rmse) +
                " over the baseline)";
  } else {
    const CandidateReport& w = *decision.eligible.front();
    d.cause = w.cause;
    d.verdict = std::string(to_string(w.cause)) + ": " + w.evidence + ". " + w.extension +
                " lowers the held-out rms error from " + num(d.baseline_heldout.rmse) + " to " +
                num(w.heldout.rmse) + " " + unit + " (gain " + num(w.gain) + ")";
    if (!w.left_out.empty()) {
      d.verdict +=
          ", and carries over to every record left out whole (gain " + left_out_summary(w) + ")";
    }
  }
}

// Notes where the verdict is not clean: a candidate gaining more than the named one without a
// significant statistic, or no cause while the baseline's error is above the noise floor.
void note_unclean_verdict(Diagnosis& d, const Decision& decision, const DiagnosisOptions& options) {
  if (d.cause != Cause::kNone && !decision.beyond) {
    const CandidateReport& named = *d.candidate(d.cause);
    for (const CandidateReport& c : d.candidates) {
      if (!c.significant && c.gain > named.gain * 1.05 && c.gain >= options.min_gain) {
        d.notes.push_back("not clean: " + std::string(to_string(c.cause)) +
                          " lowers the held-out error more (gain " + num(c.gain) +
                          ") but its statistic is not significant (" + c.evidence + ")");
      }
    }
  }
  if (d.cause == Cause::kNone && !decision.at_floor) {
    const CandidateReport* best_any = decision.best_any;
    d.notes.push_back("not clean: the baseline's held-out error is " +
                      num(d.baseline_heldout.rmse / d.noise_rms) +
                      "x the noise, but no single candidate explains the rest (best gain " +
                      num(best_any->gain) + ", " + std::string(to_string(best_any->cause)) +
                      (best_any->significant ? "" : ", statistic not significant") + ")");
  }
}

// Notes how much of the output's power something other than this input drives (called when the
// coherent share is below kMinCoherentShare).
void note_incoherent_output(Diagnosis& d, const details::DiagnosisRecord& r,
                            const std::string& unit) {
  double mean = 0.0, square = 0.0;
  for (const double v : r.y) mean += v, square += v * v;
  mean /= static_cast<double>(r.n);
  const double variance = square / static_cast<double>(r.n) - mean * mean;
  const double noise_share = variance > 0.0 ? d.noise_rms * d.noise_rms / variance : 0.0;
  // The incoherent power stays in the error of any model driven by this input alone (of any
  // linear filter of the prediction, exactly; of other models, about).
  const double floor_rms = std::sqrt(std::max(0.0, (1.0 - d.coherent_share) * variance));
  d.notes.push_back(
      "not clean: only " + num(100.0 * d.coherent_share) +
      " % of the output's power is coherent with this input's prediction, and noise makes " +
      num(100.0 * noise_share) +
      " %: the rest comes from something not in this record (another input driving this "
      "output, as in a multi-axis stage, or a disturbance), which no single-input model or "
      "candidate here explains; such a model could lower the error to about " +
      num(floor_rms) + " " + unit + " at best (gain " +
      num(floor_rms > 0.0 ? d.baseline_heldout.rmse / floor_rms : 0.0) +
      "); where the record holds the other inputs, name them all (--u-column u1,u2,...) and "
      "diagnose measures their coupling");
}

// Notes when every reversal of the input is at its extremes: the record shows one loop only.
void note_single_loop(Diagnosis& d, const details::DiagnosisRecord& r,
                      const details::InputEvents& ev) {
  const auto [lo, hi] = std::minmax_element(r.u.begin(), r.u.end());
  const double band = kOneLoopBand * (*hi - *lo);
  std::size_t reversals = 0, inner = 0;
  for (const std::size_t k : ev.event_samples) {
    if (ev.step[k]) continue;
    ++reversals;
    if (r.u[k] > *lo + band && r.u[k] < *hi - band) ++inner;
  }
  if (reversals >= 4 && inner == 0) {
    d.notes.push_back("every reversal of the input is at its extremes (" + num(*lo) + " and " +
                      num(*hi) + " " + r.units.input +
                      "): the record shows one loop and no minor loops, so a model fitted on "
                      "it may not hold for smaller loops or other excitations; check it on "
                      "another record (hystbench simulate, or diagnose --model)");
  }
}

// Notes on the record: a given model that does not match it, what its excitation cannot show.
void note_record(Diagnosis& d, const details::DiagnosisRecord& r, const details::InputEvents& ev,
                 const DiagnosisOptions& options) {
  if (given_model_stale(d, options)) {
    d.notes.push_back(
        "the given model's parameters do not match this record: the same structure "
        "refitted here lowers the held-out error " +
        num(d.baseline_heldout.rmse / d.refit_heldout->rmse) +
        "x; candidates are tested on the refit's residual and named only for what "
        "they gain beyond that refit");
  }
  if (ev.hold_seconds < 0.5) {
    d.notes.push_back("the input never holds: creep and drift can only be seen indirectly");
  }
  note_single_loop(d, r, ev);
  if (ev.steps == 0) {
    d.notes.push_back(
        "no input steps: dynamics and delay show only through the fast parts of "
        "the excitation");
  }
}

// A runner-up that explains the same as the named cause (within the noise of it) and about as
// well leaves the choice between them open.
void note_ambiguity(Diagnosis& d, const Decision& decision) {
  const std::vector<const CandidateReport*>& eligible = decision.eligible;
  for (std::size_t i = 1; i < eligible.size() && !decision.beyond; ++i) {
    if (!eligible[i]->named && eligible[i]->gain >= kAmbiguity * eligible.front()->gain) {
      d.notes.push_back("not clean: " + std::string(to_string(eligible[i]->cause)) +
                        " explains the data about as well (gain " + num(eligible[i]->gain) +
                        " against " + num(eligible.front()->gain) + ")");
    }
  }
}

// The extended model: the baseline's when no cause is named.
void extend_by_nothing(Diagnosis& d) {
  d.extended = d.baseline;
  d.extended_description = "the baseline (no extension named)";
  d.extended_fit = d.baseline_fit;
  d.extended_heldout = d.baseline_heldout;
  d.extended_prediction = d.baseline_prediction;
}

Diagnosis run_diagnosis(std::span<const double> t, std::span<const double> u,
                        std::span<const double> y, const DiagnosisOptions& options,
                        const std::vector<details::RecordPart>& parts) {
  report(options, 0.0, "checking the record");
  const std::vector<std::size_t> starts = starts_of(parts);
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
    score_left_out(d, r, parts, base.spec, fits, options);
  }

  report(options, 0.95, "deciding");
  Decision decision;
  decision.reference = d.baseline_heldout.rmse;
  if (d.refit_heldout) decision.reference = std::min(decision.reference, d.refit_heldout->rmse);
  const double floor = options.noise_floor_factor * d.noise_rms;
  decision.at_floor = d.baseline_heldout.rmse <= floor;
  d.noise_allowance_rms =
      std::sqrt(options.noise_floor_factor * options.noise_floor_factor - 1.0) * d.noise_rms;
  decision.eligible = eligible_candidates(d, decision, options);
  prefer_the_plays_shape(d, decision);
  order_rate_and_delay(d, decision, r, ev);
  const std::string unit = r.units.output;
  test_on_shape(d, r, fits, ev, options, decision);
  decision.best_any = &*std::max_element(
      d.candidates.begin(), d.candidates.end(),
      [](const CandidateReport& a, const CandidateReport& b) { return a.gain < b.gain; });
  decide_cause(d, decision, options, unit);
  note_unclean_verdict(d, decision, options);
  if (!decision.at_floor && d.coherent_share < kMinCoherentShare) {
    note_incoherent_output(d, r, unit);
  }
  note_record(d, r, ev, options);

  if (d.cause == Cause::kNone) {
    extend_by_nothing(d);
  } else {
    const std::string reference_name = decision.reference < d.baseline_heldout.rmse
                                           ? "the given model refitted here"
                                           : "the baseline";
    name_causes_and_extend(
        d, {r, fits, ev, ref.profiles, ref.response, options, decision.reference, reference_name,
            decision.on_shape, decision.beyond, base.spec.delay_samples, decision.shape});
    note_ambiguity(d, decision);
  }
  report(options, 1.0, "done");
  return d;
}

}  // namespace

Diagnosis diagnose(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                   const DiagnosisOptions& options) {
  return run_diagnosis(t, u, y, options, {{"record", 0, u.size()}});
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
  const std::vector<double> offsets = align_offsets(t, u, y, options, parts);
  Diagnosis d = run_diagnosis(t, u, y, options, parts);
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

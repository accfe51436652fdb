#include "diagnosis/details/naming/name_causes.hpp"

#include <algorithm>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "diagnosis/details/baseline.hpp"
#include "diagnosis/details/candidate_reports.hpp"
#include "diagnosis/details/naming/rules.hpp"
#include "diagnosis/details/progress.hpp"
#include "diagnosis/details/report/reasons.hpp"
#include "diagnosis/details/residual_profiles.hpp"

namespace hystbench::compensation::details::diagnosis {

namespace {

// A significant extension joins the named one when it lowers the joint model's held-out rms by
// at least 2 %.
constexpr double kMinJoinGain = 1.02;

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

// The others, in the order of the try-first rules (naming/rules.cpp). A contender may be named:
// significant and carrying over (when the first is named beyond the shape, significant on top of
// the shape). Every significant extension that carries over (drift aside: never extrapolated) may
// join the extended model. Says why a candidate that carries over is no contender beyond the
// shape.
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
    // The plane the plays' own shape holds as well is not tried later either (the eligible-order
    // rules, naming/rules.cpp).
    if (c.cause == Cause::kLoopShape && plane_outdone(d)) continue;
    const OnTopOfShape* s = x.beyond ? on_shape_of(x, c.cause) : nullptr;
    const bool contender = c.carries_over && (x.beyond ? s && s->significant : c.significant);
    if (x.beyond && c.carries_over && !contender) {
      c.not_named = !s ? "it could not be fitted on top of " + shape_name(x.shape)
                       : "on top of " + shape_name(x.shape) +
                             " its statistic is not significant (gain " + num(s->gain) + ")";
    }
    const bool joins = c.significant && c.carries_over && c.cause != Cause::kDrift;
    // A statistic a stronger cause swamps is read again on what the causes before it leave
    // (the read-again rules, naming/rules.cpp).
    const bool swamped = read_again_rule(c.cause, d.cause) != nullptr;
    const bool retest = swamped && c.carries_over && !contender && (!x.beyond || s != nullptr);
    const double gain = s ? s->gain : c.heldout.rmse > 0.0 ? x.reference / c.heldout.rmse : 0.0;
    if (contender || joins || retest) order.push_back({i, gain, contender, retest});
  }
  // The shape first, those read again last, else by rank (the try-first rules).
  std::sort(order.begin(), order.end(),
            [&d](const Next& a, const Next& b) { return tried_before(d, a, b); });
  return order;
}

// Names a contender whose outcome `o` on top of the joint model (held-out rms joint_rms, holding
// `before`) gains kMinAddedGain (or min_gain when lower) added to the stronger causes and is not
// within their noise; else says why not.
void judge_contender(Diagnosis& d, const Naming& x, const Next& next,
                     const details::CandidateOutcome& o, double joint_rms,
                     const std::string& before) {
  CandidateReport& c = d.candidates[next.index];
  const double rms = o.fit.heldout.rmse;
  const OnTopOfShape* s = x.beyond ? on_shape_of(x, c.cause) : nullptr;
  using Verdict = AddedJudgement::Verdict;
  AddedJudgement j;
  j.gain = next.gain;
  j.over_shape = s != nullptr;
  j.added_gain = rms > 0.0 ? joint_rms / rms : 0.0;
  j.added_rms = quadrature_difference(joint_rms, rms);
  j.needed = added_gain_needed(x.options);
  j.allowance = d.noise_allowance_rms;
  j.min_gain = x.options.min_gain;
  if (j.added_rms < j.allowance) {
    j.verdict = Verdict::kWithinNoise;
  } else if (j.gain < j.min_gain && j.added_gain < j.needed) {
    j.verdict = Verdict::kBelowMinGain;
  } else if (j.added_gain < j.needed) {
    j.verdict = Verdict::kMostlyTheirs;
  }
  if (j.verdict != Verdict::kNamed) {
    c.not_named = not_named_reason(j, before, x.r.units.output);
    return;
  }
  d.causes.push_back({c.cause, next.gain, s ? s->outcome.fit.heldout.rmse : c.heldout.rmse,
                      s ? shape_name(x.shape) : x.reference_name, j.added_gain, j.added_rms,
                      // A retested cause's evidence is read on the joint model's residual.
                      s && !next.retest ? s->outcome.evidence : c.evidence,
                      s ? s->outcome.extension : c.extension});
  c.named = true;
  c.not_named.clear();
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
  // A statistic read again (its read-again rule's), read before the fit: not significant there
  // either, it is not tried.
  const ReadAgainRule* again = next.retest ? read_again_rule(c.cause, d.cause) : nullptr;
  if (next.retest && again->statistic(jc) < c.threshold) return false;
  try {
    details::CandidateOutcome o = test_of(c.cause)(jc);
    if (next.retest) {
      if (o.statistic < o.threshold) return false;
      // A statistic whose rule says so (the shape's) must also gain min_gain on what the first
      // leaves, as the first must over the reference.
      const double added =
          o.fit.heldout.rmse > 0.0 ? joint.fit.heldout.rmse / o.fit.heldout.rmse : 0.0;
      if (again->must_gain_min_gain && added < x.options.min_gain) {
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
  } catch (const DiagnosisCancelled&) {
    throw;
  } catch (const std::exception&) {
    // A combination the designs cannot fit is left out.
    if (next.contender) c.not_named = "it could not be fitted on top of " + before;
  }
  return false;
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

}  // namespace

void name_causes_and_extend(Diagnosis& d, const Naming& x) {
  Joint joint = name_first_cause(d, x);
  const std::vector<Next> order = next_causes(d, x);
  report(x.options, 0.97, "naming the other causes and joining the significant extensions");
  for (const Next& next : order) {
    if (try_next_cause(d, x, next, joint)) {
      apply_after_join_rules(d, x, d.candidates[next.index].cause, joint);
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
}

void extend_by_nothing(Diagnosis& d) {
  d.extended = d.baseline;
  d.extended_description = "the baseline (no extension named)";
  d.extended_fit = d.baseline_fit;
  d.extended_heldout = d.baseline_heldout;
  d.extended_prediction = d.baseline_prediction;
}

}  // namespace hystbench::compensation::details::diagnosis

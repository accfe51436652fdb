#pragma once
// The naming procedure's special-case rules (diagnosis internals). Each kind of rule is an
// ordered table in rules.cpp, one row a rule (its name, when it applies, what it does, why),
// evaluated row by row in the table's order; the comment above each row names the test that
// holds it. The general rules (significance, min_gain, carrying over, the noise allowance, the
// added gain) are the procedure's own (eligible_candidates, name_causes_and_extend).
#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/candidates.hpp"
#include "diagnosis/details/naming/decision.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// The record the eligible-order rules read (the error after the input's reversals).
struct RecordEvents {
  const details::DiagnosisRecord& r;
  const details::InputEvents& ev;
};

/// Applies the eligible-order rules, in order, to Decision::eligible as eligible_candidates left
/// it (largest gain first): a rule that applies moves or removes a candidate, and says why in d
/// (a note, or the candidate's not_named).
void apply_eligible_order_rules(Diagnosis& d, Decision& decision, const RecordEvents& record);

/// Whether cause a (held-out gain gain_a) goes before cause b (gain_b) where causes are ranked:
/// the first precedence rule that pairs them decides, else the larger gain.
bool ranks_before(Cause a, double gain_a, Cause b, double gain_b);

/// Whether the cause after the first `a` is tried before `b` (both in d.candidates): the first
/// try-first rule that tells them apart decides, else ranks_before.
bool tried_before(const Diagnosis& d, const Next& a, const Next& b);

/// A cause whose statistic a stronger cause's error swamps on the reference's residual: not
/// significant there, it is read again on what the causes before it leave (Next::retest).
struct ReadAgainRule {
  const char* name;
  Cause cause;
  /// Whether it is read again behind `first`, the cause named first.
  bool (*behind)(Cause first);
  /// Its statistic on a joint model's residual, read before its fit.
  double (*statistic)(const details::CandidateContext& c);
  /// Read again and significant, it must also gain min_gain on what the first leaves: it
  /// changes the family every later cause is judged in.
  bool must_gain_min_gain;
  const char* reason;
};

/// The read-again rule of `cause` behind `first`, or nullptr when it is not read again.
const ReadAgainRule* read_again_rule(Cause cause, Cause first);

/// Applies the after-join rules, in order, once the part of `joined` has joined the joint model
/// (try_next_cause returned true): a rule that applies refits a part the join changed.
void apply_after_join_rules(const Diagnosis& d, const Naming& x, Cause joined, Joint& joint);

}  // namespace hystbench::compensation::details::diagnosis

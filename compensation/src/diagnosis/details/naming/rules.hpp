#pragma once
// The naming procedure's special-case rules (diagnosis internals): the order causes are ranked
// in, the statistics read again on a joint model's residual, the plays' shape before the plane,
// a delay before a rate law it ties with, and the delay found again on top of the shape.
#include "details/diagnosis_signals.hpp"
#include "diagnosis/details/candidates.hpp"
#include "diagnosis/details/naming/decision.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// The order causes are named in: by gain, but creep before drift and before rate dependence.
/// Creep and drift both explain a slow change of the output; creep is the part the input
/// explains, the drift what is left, and a drift's pieces, fitted across the held-out blocks
/// between them, follow a slow creep at least as well as the creep lags that predict it. A rate
/// law's widening, where the filtered rate decays after a change, trails it as creep does; its
/// own gain beside a stronger cause (a delay) is mostly that cause's, so it would be tried
/// first and take the creep's share.
bool ranks_before(Cause a, double gain_a, Cause b, double gain_b);

/// The statistic of a cause that is read again on a joint model's residual (drift: the time
/// profile; creep: the hold profile; the shape: the level profile), without its fit.
double retest_statistic(Cause cause, const details::CandidateContext& c);

/// The plane, eligible beside the play family's own shape extension (asymmetry), is left out
/// unless it predicts the held-out blocks kPlaneOverPlays better; it is not tried later either.
void prefer_the_plays_shape(Diagnosis& d, Decision& decision);

/// A delay and a rate law both lag a ramp, and on a coarse record gain about as much (a 1-sample
/// delay at 100 Hz: the delay 1.79x, a thresholds law 1.80x). Right after a reversal they differ:
/// for its length a delay carries the output on in the old direction, a rate law's widened
/// thresholds hold it. When a rate law is eligible first and a delay within kAmbiguity of it
/// predicts the held-out samples there better (by more than the noise allows), the delay is named
/// first. Only that way: a law named first takes a delay's lag into its widening, and the delay
/// then adds nothing, while on top of a delay the rate candidate tries the delay a sample less.
void order_rate_and_delay(Diagnosis& d, Decision& decision, const details::DiagnosisRecord& r,
                          const details::InputEvents& ev);

/// A delay named first was found on the baseline, which misses the loop's shape: off by a
/// sample at 20 kHz, the lag left is what a rate law then takes (1.46x added, none hidden). With
/// the shape joined, the delay is found again on top of both and kept where it predicts better.
void find_delay_again(const Diagnosis& d, const Naming& x, Joint& joint);

}  // namespace hystbench::compensation::details::diagnosis

#pragma once
// Diagnosis of what a hysteresis model misses on a measured record (t, u, y).
// Not real-time: allocates freely; seconds for a record of a few hundred thousand samples
// (hystbench-bench --benchmark_filter=BM_DiagnoseModeAndDelay measures it).
//
// The record is cut into `blocks` equal blocks; every `heldout_every`-th block (from block
// `heldout_every / 2`) is held out, the others are the fit part. Every model is simulated
// through the whole record from its start (so the held-out blocks see the right hysteresis
// state) but its parameters are fitted on the fit part only, and every error reported as
// "held-out" is measured on the held-out blocks only.
//
// The baseline is a given model (e.g. the bench's simulation) or a classical PI identified on
// the fit part (plays uniform on half the input span, order chosen by held-out error). The
// baseline's residual is profiled against time, input level, direction, rate, time since the
// last reversal or step, and frequency. Then each candidate cause is tested: a statistic
// computed from the residual, and an extended model (the baseline structure plus the effect,
// refitted on the fit part) whose held-out error gives the gain
//   gain = baseline held-out rms / extended held-out rms.
// The named cause is the significant candidate with the largest gain above `min_gain`;
// `none` when there is none, or when the baseline's held-out error is at the noise floor
// (estimated from the second differences of the residual). Every other significant candidate
// that carries over and, added to the stronger named causes, lowers the held-out error by 1.1x
// (or min_gain when lower) is named too, unless it is within their noise (see Diagnosis::causes);
// a drift or a creep not significant on the baseline's residual is read again on theirs, and so
// is the shape behind a delay or a resonance.
//
// Candidates and their extensions:
//   asymmetry        modified PI (dead zones) or coupled-play PI
//   loop_shape       the operators swapped for a nonparametric Preisach plane (a density that
//                    varies over the plane, a saturating top: a shape no play family holds)
//   rate_dependence  rate-dependent PI (cumulative weights linear in du/dt or |du/dt|, or
//                    thresholds widening with |du/dt| or its square root)
//   creep            creep lags (CreepOperatorBank), time constants log-spaced
//   dynamics         second-order dynamics (natural frequency, damping) after the hysteresis
//   delay            pure input delay in whole samples
//   drift            slow output offset, piecewise linear in time (knots at the block edges);
//                    named, not extrapolated: the extended model is the hysteresis fitted with
//                    the drift removed, and its held-out error includes the drift curve
//                    interpolated across the held-out blocks.
// Units are the record's: t in s, u in the input unit (e.g. V), y in the output unit (µm).
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/error_metrics.hpp"

namespace hystbench::compensation {

enum class Cause {
  kNone,
  kAsymmetry,
  kRateDependence,
  kCreep,
  kDynamics,
  kDelay,
  kDrift,
  kLoopShape
};

/// "none", "asymmetry", "rate_dependence", "creep", "dynamics", "delay", "drift",
/// "loop_shape".
std::string_view to_string(Cause cause) noexcept;
std::optional<Cause> cause_from_string(std::string_view name) noexcept;
/// Every cause but none, in the order they are tested and reported.
std::span<const Cause> candidate_causes() noexcept;

struct DiagnosisOptions {
  /// The baseline model; std::nullopt = a classical PI identified on the fit part.
  std::optional<ActuatorModel> baseline;
  /// Split: `blocks` equal blocks, every `heldout_every`-th held out (25 % with 16 and 4).
  int blocks = 32;        ///< 4 .. 64
  int heldout_every = 4;  ///< 2 .. blocks / 2
  /// A candidate is named only when its held-out gain reaches this (after the first named
  /// cause, its gain added to the causes before it may instead) and its statistic is
  /// significant.
  double min_gain = 1.2;
  /// The baseline is "at the noise floor" when its held-out rms is below this times the
  /// estimated noise rms.
  double noise_floor_factor = 1.3;
  /// loop_shape swaps the given baseline's operator for a Preisach plane; false keeps its family
  /// (a family the user fixed): the candidate is reported, not tested. Without a given baseline
  /// the plane is not tested either: the classical PI the diagnosis identifies there is the
  /// reference the effects are named against, not a family to replace.
  bool swap_operator = true;
  /// Units written to the models.
  Units units;
  /// Optional progress callback: (fraction done 0..1, what is happening). Called from the
  /// diagnosis's threads one at a time; it may throw to cancel (rethrown by diagnose()).
  std::function<void(double, const std::string&)> progress;
  /// Threads the candidates are tested on at once: 0 = every core, 1 = the calling thread alone
  /// (a core left to a loop running beside). The result is the same whatever the count.
  std::size_t threads = 0;
  /// Optional: polled before each fit, also inside a candidate's test (every few ms to a few
  /// hundred ms on a 10 kHz record), from any of the diagnosis's threads (so thread-safe); true
  /// stops the diagnosis, which throws DiagnosisCancelled.
  std::function<bool()> cancelled;
};

/// What diagnose() throws when DiagnosisOptions::cancelled said so.
struct DiagnosisCancelled : std::runtime_error {
  DiagnosisCancelled() : std::runtime_error("the diagnosis was cancelled") {}
};

/// How the record was split into fit and held-out parts.
struct DataSplit {
  std::size_t samples = 0;
  std::size_t blocks = 0;
  /// Held-out sample ranges [first, second), in time order.
  std::vector<std::pair<std::size_t, std::size_t>> heldout;
  std::size_t fit_samples = 0;
  std::size_t heldout_samples = 0;
  /// Samples at the start, before the input has reached both its extremes (the hysteresis
  /// state there depends on what came before the record): simulated, neither fitted nor scored.
  std::size_t skipped = 0;
  /// Records end to end (diagnose() of a set): each one's start is skipped the same way.
  std::size_t records = 1;
  /// The skipped sample ranges [first, second), one per record at most, in time order.
  std::vector<std::pair<std::size_t, std::size_t>> skipped_ranges;

  bool is_heldout(std::size_t k) const noexcept;
  bool is_skipped(std::size_t k) const noexcept;
  /// One line, e.g. "4 interleaved blocks of 2125 samples held out (25 %): 4250-6375, ...".
  std::string describe(double sample_period_s) const;
};

/// The baseline residual's mean against one explanatory variable (binned).
struct ResidualProfile {
  std::string variable;         ///< "time", "input", "direction", "rate", "since_event"
  std::string label;            ///< human-readable, with unit
  std::vector<double> centers;  ///< bin centers [variable unit]
  std::vector<double> means;    ///< mean residual per bin [output unit]
  std::vector<std::size_t> counts;
  /// Share of the residual variance the binned means explain, 0..1.
  double explained = 0.0;
};

/// Measured output against the baseline prediction, per frequency (Welch estimate):
/// gain = |S_y,yhat / S_yhat,yhat|, phase of the same ratio, coherence 0..1, the one-sided power
/// spectral densities of the prediction and of the measured output [output unit^2 / Hz], and
/// whether the bin is informative: coherence >= 0.5, the prediction above the noise floor and
/// the measured output 10x above it.
struct FrequencyResponse {
  std::vector<double> frequency_hz, gain, phase_rad, coherence, input_psd, output_psd;
  std::vector<unsigned char> informative;
};

/// A model fitted on every other record of a set, predicting one record it never saw: rms
/// error [output unit] on that record after its start-up, the record's mean error removed (a
/// sensor offset differs between runs; it is not a property of the device).
struct LeftOutScore {
  std::string record;         ///< the record's name
  double baseline_rms = 0.0;  ///< the baseline structure, fitted on the others
  double rms = 0.0;           ///< this candidate's structure, fitted on the others
  double gain = 0.0;          ///< baseline_rms / rms
};

struct CandidateReport {
  Cause cause = Cause::kNone;
  double statistic = 0.0;  ///< the cause's test statistic (what it is: see `evidence`)
  double threshold = 0.0;  ///< significant when statistic >= threshold
  bool significant = false;
  std::string evidence;   ///< one line: what the residual shows for this cause
  std::string extension;  ///< what the extended model adds, with its fitted parameters
  ActuatorModel model;    ///< the extended model, fitted on the fit part
  ErrorStats fit;         ///< on the fit part (prediction including drift for drift)
  ErrorStats heldout;     ///< on the held-out part
  double gain = 0.0;      ///< baseline held-out rms / this held-out rms
  /// Fitted drift per sample [output unit] (drift only; empty otherwise).
  std::vector<double> drift;
  /// Whole-record prediction of the extended model (+ drift) [output unit].
  std::vector<double> prediction;
  /// Several records: this structure fitted on all records but one, scored on that one, for
  /// each record (leave-one-record-out); empty for a single record.
  std::vector<LeftOutScore> left_out;
  /// Geometric mean of the left-out gains (1 for a single record).
  double left_out_gain = 1.0;
  /// False when the extension gains in-record but not on the records left out whole: it
  /// fits something of the records that is not a property of the device. Such a candidate is
  /// never named.
  bool carries_over = true;
  /// True when it is one of Diagnosis::causes.
  bool named = false;
  /// Why it is not named, one phrase (empty when named): its statistic is not significant, its
  /// gain is below min_gain, it does not carry over, it is within the noise of the stronger
  /// causes, or the baseline is at the noise floor.
  std::string not_named;
};

/// One of the causes the record shows (Diagnosis::causes).
struct NamedCause {
  Cause cause = Cause::kNone;
  /// Held-out gain of its extension over `against` (rms of that / rms of this): the rank.
  double gain = 0.0;
  double heldout_rms = 0.0;  ///< its extension's held-out rms [output unit]
  /// What the gain is measured against: "the baseline" ("the given model refitted here" when a
  /// given model does not match the record), or "the loop's shape (asymmetry)" for the other
  /// causes when the shape is named (see Diagnosis::causes).
  std::string against;
  /// Held-out gain of the joint model with it over the joint model of the causes before it
  /// (for the first, `gain`).
  double added_gain = 0.0;
  /// The held-out rms it explains beyond the causes before it, in quadrature:
  /// sqrt(rms before^2 - rms with it^2) [output unit]; for the first, beyond `against`.
  double added_rms = 0.0;
  std::string evidence;   ///< what the residual shows for it
  std::string extension;  ///< what its extension adds, with the fitted parameters
};

struct Diagnosis {
  /// The largest named cause (causes.front()), or none.
  Cause cause = Cause::kNone;
  /// Every named cause, largest held-out gain first; empty when the cause is none. After the
  /// first (`cause`, chosen as the verdict says), the candidates that are significant and carry
  /// over are tested again, strongest first, on top of the extended model built so far (the
  /// causes before them and any extension that lowered its error); one is named when its
  /// added_gain reaches 1.1 (or min_gain when lower: an effect beside a larger one gains little
  /// over the baseline on its own) and it is not within the noise of the causes before it: it
  /// must explain at least `noise_allowance_rms` of held-out rms beyond them (added_rms). When
  /// the first is named beyond the loop's shape (asymmetry), the other causes are judged on top
  /// of the shape (significant there, gain over the shape's extension); they come first, ranked
  /// by that gain, and the shape last, itself judged on top of the first. A drift or a creep not
  /// significant on the baseline's residual, which a stronger cause's error on every move swamps,
  /// is read again on what the causes before it leave, and so is the shape behind a delay or a
  /// resonance named first: gaining min_gain there, it joins right after the first (a delay
  /// first is found again on top of it), the others are judged on top of it, and it is listed
  /// last.
  std::vector<NamedCause> causes;
  /// The held-out rms [output unit] an effect must explain beyond the stronger named causes to
  /// be told apart from them: sqrt(noise_floor_factor^2 - 1) x noise_rms, what a model at the
  /// noise floor may still leave above the noise.
  double noise_allowance_rms = 0.0;
  /// The records diagnosed together (one name for a single record), and where each starts in
  /// the concatenation every sample index and prediction here refers to.
  std::vector<std::string> records;
  std::vector<std::size_t> record_starts;
  /// Several records: the output offset subtracted from each (0 for the first) so that their
  /// sensor offsets agree [output unit]; every prediction here is of the shifted outputs.
  std::vector<double> record_offsets;
  /// One paragraph: the named cause and why, or why none.
  std::string verdict;
  /// Caveats: ambiguous candidates, effects left over, missing excitation, ...
  std::vector<std::string> notes;

  std::size_t samples = 0;
  double sample_period_s = 0.0;
  DataSplit split;
  /// Noise rms [output unit]: from the baseline residual's second differences, or, when the
  /// input repeats (`input_period` > 0 samples), from the output's period-to-period difference
  /// if that is lower (it also holds when the residual has content up to the Nyquist frequency).
  double noise_rms = 0.0;
  std::size_t input_period = 0;
  std::string noise_source;  ///< how noise_rms was estimated, one phrase
  /// Share of the output's power (beyond its mean) that is coherent with the baseline's
  /// prediction, 0..1 (Welch coherence weighted by the output spectrum). Well below 1 while the
  /// noise is small: something not in the record drives the output (another input, a
  /// disturbance), which no single-input model explains.
  double coherent_share = 1.0;

  bool baseline_given = false;
  std::string baseline_description;
  ActuatorModel baseline;
  ErrorStats baseline_fit, baseline_heldout;
  std::vector<double> baseline_prediction;
  /// With a given baseline: the same structure refitted on the fit part (no new effect).
  std::optional<ErrorStats> refit_heldout;

  std::vector<ResidualProfile> profiles;
  FrequencyResponse frequency_response;
  std::vector<CandidateReport> candidates;  ///< in candidate_causes() order

  /// The named cause's extended model (the baseline for none).
  ActuatorModel extended;
  std::string extended_description;
  /// The causes the extended model holds: the named one first, then every other significant
  /// one whose test, repeated on top of the joint model, lowered the held-out error (drift is
  /// never extrapolated, so never joined).
  std::vector<std::string> extended_parts;
  ErrorStats extended_fit, extended_heldout;
  std::vector<double> extended_prediction;

  const CandidateReport* candidate(Cause cause) const noexcept;
  const ResidualProfile* profile(std::string_view variable) const noexcept;
};

/// Diagnoses a record. t [s] strictly increasing (uniform sampling assumed, 100 Hz .. 20 kHz
/// and beyond), u input, y output, equal lengths. Throws std::invalid_argument with a clear
/// message for fewer than 400 samples, mismatched lengths, NaN/inf, non-increasing t, constant
/// u or y, or bad options.
Diagnosis diagnose(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                   const DiagnosisOptions& options = {});

/// A model's error on a record it was not fitted on (`hystbench diagnose --validate`, and each
/// record left out of a set): simulated from rest at u[0], scored after the start-up (until the
/// input has reached both its extremes, at most a quarter of the record), the mean error removed (a
/// sensor offset differs between runs; it is not a property of the device) and reported apart.
struct ValidationScore {
  double rmse = 0.0;     ///< rms error, mean removed [output unit]
  double max_abs = 0.0;  ///< largest |error - mean| [output unit]
  double offset = 0.0;   ///< mean error [output unit]
  std::size_t samples = 0, skipped = 0;
};
/// dt [s] > 0; u, y equal lengths, at least 2 samples. Throws std::invalid_argument otherwise.
ValidationScore validate_model(ActuatorModel model, std::span<const double> u,
                               std::span<const double> y, double dt);

/// One record of a set of records of the same device (t [s], u, y as above).
struct RecordView {
  std::span<const double> t, u, y;
  std::string name;
};

/// Diagnoses several records of one device together. They are taken end to end (same sample
/// period within 1 %; each record's start is left out until its own input has reached both its
/// extremes), fitted on every record's fit blocks and scored on the held-out blocks as above.
/// Every candidate's structure (and the baseline's) is also fitted on all records but one and
/// scored on that one, for each record in turn: a cause is named only when it gains on the
/// records left out whole too, so effects seen only across records (rate dependence between
/// runs at different frequencies) are found, and extensions that fit one record but not the
/// device are not named. One record: the same as diagnose(t, u, y). Throws
/// std::invalid_argument naming the record for a bad record or mismatched sample periods.
Diagnosis diagnose(std::span<const RecordView> records, const DiagnosisOptions& options = {});

}  // namespace hystbench::compensation

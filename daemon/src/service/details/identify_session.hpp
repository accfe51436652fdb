#pragma once
// identify after its excitation: the fitted candidates (one per family; several with
// `--model auto`), each verified on the loop by a short tracking segment through its inverse;
// then the record diagnosed with the best one (the candidates' diagnoses run on a worker while
// the loop verifies them) and its extension verified against it, before the coordinator adopts
// one and reports run.finished. Supervisor thread only. The coordinator
// (identify_coordinator.hpp) walks the session through its steps, in service/:
// identify_candidates.cpp (the fits), identify_verification.cpp (the segments on the loop),
// identify_extension.cpp (the diagnosis and the extended candidate), identify_delay_trim.cpp and
// identify_parts_alone.cpp (the extension's trials), identify_choice.cpp (the choice, the model
// file and the result).
#include <cstddef>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/model_check.hpp"
#include "hystbench/compensation/stage_responses.hpp"
#include "hystbench/daemon/loop/run_program.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"
#include "runs/details/diagnosis_ahead.hpp"

namespace hystbench::daemon {

struct IdentifyCandidate {
  compensation::FitResult fit;
  /// null until verified; then {end, reason, log, rms/max error ...} or {end: "not_run", reason}.
  nlohmann::json verification;
  /// Names the candidate in its verification's run id and stage: its family, and for the
  /// dead-zone neighbour its order too (e.g. "mpi-4dz").
  std::string label;
  /// The same on sines, by frequency [Hz] (none ran: empty): the extension and the model it
  /// extends on the fast sine, a rate law and its rate-free self on the rate sine.
  std::map<double, nlohmann::json> sines;
  /// Its static part driven by its inverse (model_check.hpp); empty until checked.
  std::optional<compensation::ModelCheck> check;
};

/// c.check, or where it is empty the check at the loop's period dt_s.
compensation::ModelCheck check_of(const IdentifyCandidate& c, double dt_s);

/// The family of a fit's hysteresis model, as model files name it ("mpi", "rpi", ...).
std::string model_type_name(const compensation::FitResult& fit);

/// A family's fit as a candidate not yet verified, labelled with the family.
IdentifyCandidate family_candidate(compensation::FitResult fit);

/// The candidate that tracks best: the lowest verified max error on the standard triangle,
/// figures within 3 % of the lowest counting as equal (a margin above the spread of two triangles
/// on one model, which the bench's history moves) and the first of them taken: candidates come
/// by held-out error, best first. Candidates in `left_out` are skipped, and so is a candidate
/// whose check failed where another's passed (its inverse does not reach its own output: a model
/// that fits the record may still be unusable on the bench); none verified: the first.
std::size_t best_verified(const std::vector<IdentifyCandidate>& candidates,
                          const std::vector<std::size_t>& left_out);

/// The candidates best_verified() leaves out: the extension `extended` (judged against its base
/// instead), and the loser of a rate law (candidate 0) and its rate-free self `rate_free` on the
/// sine at `sine_hz`; a law that loses takes its dead-zone neighbour along.
std::vector<std::size_t> left_out_of_choice(const std::vector<IdentifyCandidate>& candidates,
                                            std::optional<std::size_t> extended,
                                            std::optional<std::size_t> rate_free, double sine_hz);

/// Whether identify adopts the extended model `ext` over the model it extends, `base`, from their
/// verification segments: the fast sine at fast_hz (0: none ran) and the middle one at mid_hz
/// (0: none).
bool extension_tracks_better(const IdentifyCandidate& base, const IdentifyCandidate& ext,
                             double fast_hz, double mid_hz = 0.0);

/// The extension's slow parts alone (the base's mode and delay kept) against `base`: they track
/// the middle sine better as extension_tracks_better() judges a sine (the triangle within the
/// spread between runs), and the fast sine no worse than that spread.
bool slow_parts_track_better(const IdentifyCandidate& base, const IdentifyCandidate& alone,
                             double fast_hz, double mid_hz);

/// The extension's parts (its result's parts[].cause) by the band they act in: fast (a mode, a
/// delay) and the others.
struct PartsByBand {
  std::vector<std::string> fast, slow;
};
PartsByBand split_parts(const nlohmann::json& parts);

/// The band an extension's parts act in: fast (a mode, a delay: the fast sine judges them), slow
/// (creep, a rate law, the loop's shape: the triangle and the middle sine). Its key in the
/// extension's result: "fast_parts" or "slow_parts".
enum class PartsBand { kFast, kSlow };
const char* parts_key(PartsBand band);

/// Whether identify tries one band of the extension's parts alone (queue_parts_alone()):
/// the extension holds parts of both bands and does not track better on the bench as a whole;
/// the fast band where it gained on the fast sine, the slow band where it gained on the middle
/// sine and lost on the fast one.
bool parts_alone_worth_trying(const IdentifyCandidate& base, const IdentifyCandidate& ext,
                              const PartsByBand& parts, PartsBand band, double fast_hz,
                              double mid_hz);

/// Whether an extended model may be played and written: its check (model_check.hpp) passes, or
/// it fails on its inverse by no more (rms and max) than the model identify keeps without it
/// fails its own (`base`: that check; check["base"], check["accepted"]). Writes the check to
/// extension["check"] and, where it fails, extension["adopted"] = false and ["why"].
bool passes_check(const compensation::ActuatorModel& model, const compensation::ModelCheck& base,
                  double dt_s, nlohmann::json& extension);

/// "its dynamics alone, without rate_dependence": one band of an extension's parts.
std::string parts_alone_text(const PartsByBand& parts, PartsBand band);

/// `from` with the dynamics and the delay of `timing`: one band of an extension's parts alone
/// (the base with the extension's fast parts, or the extension with the base's); `from`'s
/// label and notes.
IdentifyCandidate with_timing_of(const IdentifyCandidate& from, const IdentifyCandidate& timing,
                                 double dt_s);

/// Where the whole extension `ext` failed its check: `base` with the extension's fast parts
/// alone, checked (extension["fast_parts"]: parts, left_out, check), with no note of them (the
/// caller describes the extension); empty where the extension does not hold parts of both bands,
/// or the fast parts fail the check too (passes_check(): by more than the base fails its own).
std::optional<IdentifyCandidate> fast_parts_instead(const IdentifyCandidate& base,
                                                    const IdentifyCandidate& ext, double dt_s,
                                                    nlohmann::json& extension);

/// One band of the parts alone (`alone`): the fast parts judged as the whole extension is, the
/// slow parts by slow_parts_track_better(). Says so in extension[parts_key(band)] (verified,
/// adopted, why) and, adopted, in extension["adopted"] and ["why"].
bool adopt_parts_alone(const IdentifyCandidate& base, const IdentifyCandidate& alone,
                       PartsBand band, double fast_hz, double mid_hz, nlohmann::json& extension);

/// Each of extension["parts"] says whether the model took it ("adopted"): all of an extension
/// adopted whole, one band's parts of one adopted in part (`alone`), none otherwise.
void mark_adopted_parts(nlohmann::json& extension, bool extended, std::optional<PartsBand> alone);

/// The verified gains of `ext` against `base`: the triangle's max and rms, the fast and middle
/// sines' rms (null where one did not run).
nlohmann::json verified_gain_json(const IdentifyCandidate& base, const IdentifyCandidate& ext,
                                  double fast_hz, double mid_hz);

/// v[key] of candidate c's sine at hz, or null when it did not run.
nlohmann::json sine_field(const IdentifyCandidate& c, double hz, const char* key);

/// The verified rms error of candidate c's sine at hz [% of the reference span]; +inf when it did
/// not run to the end.
double verified_sine_rms(const IdentifyCandidate& c, double hz);

/// The sine a rate law is judged on [Hz]: the fastest the rate bench tracks, at most a twentieth
/// of the loop rate.
double rate_sine_frequency(double loop_rate_hz);

/// One verification segment: a candidate's standard triangle, or a sine.
struct VerificationJob {
  std::size_t candidate = 0;
  double sine_hz = 0.0;  ///< the sine's frequency [Hz]; 0 = the standard triangle
  /// A precondition sweep of 0.1 s instead of the daemon's (the two halves of a trial that
  /// differ in one parameter; the sweep sets the same state for both).
  bool short_precondition = false;
};

/// Where identify is after its excitation. The steps come in this order, each entered once:
/// continue_identify() moves on when the step's runs are played (or none is left to play). An
/// interrupted session (stop, abort, fault, shutdown) skips to its end from any step.
enum class IdentifyStep {
  kVerifyingCandidates,  ///< the fitted candidates' triangle and sines on the loop
  kExtending,  ///< the diagnosis of the record ran (or failed); its extension, delay trim and
               ///< parts alone verified on the loop
  kMeasuringResponses,  ///< frf's run, where it did not play while the diagnosis ran (last;
                        ///< nothing left after it)
};

struct IdentifySession {
  IdentifyStep step = IdentifyStep::kVerifyingCandidates;
  nlohmann::json result;  ///< the identify run's result so far (run.finished adds the model)
  std::string log_path;
  std::size_t samples = 0;
  double fit_sample_period_s = 0.0;
  nlohmann::json history;                     ///< what identify did against the actuator's history
  std::vector<IdentifyCandidate> candidates;  ///< by held-out error, best first
  std::vector<VerificationJob> jobs;          ///< the segments to play, in order
  std::size_t next = 0;                       ///< the job being (or to be) played
  /// The record at the loop rate (outputs matched to the inputs they answer) and its samples
  /// that the fit simulates but does not score (ramp, settle, precondition): the diagnosis's.
  std::vector<double> u, y;
  std::size_t unscored = 0;
  bool extend = true;                   ///< diagnose and extend the chosen model
  bool swap_operator = true;            ///< the extension may swap the operator (loop_shape)
  std::size_t base = 0;                 ///< the candidate the extension extends
  std::optional<std::size_t> extended;  ///< the extended candidate, when there is one
  double fast_hz = 0.0;                 ///< the fast sine's frequency [Hz]; 0 = none
  double mid_hz = 0.0;                  ///< the middle sine's (fast / 2.5) [Hz]; 0 = none
  /// The fast sine judges a delay or dynamics: its output lag trims the extension's delay.
  bool trim_delay = false;
  bool trim_tried = false;  ///< the trim was measured (once)
  /// On trial, the last two candidates: the extension with its delay trimmed (this one), and as
  /// timed, played again.
  std::optional<std::size_t> trim;
  /// The base with only the extension's mode and delay, and the extension with the base's, when
  /// the whole extension gained in that band but not on the bench as a whole
  /// (queue_parts_alone()); tried once.
  std::optional<std::size_t> fast_parts, slow_parts;
  bool parts_alone_tried = false;
  /// The band of parts the extension holds alone, where the whole failed its check and that band
  /// passed it (the extension's fast parts on the base); empty = the whole extension.
  std::optional<PartsBand> extension_band;
  /// The base's sines played while its diagnosis ran [Hz] (play_while_diagnosing()).
  std::vector<double> sines_while_diagnosing;
  /// The rate-free neighbour of a rate law (candidate 0), when there is one: the two are judged
  /// against each other on the rate sine; a law that loses is not adopted (nor its dead-zone
  /// neighbour), a law that wins leaves its rate-free self out.
  std::optional<std::size_t> rate_free;
  double rate_sine_hz = 0.0;  ///< the rate sine's frequency [Hz]
  nlohmann::json extension;   ///< what the extension found, added and verified
  std::string program_id;     ///< run id of the verification on the loop
  bool interrupted = false;   ///< stop, abort or fault during a verification
  /// The stage's frequency responses (frf's run: while the chosen candidate's diagnosis runs,
  /// else last): the options of the run while it plays, what it measured, and what the result
  /// says of it. responses_tried: the run was started (or failed to start), once.
  std::optional<sim::FrequencyResponseExcitationOptions> response_options;
  bool responses_tried = false;
  std::optional<compensation::StageResponses> responses;
  nlohmann::json responses_result;
  /// The candidates' diagnoses, run while the loop verifies them (with the extension on);
  /// last, so that it stops before the record it reads goes.
  std::unique_ptr<details::DiagnosisAhead> ahead;
};

/// The diagnosis of identify's record (u, y at the loop's period dt) with candidate i as the
/// baseline, its delay less the driver's exchange latency (the record holds the outputs matched
/// to the inputs they answer); the models and the record are copied: it runs beside the session.
/// swap_operator: the diagnosis may swap its operator for a Preisach plane (loop_shape).
details::DiagnosisAhead::Task identify_diagnosis(const std::vector<IdentifyCandidate>& candidates,
                                                 double exchange_s, std::span<const double> u,
                                                 std::span<const double> y, double dt,
                                                 bool swap_operator);

/// Fits the requested family, or with options.kind unset ("auto") each of pi, mpi, cpi and rpi
/// (a family that fails is left out); sorted by held-out error. Throws when none fits.
/// t, u, y are already shifted by the delay chosen in ticks: no further delay is searched
/// (options.delay_samples is ignored; at the fit rate it would step in blocks of ticks, and the
/// caller sets the model's delay to the ticks).
std::vector<IdentifyCandidate> fit_identify_candidates(std::span<const double> t,
                                                       std::span<const double> u,
                                                       std::span<const double> y,
                                                       const compensation::FitOptions& options);

/// One family with its dead zones chosen by held-out error (options.dead_zones < 0): the same
/// family with one dead zone per side fewer, fitted on the same shifted record, appended as a
/// candidate for the verification to judge. The held-out error hardly tells m from m - 1, the
/// tracking does: the outermost dead zone fits the record's end of range, and the inverse can
/// overshoot there. A plane that kept the identity as its output map is verified against the
/// other map its fit tries (a few dead zones per side): the record's held-out end can prefer the
/// identity where the bench's triangle, whose minor loops turn inside the range, needs the map.
/// A plane's rate law is refitted on the neighbour, not searched for again. Nothing is appended
/// for auto, fixed dead zones, a PI family fitted without any, or a neighbour fit that fails.
void add_dead_zone_neighbour(std::vector<IdentifyCandidate>& candidates, std::span<const double> t,
                             std::span<const double> u, std::span<const double> y,
                             const compensation::FitOptions& options);

/// A rate-dependent PI whose rate law the fit kept: the same plays and dead zones without the
/// law (its nested modified PI refitted, as an rpi with zero rate coefficients), appended as a
/// candidate for the verification to judge on the triangle and on the rate sine. A law that
/// gains on the held-out record can still track worse than none where the actuator follows
/// another law (a switching front: docs/measurements.md, "Rate dependence on"); on the slow
/// triangle a law that helps and its rate-free self differ by no more than two runs of one model.
/// A Preisach plane whose rate law the fit kept: the plane refitted without it, with the same
/// output map. Nothing is appended for another family, a rate-free fit, or a refit that fails.
void add_rate_free_neighbour(std::vector<IdentifyCandidate>& candidates, std::span<const double> t,
                             std::span<const double> u, std::span<const double> y,
                             const compensation::FitOptions& options);

}  // namespace hystbench::daemon

#pragma once
// The identify coordinator: what identify does after its excitation has played on one axis. It
// fits the record's candidates, plays each one's verification segments on the loop, diagnoses the
// record and verifies the extension, measures the frequency response of the chosen model, then
// adopts that model and delivers identify's result. Where it is: IdentifyStep
// (identify_session.hpp). Supervisor thread only; it takes the bench's mutex where it touches the
// run supervisor, and never runs on the loop thread. A stage's identify (several axes) is the
// stage coordinator's (stage_coordinator.hpp).
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/stage_responses.hpp"
#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "runs/details/diagnosis_ahead.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/run_result.hpp"
#include "service/details/bench_parts.hpp"

namespace hystbench::daemon {

struct IdentifySession;

namespace details {

class IdentifyCoordinator {
 public:
  /// What identify asks of the bench's other components (each called on the supervisor thread).
  struct Hooks {
    /// What the run builders need to know (settings, model, present output). The caller holds
    /// the bench's mutex.
    std::function<RunContext()> run_context;
    /// The chosen model becomes the active one (its file already saved at `path`), with the
    /// responses identify measured; returns the feedback a track through its inverse gets now,
    /// or null with `why` set. The caller holds the bench's mutex.
    std::function<nlohmann::json(compensation::ModelFile file, const std::string& path,
                                 const std::optional<compensation::StageResponses>& responses,
                                 nlohmann::json* why)>
        adopt;
    /// identify's result, kept and announced (run.finished). No lock held.
    std::function<void(nlohmann::json)> deliver;
  };

  IdentifyCoordinator(BenchParts bench, Hooks hooks);
  ~IdentifyCoordinator();
  IdentifyCoordinator(const IdentifyCoordinator&) = delete;
  IdentifyCoordinator& operator=(const IdentifyCoordinator&) = delete;

  /// identify's excitation played (`result` its collected result): fits the candidates and
  /// queues the first segment; without one to play, delivers the result (with fit_error when no
  /// candidate fits). `fit_request`: the identify request's fit options (BuiltRun::fit).
  void excitation_played(const RunProgram& run, RunResult result,
                         const nlohmann::json& fit_request);
  /// Whether `run` is the segment identify has on the loop (the supervisor hands it back to
  /// segment_played()).
  bool owns(const RunProgram& run) const;
  /// The segment on the loop came back: its figures kept, then the next segment, or the model
  /// chosen and the result delivered.
  void segment_played(std::unique_ptr<RunProgram> run);

 private:
  /// The fitted candidates of identify's record, not yet verified. Throws when none fits.
  std::unique_ptr<IdentifySession> fit_candidates(const RunProgram& run, const RunResult& result,
                                                  const nlohmann::json& fit_request);
  /// Diagnoses s's candidates ahead on a worker (s.ahead), in the order the choice prefers them:
  /// started with those there are, or those fitted since queued on it. Nothing where s does not
  /// extend its model.
  void diagnose_candidates_ahead(IdentifySession& s) const;
  /// Submits the next verification segment; false when none is left or it failed.
  bool verify_next_candidate();
  /// A verification segment came back: its figures go to its candidate.
  void verification_finished(std::unique_ptr<RunProgram> run);
  /// The next segment, else the extension (once), else the responses (where they did not play
  /// while the diagnosis ran), else finish().
  void continue_identify();
  /// While the best verified candidate's diagnosis still runs (on its own from now on), plays
  /// what identify would play after it: the frf run, then that candidate's sines an extension of
  /// delay or dynamics is judged against. True when a segment started; false when all have
  /// played (or there is no diagnosis ahead).
  bool play_while_diagnosing();
  /// Diagnoses the record with the best verified candidate and queues its extension's
  /// verification; false when nothing is added (the reason in the session's extension).
  bool extend_identified_model();
  /// The extension's progress as fit.progress events of identify's run.
  DiagnosisAhead::Progress extension_progress() const;
  /// The base's diagnosis: the worker's (waited for, or run at once on every core), else run
  /// here; the worker ends either way.
  DiagnosisAhead::Taken take_diagnosis(double exchange_s, const DiagnosisAhead::Progress& progress);
  /// Once the extension's fast sine has played: its model with the delay the sine's output lag
  /// measures, and the model as timed, queued on that sine ahead of the segments left (nothing
  /// when the lag is outside the trim's bounds or the sine judges no delay or dynamics).
  void queue_delay_trim();
  /// Once both have played: the extension takes the trimmed delay when it tracks that sine
  /// better; the two trial candidates are dropped either way.
  void settle_delay_trim();
  /// Once the extension is verified (its delay trim settled): where it holds slower parts beside
  /// a mode or a delay and does not track better on the bench, the base with that mode and delay
  /// alone (it gained on the fast sine), the extension without them (it gained on the middle
  /// sine), each queued on the triangle and both sines.
  void queue_parts_alone();
  /// After the whole extension's verdict (`extended`, `chosen`): a band of its parts alone that
  /// tracks better is taken (the band the extension held alone where the whole failed its
  /// check; else the fast band, then the slow one), and every part says whether it was.
  static void settle_parts_alone(IdentifySession& s, std::size_t& chosen, bool& extended);
  /// identify's frf run (while the diagnosis runs, else last); false when it did not start.
  bool measure_responses();
  /// identify's frf run came back: its responses go with the chosen model; the session goes on
  /// where it played while the diagnosis ran.
  void responses_measured(std::unique_ptr<RunProgram> run);
  /// Adopts the chosen candidate and delivers identify's result; the session ends.
  void finish();
  void emit(const nlohmann::json& event) const;
  bool quitting() const noexcept;

  BenchParts bench_;
  const double dt_;  // the loop's period [s]
  Hooks hooks_;
  std::unique_ptr<IdentifySession> session_;  // from excitation_played() to finish()
};

}  // namespace details
}  // namespace hystbench::daemon

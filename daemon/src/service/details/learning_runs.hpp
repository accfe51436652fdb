#pragma once
// The bench's learning runs (track --learn, --learned): the learners of the run the loop plays
// (one, or on a stage one per axis), each trial scored on the supervisor thread as the loop
// closes it, the next drive offered, run.progress for each trial, and at the run's end each
// learner's result with its drive kept in the model folder. Supervisor thread, except
// started(); it takes the bench's mutex where it reads the learners or the run supervisor, and
// never runs on the loop thread (the trials' exchanges live in the program the loop plays).
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "runs/details/track_learning.hpp"
#include "service/details/bench_parts.hpp"

namespace hystbench::daemon::details {

class LearningRuns {
 public:
  /// The model file a learning run plays with, for its kept drive's metadata: the active
  /// model's file name, or on a stage axis `axis`'s (empty: none). The caller holds the bench's
  /// mutex.
  using ModelFile = std::function<std::string(const std::string& axis)>;

  LearningRuns(BenchParts bench, ModelFile model_file);
  LearningRuns(const LearningRuns&) = delete;
  LearningRuns& operator=(const LearningRuns&) = delete;

  /// Run `run_id` was launched with `learning` (null: it does not learn) and, on a stage, the
  /// other axes' learners. The caller holds the bench's mutex.
  void started(const std::string& run_id, std::unique_ptr<TrackLearning> learning,
               std::vector<std::unique_ptr<TrackLearning>> others = {});
  /// Each supervisor wake-up: the trials the loop closed scored, the next drives offered,
  /// run.progress for each of axis 0's trials.
  void poll();
  /// The run ended (played or not): its learning's result in `report` (`learning`, the last
  /// trial's figures as the run's) and its drive kept as RUN-learned. Nothing for another run.
  void finished(const RunProgram& run, nlohmann::json& report);
  /// A stage's run ended: each axis's learning and last trial's figures under report["axes"],
  /// each axis's drive kept as RUN-AXIS-learned, and report["learned_drive"] the name
  /// `track --learned` replays them by. Nothing for another run.
  void axes_finished(const RunProgram& run, nlohmann::json& report);

 private:
  /// Takes the trials the loop closed, offers the next drive and emits run.progress for each.
  void announce_trials(TrackLearning& learning, const std::string& run_id);
  /// Saves `learning`'s kept drive as NAME-learned in the model folder (nothing for a replay),
  /// `more` added to its metadata; `l` (the learning's result) gets drive and drive_file, or
  /// drive_file_error.
  void keep_learned_drive(const TrackLearning& learning, const std::string& name,
                          const std::string& model_file, double tare_um, const nlohmann::json& more,
                          nlohmann::json& l) const;

  BenchParts bench_;
  ModelFile model_file_;
  // Guarded by mutex_: the learning run's learners (axis 0's, and on a stage the others').
  std::unique_ptr<TrackLearning> learning_;
  std::vector<std::unique_ptr<TrackLearning>> axis_learning_;
  std::string run_id_;
};

}  // namespace hystbench::daemon::details

#pragma once
// The stage coordinator: the bench on a stage of several axes (BenchSettings::axes). It keeps the
// stage's model (each axis's model file, their coupling, what each axis's drive leaves on the
// others) and starts the stage's runs: identify one axis at a time, frf, track and excite every
// axis together (their programs: runs/details/stage_runs.hpp). On the supervisor thread it fits
// identify's record, measures each axis's responses after it and keeps what they measured.
// Commands come with the bench's mutex held; the supervisor-thread steps take it where they touch
// the stage's state. Never on the loop thread.
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hystbench/daemon/runs/upload_store.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/run_result.hpp"
#include "service/details/bench_parts.hpp"

namespace hystbench::daemon::details {

class RequestParams;
struct IdentifyRequest;
struct StageModel;
class ModelStore;
class LearningRuns;

class StageCoordinator {
 public:
  /// What the stage asks of the bench.
  using Hooks = RunHooks;

  /// `models`, `learning` and `uploads` are the bench's, and outlive the coordinator.
  StageCoordinator(BenchParts bench, ModelStore& models, LearningRuns& learning,
                   UploadStore& uploads, Hooks hooks);
  ~StageCoordinator();
  StageCoordinator(const StageCoordinator&) = delete;
  StageCoordinator& operator=(const StageCoordinator&) = delete;

  // Commands; the caller holds the bench's mutex, and for a run the bench is idle.
  /// identify: each axis excited in turn, the others held.
  nlohmann::json start_identify(const IdentifyRequest& request);
  /// track: every axis's reference together.
  nlohmann::json start_track(const RequestParams& request, std::uint64_t client);
  /// excite: drive_uploads names a complete drive upload per axis, each played open loop from its
  /// axis's present output, every axis's record as long as the longest (the others hold their
  /// last drive).
  nlohmann::json start_excite(const RequestParams& request, std::uint64_t client);
  /// frf: each axis's responses, for its feedback. Throws no_model before an identify.
  nlohmann::json start_frf(const RequestParams& request);
  /// model.load: `stored` names the stage identify's run, whose axes' model files (RUN-AXIS.json,
  /// with their responses and the coupling they carry) become the stage's model; or `models`
  /// gives those documents by axis. A refused request keeps nothing.
  nlohmann::json load_model(const RequestParams& request);
  /// status' and model.get's word on the stage: null before a model.
  nlohmann::json status() const;
  /// The stage's model, or null before an identify or a model.load.
  const StageModel* model() const noexcept { return stage_.get(); }
  /// Each axis's model file, in the model folder.
  std::vector<std::string> model_paths() const;
  /// The model file of `axis` (its name in the model folder; empty without a model).
  std::string model_file(const std::string& axis) const;
  /// Every axis's present output [V].
  std::vector<double> axis_outputs() const;

  // The supervisor thread's steps, each delivering its run's result.
  /// identify's record played: its fit, the stage model kept and saved, then each axis's
  /// responses measured (the result delivered after them).
  void identified(const RunProgram& run, RunResult result);
  /// An frf run played (identify's own or the command's): each axis's responses kept with its
  /// model, and its files saved again.
  void responses_measured(const RunProgram& run, RunResult result);

 private:
  /// identify's frf: each axis's responses. False when it did not start (`why` says so).
  bool measure_responses(const std::string& identify_run_id, std::string& why);
  /// Writes each axis's model file (RUN-AXIS.json, its responses with it) to the model folder;
  /// the file names. Throws CommandError io_error. The caller holds the bench's mutex.
  nlohmann::json save_models();

  BenchParts bench_;
  ModelStore& models_;
  LearningRuns& learning_;
  UploadStore& uploads_;
  Hooks hooks_;
  // Under the bench's mutex:
  std::unique_ptr<StageModel> stage_;
  nlohmann::json fit_request_;  // identify's fit options (BuiltRun::fit), for its record
  // An frf under way: each axis's excitation options and the ticks of each turn.
  std::vector<sim::FrequencyResponseExcitationOptions> frf_options_;
  std::size_t frf_turn_ = 0;
  nlohmann::json identify_report_;  // identify's result while its frf plays
};

}  // namespace hystbench::daemon::details

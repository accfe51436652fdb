#pragma once
// The runs of a stage of several axes (BenchSettings::axes): identify moves one axis at a time
// and fits each axis's model of its own displacement and the coupling between them
// (compensation::fit_stage); track plays a reference per axis, each through its axis's
// compensator, with the coupling taken out of the feedforward's targets (static decoupling:
// compensation::StageDecoupler; or, asked for, dynamic where the stage's measured responses
// show the coupling's modes: compensation::DynamicStageDecoupler). Each axis's program is the
// one-axis builder's (make_axis_track_program), stepped together by the loop
// (RunProgram::stage_axes). Pure (no threads, no files); errors are CommandError naming the cause.
// Not real-time safe.
#include <cstddef>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/stage_decoupling.hpp"
#include "hystbench/daemon/runs/upload_store.hpp"
#include "hystbench/sim/frequency_response_excitation.hpp"
#include "hystbench/sim/stage_reference.hpp"
#include "runs/details/identify_program.hpp"
#include "runs/details/request_params.hpp"
#include "runs/details/run_context.hpp"
#include "runs/details/track_request.hpp"

namespace hystbench::daemon::details {

/// A stage's identified model: each axis's model of its own displacement, and the coupling.
struct StageModel {
  std::vector<std::string> axes;
  std::vector<compensation::ModelFile> models;  ///< per axis, its input range the output's
  compensation::CouplingEstimate coupling;
  compensation::StageDecoupler decoupler;
  /// cross[i][j] (i != j): axis j's drive to axis i's output, measured with the axes'
  /// responses (frf, identify); empty until measured, a pair's responses empty where they
  /// could not be measured.
  std::vector<std::vector<compensation::StageResponses>> cross;
  std::string run_id;                                ///< the identify run it was fitted on
  nlohmann::json report = nlohmann::json::object();  ///< identify's result keys (stage, axes)
};

/// The model folder's file of a stage identify's axis: "RUN-AXIS.json".
std::string stage_model_file(const std::string& run_id, const std::string& axis);

/// ctx for axis a: its model in `stage` (null: none), with the responses its frf measured, and
/// its present output u_now [V]; no plan or feedback cache, no bench-wide responses.
RunContext axis_context(const RunContext& ctx, const StageModel* stage, std::size_t a,
                        double u_now);

/// identify on a stage of `axes`: in turn a, axis a ramps from its present output u_now[a] to
/// identify's excitation, plays it and ramps back, while the others hold theirs. BuiltRun::fit
/// holds what fit_stage_identify() needs. bad_params when the run is longer than the bench
/// records.
BuiltRun make_stage_identify_program(const IdentifyRequest& request, const RunContext& ctx,
                                     std::span<const std::string> axes,
                                     std::span<const double> u_now);

/// The stage's model from a completed stage identify run (its `fit` request): each turn's record
/// (the moved axis's drive, every axis's output) to compensation::fit_stage at identify's fit
/// rate, each axis's model taking the output range as its input range. Each axis's model file
/// carries the stage (its axes and the coupling) under identification.stage, so that
/// stage_model_from_files() builds the stage again. Throws CommandError fit_error naming the
/// cause.
/// The stage of `axes` again from its axes' model files, in axis order (`names`: the files'
/// names, for the report): each must be of the same stage identify and name its axis; the
/// coupling is the one they carry. Throws CommandError bad_model naming the file and the cause.
StageModel stage_model_from_files(std::vector<compensation::ModelFile> files,
                                  std::span<const std::string> axes,
                                  std::span<const std::string> names);

StageModel fit_stage_identify(const RunProgram& run, const nlohmann::json& fit,
                              const BenchSettings& settings);

/// frf on a stage: in turn a, axis a plays frf's multisines (options[a], from its present output
/// u_now[a]) while the others hold theirs; BuiltRun::fit holds the turn's length.
BuiltRun make_stage_response_program(
    std::span<const sim::FrequencyResponseExcitationOptions> options, const RunContext& ctx,
    std::span<const std::string> axes, std::span<const double> u_now);

/// Each axis's frequency responses from its turn of a completed stage frf run (turn ticks
/// each). Throws CommandError measurement_failed as measure_responses() does.
std::vector<compensation::StageResponses> measure_stage_responses(
    const RunProgram& run, std::span<const sim::FrequencyResponseExcitationOptions> options,
    std::size_t turn);

/// The stage's cross responses from the same run: cross[i][j] from axis j's turn and axis i's
/// output (i != j; the diagonal left empty). A pair that cannot be measured is left empty.
std::vector<std::vector<compensation::StageResponses>> measure_stage_cross_responses(
    const RunProgram& run, std::span<const sim::FrequencyResponseExcitationOptions> options,
    std::size_t turn);

/// A track request on a stage: what every axis shares (compensator, precondition, approach;
/// TrackRequest), and either a built-in stage reference or an uploaded reference per axis.
struct StageTrackRequest {
  TrackRequest common;
  sim::StageReferenceSpec builtin;
  /// Per axis of the stage, in its order, the name of its complete reference upload; empty for a
  /// built-in reference.
  std::vector<std::string> uploads;
  /// The coupling taken out of the feedforward's targets (with an inverse and a stage model).
  bool decouple = true;
  /// With its dynamics (each path's shape from the stage's measured responses:
  /// compensation::DynamicStageDecoupler) where they were measured; else (the default) its
  /// static gains.
  bool dynamic = false;
  /// `learned` RUN, a stage's learning run: per axis of the stage, in its order, the drive it
  /// starts from (RUN-AXIS); empty for none.
  std::vector<std::string> learned_drives;
};

/// The upload names of `uploads` ({axis: upload}, request key `key`) in the stage's axis order;
/// bad_params naming an axis that is not the stage's, a name that is not one, or the axis
/// without its `what` (`why`: the rule, for the message).
std::vector<std::string> upload_per_axis(const nlohmann::json& uploads, const std::string& key,
                                         std::span<const std::string> axes, const std::string& what,
                                         const std::string& why);

/// excite on a stage: each axis's complete drive upload (`drives`, in the stage's order)
/// played as make_excite_program() plays one, from the axis's present output `u_now` [V]
/// within its slew limit; the shorter drives hold their last value to the longest's end.
/// bad_params naming the axis whose drive the limits refuse, or a run longer than the bench
/// records. With the stage's coupling (`stage`), each axis's prediction is coupled as track's.
BuiltRun make_stage_excite_program(std::span<const Upload* const> drives, const RunContext& ctx,
                                   const StageModel* stage, std::span<const std::string> axes,
                                   std::span<const double> u_now);

/// The request's keys: reference (raster, lissajous or spiral; default raster), frequencies_hz,
/// range_fraction, duration_s, or reference_uploads {axis: upload} naming every axis; decouple,
/// decoupling ("static", the default, or "dynamic"); and track's own (compensator, precondition,
/// approach, gains, learning: learn_trials, learned RUN). bad_params naming the key: an unknown
/// reference, an axis without its upload or an upload for no axis, a one-axis reference's key,
/// one axis's learned drive in place of the learning run's.
StageTrackRequest parse_stage_track_request(const RequestParams& request, const RunContext& ctx,
                                            std::span<const std::string> axes);

/// The stage's track run: axis a's program from make_axis_track_program() over its reference
/// (uploads[a], else the built-in one sampled over axis a's range) with the feedforward fed the
/// decoupled targets; axis 0's program holds the others (RunProgram::stage_axes) and the
/// preparation runs each axis's. bad_params when the axes' references differ in length.
BuiltRun make_stage_track_program(const StageTrackRequest& request, const RunContext& ctx,
                                  const StageModel* stage, std::span<const double> u_now,
                                  std::span<const Upload* const> uploads);

/// `tune` on a stage: each axis's loop designed on its responses and for the coupling (as a
/// track of `kind` would run them: lowered together where the check asks; gains by hand
/// checked), nothing run. {"axes": {axis: the loop's summary with its `curves`},
/// "feedback_interaction": the check together, absent without cross responses}. Errors are
/// plan_feedback()'s (no_frequency_response, no_design, unsafe_gains unless gains.force).
nlohmann::json stage_tune(const RunContext& ctx, const StageModel* stage,
                          std::span<const double> u_now, std::span<const std::string> axes,
                          compensation::CompensatorKind kind, const FeedbackGainsRequest& gains);

/// The result of a finished stage run: `axes` keyed by name, each its program's tracking error
/// (rms/max µm and %, track) and model error; for a track run `coupling_error`, what the other
/// axes' motion left on each axis (compensation::coupling_error_left over the scored samples).
nlohmann::json stage_result(const RunProgram& run, std::span<const std::string> axes);
/// A stage run's result (collect_result()'s report): the first axis's figures at its top
/// replaced by stage_result()'s.
void replace_with_stage_result(nlohmann::json& report, const RunProgram& run,
                               std::span<const std::string> axes);

}  // namespace hystbench::daemon::details

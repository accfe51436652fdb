// The stage coordinator (stage_coordinator.hpp): a stage's model, its runs and their results.
#include "service/details/stage_coordinator.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>

#include "hystbench/common/command_error.hpp"
#include "runs/details/identify_program.hpp"
#include "runs/details/response_program.hpp"
#include "runs/details/run_result.hpp"
#include "runs/details/stage_runs.hpp"
#include "service/details/learning_runs.hpp"
#include "service/details/model_folder.hpp"
#include "service/details/model_store.hpp"
#include "service/details/run_log.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

StageCoordinator::StageCoordinator(BenchParts bench, ModelStore& models, LearningRuns& learning,
                                   UploadStore& uploads, Hooks hooks)
    : bench_(bench),
      models_(models),
      learning_(learning),
      uploads_(uploads),
      hooks_(std::move(hooks)) {}

StageCoordinator::~StageCoordinator() = default;

std::vector<double> StageCoordinator::axis_outputs() const {
  std::vector<double> u;
  for (std::size_t a = 0; a < bench_.settings.axes.size(); ++a) {
    u.push_back(bench_.loop.last_output(a));
  }
  return u;
}

json StageCoordinator::status() const {
  if (!stage_) return nullptr;
  json s = stage_->report;
  s["run_id"] = stage_->run_id;
  s["axes_order"] = stage_->axes;
  return s;
}

std::vector<std::string> StageCoordinator::model_paths() const {
  std::vector<std::string> paths;
  if (!stage_) return paths;
  for (const std::string& axis : stage_->axes) {
    paths.push_back(
        (std::filesystem::path(bench_.settings.model_dir) / stage_model_file(stage_->run_id, axis))
            .string());
  }
  return paths;
}

std::string StageCoordinator::model_file(const std::string& axis) const {
  return stage_ ? stage_model_file(stage_->run_id, axis) : "";
}

json StageCoordinator::save_models() {
  json saved = json::array();
  for (std::size_t a = 0; a < stage_->axes.size(); ++a) {
    const std::string name = stage_model_file(stage_->run_id, stage_->axes[a]);
    json document = compensation::to_json(stage_->models[a]);
    // What the other axes' drives left on this axis, measured with the responses.
    if (a < stage_->cross.size()) {
      json cross = json::object();
      for (std::size_t j = 0; j < stage_->cross[a].size(); ++j) {
        if (j != a && !stage_->cross[a][j].responses.empty()) {
          cross[stage_->axes[j]] = compensation::to_json(stage_->cross[a][j]);
        }
      }
      if (!cross.empty()) document["identification"]["stage"]["cross_responses"] = cross;
    }
    const FolderModel kept = keep_model_document(bench_.settings.model_dir, name, document);
    saved.push_back(std::filesystem::path(kept.path).filename().string());
  }
  return saved;
}

json StageCoordinator::load_model(const RequestParams& request) {
  if (!request.has("stored") && !request.has("models")) {
    throw common::CommandError(
        "not_on_stage",
        "model.load on a stage of " + std::to_string(bench_.settings.axes.size()) +
            " axes takes 'stored': the stage identify's run id, whose axes' models (RUN-AXIS.json) "
            "load together with their coupling, or 'models': those files' documents by axis");
  }
  std::vector<compensation::ModelFile> files;
  std::vector<std::string> names;
  if (request.has("models")) {
    // Every axis's document checked first: a refused request keeps nothing.
    const json& documents = request.params()["models"];
    for (const std::string& axis : bench_.settings.axes) {
      names.push_back("models." + axis);
      if (!documents.contains(axis)) {
        throw common::CommandError("bad_params", "models: no model for axis '" + axis +
                                                     "' (a stage's models load together)");
      }
      try {
        files.push_back(compensation::model_file_from_json(documents[axis]));
      } catch (const std::exception& e) {
        throw common::CommandError("bad_model", names.back() + ": " + e.what());
      }
    }
    for (const auto& [axis, document] : documents.items()) {
      (void)document;
      if (std::find(bench_.settings.axes.begin(), bench_.settings.axes.end(), axis) ==
          bench_.settings.axes.end()) {
        throw common::CommandError("bad_params", "models: '" + axis + "' is no axis of the stage");
      }
    }
  } else {
    const std::string run_id = request.string("stored", "");
    for (const std::string& axis : bench_.settings.axes) {
      names.push_back(stage_model_file(run_id, axis));
      files.push_back(load_stored_model(bench_.settings.model_dir, names.back()).file);
    }
  }
  auto model = std::make_unique<StageModel>(
      stage_model_from_files(std::move(files), bench_.settings.axes, names));
  if (request.has("models")) {
    // Kept as their identify's files: model list shows them, --stored RUN loads them again.
    for (std::size_t a = 0; a < bench_.settings.axes.size(); ++a) {
      names[a] = stage_model_file(model->run_id, bench_.settings.axes[a]);
      (void)keep_model_document(bench_.settings.model_dir, names[a],
                                request.params()["models"][bench_.settings.axes[a]]);
    }
  }
  stage_ = std::move(model);
  models_.changed();
  json axes = json::object();
  for (std::size_t a = 0; a < stage_->axes.size(); ++a) {
    const compensation::ModelFile& f = stage_->models[a];
    json& axis = axes[stage_->axes[a]] = {
        {"name", names[a]},
        {"type", std::string(compensation::to_string(f.model.hysteresis().kind()))},
        {"responses", f.responses.has_value()}};
    const OutputLimits& lim = bench_.settings.loop.limits;
    check_input_range(f.model, lim.u_min, lim.u_max, axis);
  }
  return {
      {"stage_run_id", stage_->run_id}, {"axes", axes}, {"coupling", stage_->report["coupling"]}};
}

json StageCoordinator::start_identify(const IdentifyRequest& request) {
  const std::vector<double> u_now = axis_outputs();
  BuiltRun run =
      make_stage_identify_program(request, hooks_.run_context(), bench_.settings.axes, u_now);
  json fit = std::move(run.fit);
  json reply = bench_.runs.launch("identify", std::move(run));
  fit_request_ = std::move(fit);
  return reply;
}

json StageCoordinator::start_track(const RequestParams& request, std::uint64_t client) {
  const std::vector<double> u_now = axis_outputs();
  const RunContext ctx = hooks_.run_context();
  const RunContext first = axis_context(ctx, stage_.get(), 0, u_now[0]);
  const StageTrackRequest track = parse_stage_track_request(request, first, bench_.settings.axes);
  std::vector<std::shared_ptr<const Upload>> uploads;
  std::vector<const Upload*> raw;
  for (const std::string& name : track.uploads) {
    uploads.push_back(uploads_.complete(name, client, UploadKind::kReference));
    raw.push_back(uploads.back().get());
  }
  BuiltRun run = make_stage_track_program(track, ctx, stage_.get(), u_now, raw);
  std::unique_ptr<TrackLearning> learning = std::move(run.learning);
  std::vector<std::unique_ptr<TrackLearning>> others = std::move(run.axis_learning);
  json reply = bench_.runs.launch("track", std::move(run));
  for (const std::string& name : track.uploads) uploads_.erase(name, client);
  learning_.started(reply["run_id"].get<std::string>(), std::move(learning), std::move(others));
  return reply;
}

json StageCoordinator::start_excite(const RequestParams& request, std::uint64_t client) {
  if (!request.has("drive_uploads")) {
    throw common::CommandError("bad_params",
                               "drive_uploads: missing; a stage's excite names a complete drive "
                               "upload per axis ({axis: upload}: hystbench excite --input-file "
                               "with a column per axis)");
  }
  const std::vector<std::string> names =
      upload_per_axis(request.params()["drive_uploads"], "drive_uploads", bench_.settings.axes,
                      "drive", "a stage's excite drives every axis");
  std::vector<std::shared_ptr<const Upload>> uploads;
  std::vector<const Upload*> raw;
  for (const std::string& name : names) {
    uploads.push_back(uploads_.complete(name, client, UploadKind::kDrive));
    raw.push_back(uploads.back().get());
  }
  BuiltRun run = make_stage_excite_program(raw, hooks_.run_context(), stage_.get(),
                                           bench_.settings.axes, axis_outputs());
  json reply = bench_.runs.launch("excite", std::move(run));
  for (const std::string& name : names) uploads_.erase(name, client);  // the run has them now
  return reply;
}

json StageCoordinator::start_frf(const RequestParams& request) {
  if (!stage_) {
    throw common::CommandError("no_model",
                               "frf on a stage measures each axis's responses for its model: "
                               "identify the stage first");
  }
  const std::vector<double> u_now = axis_outputs();
  const RunContext ctx = hooks_.run_context();
  std::vector<sim::FrequencyResponseExcitationOptions> options;
  for (std::size_t a = 0; a < u_now.size(); ++a) {
    options.push_back(response_options(request, axis_context(ctx, stage_.get(), a, u_now[a])));
  }
  BuiltRun run = make_stage_response_program(options, ctx, bench_.settings.axes, u_now);
  const std::size_t turn = run.fit.value("turn_samples", std::size_t{0});
  json reply = bench_.runs.launch("frf", std::move(run));
  frf_options_ = std::move(options);
  frf_turn_ = turn;
  return reply;
}

bool StageCoordinator::measure_responses(const std::string& identify_run_id, std::string& why) {
  std::lock_guard lock(bench_.mutex);
  const std::vector<double> u_now = axis_outputs();
  const RunContext ctx = hooks_.run_context();
  std::vector<sim::FrequencyResponseExcitationOptions> options;
  std::unique_ptr<RunProgram> p;
  std::size_t turn = 0;
  try {
    for (std::size_t a = 0; a < u_now.size(); ++a) {
      options.push_back(response_options(axis_context(ctx, stage_.get(), a, u_now[a])));
    }
    BuiltRun run = make_stage_response_program(options, ctx, bench_.settings.axes, u_now);
    turn = run.fit.value("turn_samples", std::size_t{0});
    p = std::move(run.program);
    p->run_id = identify_run_id + "-frf";
    open_run_log(*p, run.header, bench_.settings);
  } catch (const std::exception& e) {
    why = e.what();
    return false;
  }
  if (!bench_.runs.submit_segment(std::move(p), "measuring each axis's frequency responses",
                                  "responses_log", why)) {
    return false;
  }
  frf_options_ = std::move(options);
  frf_turn_ = turn;
  return true;
}

void StageCoordinator::responses_measured(const RunProgram& run, RunResult result) {
  std::vector<sim::FrequencyResponseExcitationOptions> options;
  std::size_t turn = 0;
  {
    std::lock_guard lock(bench_.mutex);
    options = std::move(frf_options_);
    frf_options_.clear();
    turn = frf_turn_;
  }
  json& report = result.report;
  if (run.end != RunEnd::kCompleted) {
    report["frequency_response_error"] = "the run did not complete: nothing was measured";
  } else {
    try {
      std::vector<compensation::StageResponses> measured =
          measure_stage_responses(run, options, turn);
      // What each axis's drive left on the others, for the loops' check together.
      std::vector<std::vector<compensation::StageResponses>> cross =
          measure_stage_cross_responses(run, options, turn);
      std::lock_guard lock(bench_.mutex);
      for (std::size_t a = 0; a < measured.size(); ++a) {
        const std::string& axis = bench_.settings.axes[a];
        compensation::ModelFile* model =
            stage_ && a < stage_->models.size() ? &stage_->models[a] : nullptr;
        const compensation::StageResponses* before =
            model != nullptr && model->responses ? &*model->responses : nullptr;
        report["axes"][axis]["frequency_response"] = responses_summary(measured[a], before);
        if (model != nullptr) model->responses = std::move(measured[a]);
      }
      if (stage_) {
        stage_->report["frequency_responses_from"] = run.run_id;
        stage_->cross = std::move(cross);
        // Kept with each axis's model, so that a stage loaded back designs its loops on them.
        try {
          save_models();
        } catch (const std::exception& e) {
          report["save_error"] = e.what();
        }
      }
    } catch (const std::exception& e) {
      report["frequency_response_error"] = e.what();
      spdlog::error("run {}: the stage's frequency responses: {}", run.run_id, e.what());
    }
  }
  json identified;
  {
    std::lock_guard lock(bench_.mutex);
    identified = std::move(identify_report_);
    identify_report_ = nullptr;
  }
  if (identified.is_object()) {  // identify's own frf: its result, with what the frf measured
    json measured = json::object();
    const json axes = report.value("axes", json::object());
    for (const auto& [axis, figures] : axes.items()) {
      if (figures.contains("frequency_response")) measured[axis] = figures["frequency_response"];
    }
    identified["stage_model"]["frequency_responses"] = {
        {"run_id", run.run_id}, {"log", report.value("log", "")}, {"axes", measured}};
    if (report.contains("frequency_response_error")) {
      identified["stage_model"]["frequency_responses"]["error"] =
          report["frequency_response_error"];
    }
    hooks_.deliver(std::move(identified));
    return;
  }
  hooks_.deliver(std::move(report));
}

void StageCoordinator::identified(const RunProgram& run, RunResult result) {
  json fit_request;
  {
    std::lock_guard lock(bench_.mutex);
    fit_request = fit_request_;
  }
  try {
    auto model =
        std::make_unique<StageModel>(fit_stage_identify(run, fit_request, bench_.settings));
    {
      std::lock_guard lock(bench_.mutex);
      stage_ = std::move(model);
      try {
        stage_->report["saved"] = save_models();
      } catch (const std::exception& e) {
        spdlog::warn("stage identify: the axes' models not saved: {}", e.what());
        result.report["save_error"] = e.what();
      }
      result.report["stage_model"] = stage_->report;
    }
    // Each axis's responses next, as one axis's identify measures its stage's: its feedback is
    // designed on them.
    std::string why;
    {
      std::lock_guard lock(bench_.mutex);
      identify_report_ = result.report;
    }
    if (measure_responses(run.run_id, why)) return;  // delivered when it has played
    std::lock_guard lock(bench_.mutex);
    identify_report_ = nullptr;
    result.report["stage_model"]["frequency_responses"] = {{"error", why}};
  } catch (const std::exception& e) {
    result.report["fit_error"] = e.what();
  }
  hooks_.deliver(std::move(result.report));
}

}  // namespace hystbench::daemon::details

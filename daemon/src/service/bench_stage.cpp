// The bench on a stage of several axes (BenchSettings::axes): identify one axis at a time, track
// every axis together, their results per axis (runs/details/stage_runs.hpp).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>

#include "hystbench/common/command_error.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "runs/details/identify_program.hpp"
#include "runs/details/response_program.hpp"
#include "runs/details/run_result.hpp"
#include "runs/details/stage_runs.hpp"
#include "service/details/learning_runs.hpp"
#include "service/details/model_folder.hpp"
#include "service/details/model_store.hpp"
#include "service/details/run_log.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon {

using nlohmann::json;

std::vector<double> Bench::axis_outputs() const {
  std::vector<double> u;
  for (std::size_t a = 0; a < settings_.axes.size(); ++a) u.push_back(loop_->last_output(a));
  return u;
}

json Bench::stage_status() const {
  if (!stage_) return nullptr;
  json s = stage_->report;
  s["run_id"] = stage_->run_id;
  s["axes_order"] = stage_->axes;
  return s;
}

std::vector<std::string> Bench::active_model_paths() const {
  if (!is_stage()) return {models_->active_path()};
  std::vector<std::string> paths;
  if (!stage_) return paths;
  for (const std::string& axis : stage_->axes) {
    paths.push_back((std::filesystem::path(settings_.model_dir) /
                     details::stage_model_file(stage_->run_id, axis))
                        .string());
  }
  return paths;
}

json Bench::save_stage_models() {
  json saved = json::array();
  for (std::size_t a = 0; a < stage_->axes.size(); ++a) {
    const std::string name = details::stage_model_file(stage_->run_id, stage_->axes[a]);
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
    const details::FolderModel kept =
        details::keep_model_document(settings_.model_dir, name, document);
    saved.push_back(std::filesystem::path(kept.path).filename().string());
  }
  return saved;
}

json Bench::load_stage_model(const details::RequestParams& request) {
  if (!request.has("stored") && !request.has("models")) {
    throw common::CommandError(
        "not_on_stage",
        "model.load on a stage of " + std::to_string(settings_.axes.size()) +
            " axes takes 'stored': the stage identify's run id, whose axes' models (RUN-AXIS.json) "
            "load together with their coupling, or 'models': those files' documents by axis");
  }
  std::vector<compensation::ModelFile> files;
  std::vector<std::string> names;
  if (request.has("models")) {
    // Every axis's document checked first: a refused request keeps nothing.
    const json& documents = request.params()["models"];
    for (const std::string& axis : settings_.axes) {
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
      if (std::find(settings_.axes.begin(), settings_.axes.end(), axis) == settings_.axes.end()) {
        throw common::CommandError("bad_params", "models: '" + axis + "' is no axis of the stage");
      }
    }
  } else {
    const std::string run_id = request.string("stored", "");
    for (const std::string& axis : settings_.axes) {
      names.push_back(details::stage_model_file(run_id, axis));
      files.push_back(details::load_stored_model(settings_.model_dir, names.back()).file);
    }
  }
  auto model = std::make_unique<details::StageModel>(
      details::stage_model_from_files(std::move(files), settings_.axes, names));
  if (request.has("models")) {
    // Kept as their identify's files: model list shows them, --stored RUN loads them again.
    for (std::size_t a = 0; a < settings_.axes.size(); ++a) {
      names[a] = details::stage_model_file(model->run_id, settings_.axes[a]);
      (void)details::keep_model_document(settings_.model_dir, names[a],
                                         request.params()["models"][settings_.axes[a]]);
    }
  }
  stage_ = std::move(model);
  models_->changed();
  json axes = json::object();
  for (std::size_t a = 0; a < stage_->axes.size(); ++a) {
    const compensation::ModelFile& f = stage_->models[a];
    json& axis = axes[stage_->axes[a]] = {
        {"name", names[a]},
        {"type", std::string(compensation::to_string(f.model.hysteresis().kind()))},
        {"responses", f.responses.has_value()}};
    const OutputLimits& lim = settings_.loop.limits;
    details::check_input_range(f.model, lim.u_min, lim.u_max, axis);
  }
  return {
      {"stage_run_id", stage_->run_id}, {"axes", axes}, {"coupling", stage_->report["coupling"]}};
}

json Bench::start_stage_identify(const details::IdentifyRequest& request) {
  const std::vector<double> u_now = axis_outputs();
  details::BuiltRun run =
      details::make_stage_identify_program(request, run_context(), settings_.axes, u_now);
  json fit = std::move(run.fit);
  json reply = launch("identify", std::move(run));
  pending_fit_ = std::move(fit);
  return reply;
}

json Bench::start_stage_track(const details::RequestParams& request, std::uint64_t client) {
  const std::vector<double> u_now = axis_outputs();
  const details::RunContext ctx = run_context();
  const details::RunContext first = details::axis_context(ctx, stage_.get(), 0, u_now[0]);
  const details::StageTrackRequest track =
      details::parse_stage_track_request(request, first, settings_.axes);
  std::vector<std::shared_ptr<const Upload>> uploads;
  std::vector<const Upload*> raw;
  for (const std::string& name : track.uploads) {
    uploads.push_back(uploads_.complete(name, client, UploadKind::kReference));
    raw.push_back(uploads.back().get());
  }
  details::BuiltRun run = details::make_stage_track_program(track, ctx, stage_.get(), u_now, raw);
  std::unique_ptr<details::TrackLearning> learning = std::move(run.learning);
  std::vector<std::unique_ptr<details::TrackLearning>> others = std::move(run.axis_learning);
  json reply = launch("track", std::move(run));
  for (const std::string& name : track.uploads) uploads_.erase(name, client);
  learning_->started(reply["run_id"].get<std::string>(), std::move(learning), std::move(others));
  return reply;
}

json Bench::start_stage_excite(const details::RequestParams& request, std::uint64_t client) {
  if (!request.has("drive_uploads")) {
    throw common::CommandError("bad_params",
                               "drive_uploads: missing; a stage's excite names a complete drive "
                               "upload per axis ({axis: upload}: hystbench excite --input-file "
                               "with a column per axis)");
  }
  const std::vector<std::string> names =
      details::upload_per_axis(request.params()["drive_uploads"], "drive_uploads", settings_.axes,
                               "drive", "a stage's excite drives every axis");
  std::vector<std::shared_ptr<const Upload>> uploads;
  std::vector<const Upload*> raw;
  for (const std::string& name : names) {
    uploads.push_back(uploads_.complete(name, client, UploadKind::kDrive));
    raw.push_back(uploads.back().get());
  }
  details::BuiltRun run = details::make_stage_excite_program(raw, run_context(), stage_.get(),
                                                             settings_.axes, axis_outputs());
  json reply = launch("excite", std::move(run));
  for (const std::string& name : names) uploads_.erase(name, client);  // the run has them now
  return reply;
}

json Bench::start_stage_frf(const details::RequestParams& request) {
  if (!stage_) {
    throw common::CommandError("no_model",
                               "frf on a stage measures each axis's responses for its model: "
                               "identify the stage first");
  }
  const std::vector<double> u_now = axis_outputs();
  const details::RunContext ctx = run_context();
  std::vector<sim::FrequencyResponseExcitationOptions> options;
  for (std::size_t a = 0; a < u_now.size(); ++a) {
    options.push_back(
        details::response_options(request, details::axis_context(ctx, stage_.get(), a, u_now[a])));
  }
  details::BuiltRun run = details::make_stage_response_program(options, ctx, settings_.axes, u_now);
  const std::size_t turn = run.fit.value("turn_samples", std::size_t{0});
  json reply = launch("frf", std::move(run));
  stage_frf_options_ = std::move(options);
  stage_frf_turn_ = turn;
  return reply;
}

bool Bench::measure_axes_responses(const std::string& identify_run_id, std::string& why) {
  std::lock_guard lock(mutex_);
  const std::vector<double> u_now = axis_outputs();
  const details::RunContext ctx = run_context();
  std::vector<sim::FrequencyResponseExcitationOptions> options;
  std::unique_ptr<RunProgram> p;
  std::size_t turn = 0;
  try {
    for (std::size_t a = 0; a < u_now.size(); ++a) {
      options.push_back(
          details::response_options(details::axis_context(ctx, stage_.get(), a, u_now[a])));
    }
    details::BuiltRun run =
        details::make_stage_response_program(options, ctx, settings_.axes, u_now);
    turn = run.fit.value("turn_samples", std::size_t{0});
    p = std::move(run.program);
    p->run_id = identify_run_id + "-frf";
    details::open_run_log(*p, run.header, settings_);
  } catch (const std::exception& e) {
    why = e.what();
    return false;
  }
  if (!runs_->submit_segment(std::move(p), "measuring each axis's frequency responses",
                             "responses_log", why)) {
    return false;
  }
  stage_frf_options_ = std::move(options);
  stage_frf_turn_ = turn;
  return true;
}

void Bench::axes_responses_measured(const RunProgram& run, details::RunResult result) {
  std::vector<sim::FrequencyResponseExcitationOptions> options;
  std::size_t turn = 0;
  {
    std::lock_guard lock(mutex_);
    options = std::move(stage_frf_options_);
    stage_frf_options_.clear();
    turn = stage_frf_turn_;
  }
  json& report = result.report;
  if (run.end != RunEnd::kCompleted) {
    report["frequency_response_error"] = "the run did not complete: nothing was measured";
  } else {
    try {
      std::vector<compensation::StageResponses> measured =
          details::measure_stage_responses(run, options, turn);
      // What each axis's drive left on the others, for the loops' check together.
      std::vector<std::vector<compensation::StageResponses>> cross =
          details::measure_stage_cross_responses(run, options, turn);
      std::lock_guard lock(mutex_);
      for (std::size_t a = 0; a < measured.size(); ++a) {
        const std::string& axis = settings_.axes[a];
        compensation::ModelFile* model =
            stage_ && a < stage_->models.size() ? &stage_->models[a] : nullptr;
        const compensation::StageResponses* before =
            model != nullptr && model->responses ? &*model->responses : nullptr;
        report["axes"][axis]["frequency_response"] =
            details::responses_summary(measured[a], before);
        if (model != nullptr) model->responses = std::move(measured[a]);
      }
      if (stage_) {
        stage_->report["frequency_responses_from"] = run.run_id;
        stage_->cross = std::move(cross);
        // Kept with each axis's model, so that a stage loaded back designs its loops on them.
        try {
          save_stage_models();
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
    std::lock_guard lock(mutex_);
    identified = std::move(stage_identify_report_);
    stage_identify_report_ = nullptr;
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
    deliver_result(std::move(identified));
    return;
  }
  deliver_result(std::move(report));
}

void Bench::stage_identified(const RunProgram& run, details::RunResult result) {
  json fit_request;
  {
    std::lock_guard lock(mutex_);
    fit_request = pending_fit_;
  }
  try {
    auto model = std::make_unique<details::StageModel>(
        details::fit_stage_identify(run, fit_request, settings_));
    {
      std::lock_guard lock(mutex_);
      stage_ = std::move(model);
      try {
        stage_->report["saved"] = save_stage_models();
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
      std::lock_guard lock(mutex_);
      stage_identify_report_ = result.report;
    }
    if (measure_axes_responses(run.run_id, why)) return;  // delivered when it has played
    std::lock_guard lock(mutex_);
    stage_identify_report_ = nullptr;
    result.report["stage_model"]["frequency_responses"] = {{"error", why}};
  } catch (const std::exception& e) {
    result.report["fit_error"] = e.what();
  }
  deliver_result(std::move(result.report));
}

}  // namespace hystbench::daemon

// The bench's learning runs (track --learn, --learned): each trial scored on the supervisor
// thread as the loop closes it, the next drive offered, and the drive kept in the model folder.
// A stage's other axes: bench_stage.cpp. Supervisor thread only; never on the loop.
#include <spdlog/spdlog.h>

#include <mutex>

#include "hystbench/compensation/number_text.hpp"
#include "hystbench/daemon/service/bench.hpp"
#include "runs/details/learned_drive.hpp"
#include "runs/details/track_learning.hpp"
#include "service/details/model_store.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon {

using nlohmann::json;

void Bench::learn() {
  details::TrackLearning* learning = nullptr;
  std::string run_id;
  {
    std::lock_guard lock(mutex_);
    if (!learning_ || runs_->phase() != details::RunPhase::kRunning) return;
    learning = learning_.get();
    run_id = learning_run_id_;
  }
  // Its exchange lives in the program the loop plays (handed back to this thread when it ends).
  const RunProgram* active = loop_->active();
  if (active == nullptr || active->run_id != run_id) return;
  announce_trials(*learning, run_id);
  learn_other_axes();
}

void Bench::announce_trials(details::TrackLearning& learning, const std::string& run_id) {
  // The last trial's number: trial 0, its repeat (trial 1), then the learned ones.
  const std::size_t learned = learning.request().trials;
  const std::size_t asked = learned > 0 ? learned + 1 : 0;
  std::vector<details::TrackLearning::Trial> scored;
  try {
    scored = learning.poll();
  } catch (const std::exception& e) {
    learning.fail(e.what());  // the loop must not wait for a drive that will not come
    spdlog::error("run {}: the learning failed: {}", run_id, e.what());
  }
  for (const details::TrackLearning::Trial& t : scored) {
    const std::string stage = "learning: trial " + std::to_string(t.trial) + " of " +
                              std::to_string(asked) + ", rms " +
                              compensation::fixed(t.rms_percent, 3) + " %";
    {
      std::lock_guard lock(mutex_);
      runs_->set_stage(stage);
    }
    emit({{"event", "run.progress"},
          {"run_id", run_id},
          {"kind", "track"},
          {"stage", stage},
          {"fraction", static_cast<double>(t.trial + 1) / static_cast<double>(asked + 1)},
          {"learning",
           {{"trial", t.trial},
            {"trials", asked},
            {"rms_error_percent", t.rms_percent},
            {"max_error_percent", t.max_percent},
            {"drive", t.drive}}}});
  }
}

void Bench::finish_learning(const RunProgram& run, json& report) {
  std::unique_ptr<details::TrackLearning> learning;
  std::string model_path;  // the model the run played with (a run holds model.load off)
  {
    std::lock_guard lock(mutex_);
    if (!learning_ || run.run_id != learning_run_id_) return;
    learning = std::move(learning_);
    learning_run_id_.clear();
    model_path = models_->active_path();
  }
  announce_trials(*learning, run.run_id);  // the last trial, closed as the run ended
  json l = learning->result();
  learning->put_last_trial_figures(report);
  keep_learned_drive(
      *learning, run.run_id,
      model_path.empty() ? std::string() : std::filesystem::path(model_path).filename().string(),
      report.value("tare_um", 0.0), json::object(), l);
  report["learning"] = std::move(l);
}

void Bench::keep_learned_drive(const details::TrackLearning& learning, const std::string& name,
                               const std::string& model_file, double tare_um, const json& more,
                               json& l) const {
  const std::vector<double>& drive = learning.kept_drive();
  const details::LearningRequest& r = learning.request();
  // A replay (no trial learned) keeps nothing new: its drive is the one it started from.
  if (drive.empty() || r.trials == 0) return;
  try {
    json meta = {{"range_um", r.range_um},
                 {"model", model_file.empty() ? json() : json(model_file)},
                 {"started_from", r.start_name.empty() ? json() : json(r.start_name)},
                 {"compensator_offset_um", learning.target_offset(tare_um)},
                 {"last_trial", l["trials"].empty() ? json() : l["trials"].back()}};
    meta.update(more);
    l["drive_file"] =
        details::save_learned_drive(settings_.model_dir, name, drive, learning.kept_compensator(),
                                    dt_, details::learned_for(r, drive.size()), meta);
    l["drive"] = name + "-learned";
  } catch (const std::exception& e) {
    l["drive_file_error"] = e.what();
  }
}

}  // namespace hystbench::daemon

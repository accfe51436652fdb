#include "service/details/learning_runs.hpp"

#include <spdlog/spdlog.h>

#include <exception>
#include <utility>

#include "hystbench/compensation/number_text.hpp"
#include "runs/details/learned_drive.hpp"
#include "service/details/run_supervisor.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

namespace {
/// The learner's newly scored trials; a learner that throws is failed (the loop must not wait
/// for a drive that will not come) and logged as `who`'s, and gives none.
std::vector<TrackLearning::Trial> poll_or_fail(TrackLearning& learning, const std::string& who) {
  try {
    return learning.poll();
  } catch (const std::exception& e) {
    learning.fail(e.what());
    spdlog::error("{}: the learning failed: {}", who, e.what());
    return {};
  }
}
}  // namespace

LearningRuns::LearningRuns(BenchParts bench, ModelFile model_file)
    : bench_(bench), model_file_(std::move(model_file)) {}

void LearningRuns::started(const std::string& run_id, std::unique_ptr<TrackLearning> learning,
                           std::vector<std::unique_ptr<TrackLearning>> others) {
  run_id_ = learning ? run_id : std::string();
  axis_learning_ = learning ? std::move(others) : std::vector<std::unique_ptr<TrackLearning>>{};
  learning_ = std::move(learning);
}

void LearningRuns::poll() {
  TrackLearning* learning = nullptr;
  std::string run_id;
  std::vector<TrackLearning*> others;
  {
    std::lock_guard lock(bench_.mutex);
    if (!learning_ || bench_.runs.phase() != RunPhase::kRunning) return;
    learning = learning_.get();
    run_id = run_id_;
    for (const auto& l : axis_learning_) others.push_back(l.get());
  }
  // Their exchanges live in the program the loop plays (handed back to this thread when it
  // ends); only this thread polls them.
  const RunProgram* active = bench_.loop.active();
  if (active == nullptr || active->run_id != run_id) return;
  announce_trials(*learning, run_id);
  for (TrackLearning* l : others) (void)poll_or_fail(*l, "run " + run_id + ", another axis");
}

void LearningRuns::announce_trials(TrackLearning& learning, const std::string& run_id) {
  // The last trial's number: trial 0, its repeat (trial 1), then the learned ones.
  const std::size_t learned = learning.request().trials;
  const std::size_t asked = learned > 0 ? learned + 1 : 0;
  const std::vector<TrackLearning::Trial> scored = poll_or_fail(learning, "run " + run_id);
  for (const TrackLearning::Trial& t : scored) {
    const std::string stage = "learning: trial " + std::to_string(t.trial) + " of " +
                              std::to_string(asked) + ", rms " +
                              compensation::fixed(t.rms_percent, 3) + " %";
    {
      std::lock_guard lock(bench_.mutex);
      bench_.runs.set_stage(stage);
    }
    bench_.runs.emit(
        {{"event", "run.progress"},
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

void LearningRuns::finished(const RunProgram& run, json& report) {
  std::unique_ptr<TrackLearning> learning;
  std::string model_file;  // the model the run played with (a run holds model.load off)
  {
    std::lock_guard lock(bench_.mutex);
    if (!learning_ || run.run_id != run_id_) return;
    learning = std::move(learning_);
    run_id_.clear();
    model_file = model_file_("");
  }
  announce_trials(*learning, run.run_id);  // the last trial, closed as the run ended
  json l = learning->result();
  learning->put_last_trial_figures(report);
  keep_learned_drive(*learning, run.run_id, model_file, report.value("tare_um", 0.0),
                     json::object(), l);
  report["learning"] = std::move(l);
}

void LearningRuns::axes_finished(const RunProgram& run, json& report) {
  std::vector<std::unique_ptr<TrackLearning>> learners;
  std::vector<std::string> model_files;  // each axis's model the run played with
  {
    std::lock_guard lock(bench_.mutex);
    if (!learning_ || run.run_id != run_id_) return;
    learners.push_back(std::move(learning_));
    for (auto& l : axis_learning_) learners.push_back(std::move(l));
    axis_learning_.clear();
    run_id_.clear();
    for (const std::string& axis : bench_.settings.axes) model_files.push_back(model_file_(axis));
  }
  for (std::size_t a = 0; a < learners.size() && a < bench_.settings.axes.size(); ++a) {
    TrackLearning& l = *learners[a];
    const std::string& name = bench_.settings.axes[a];
    (void)poll_or_fail(l, "run " + run.run_id + ", axis " + name);  // the last trial, closed
    json& axis = report["axes"][name];
    json learned = l.result();
    l.put_last_trial_figures(axis);
    // Each axis's drive as RUN-AXIS-learned: `track --learned RUN` replays them together.
    keep_learned_drive(
        l, run.run_id + "-" + name, model_files[a], axis.value("tare_um", 0.0),
        {{"stage", {{"run_id", run.run_id}, {"axis", name}, {"axes", bench_.settings.axes}}}},
        learned);
    axis["learning"] = std::move(learned);
  }
  if (report["axes"].contains(bench_.settings.axes.front()) &&
      report["axes"][bench_.settings.axes.front()]["learning"].contains("drive")) {
    report["learned_drive"] = run.run_id;  // the name `track --learned` takes on this stage
  }
}

void LearningRuns::keep_learned_drive(const TrackLearning& learning, const std::string& name,
                                      const std::string& model_file, double tare_um,
                                      const json& more, json& l) const {
  const std::vector<double>& drive = learning.kept_drive();
  const LearningRequest& r = learning.request();
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
        save_learned_drive(bench_.settings.model_dir, name, drive, learning.kept_compensator(),
                           bench_.dt(), learned_for(r, drive.size()), meta);
    l["drive"] = name + "-learned";
  } catch (const std::exception& e) {
    l["drive_file_error"] = e.what();
  }
}

}  // namespace hystbench::daemon::details

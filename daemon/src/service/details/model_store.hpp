#pragma once
// The bench's model store: the active model of a single-axis bench (its file and where it is
// kept), the stage's frequency responses measured last, the generation that counts the changes
// runs see, and the model folder's commands (load, list, delete). A stage's model is the stage
// coordinator's (stage_coordinator.hpp); it bumps the generation here. Not thread-safe: the
// Bench holds its mutex around every call. File I/O: never on the loop thread.
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>

#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/stage_responses.hpp"
#include "service/details/model_folder.hpp"

namespace hystbench::daemon::details {

/// A loaded model's input range against the bench's output limits [u_min, u_max] (V; infinite:
/// not known): reply["input_range"] = {model, limits}, and reply["warning"] where the model was
/// identified on drives beyond the limits by more than 1 % of their span, or on another input
/// unit than the bench's volts.
void check_input_range(const compensation::ActuatorModel& model, double u_min, double u_max,
                       nlohmann::json& reply);

class ModelStore {
 public:
  /// `folder`: BenchSettings::model_dir, where models are kept and read by name; [u_min, u_max]:
  /// the bench's output limits [V], which a loaded model's input range is checked against.
  explicit ModelStore(std::string folder, double u_min = -std::numeric_limits<double>::infinity(),
                      double u_max = std::numeric_limits<double>::infinity())
      : folder_(std::move(folder)), u_min_(u_min), u_max_(u_max) {}

  const std::string& folder() const noexcept { return folder_; }
  /// The active model, or null (none yet, or a stage bench).
  const compensation::ModelFile* active() const noexcept { return model_ ? &*model_ : nullptr; }
  /// Where the active model is kept (empty without one).
  const std::string& active_path() const noexcept { return path_; }
  /// Counts the changes of the models and responses runs see: a plan kept for one generation is
  /// not another's.
  std::uint64_t generation() const noexcept { return generation_; }
  /// A change the store does not hold (a stage's model): the next generation.
  void changed() noexcept { ++generation_; }

  /// Makes `file`, kept at `path`, the active model.
  void adopt(compensation::ModelFile file, std::string path);
  /// model.load on one axis, of the stored model `name` (a name in the folder), or of
  /// `document` kept in the folder under `name`: {path, name, type, invertible, reason,
  /// input_range}, and `warning` where the model was identified on drives beyond the bench's
  /// output limits by more than 1 % of their span (its inverse would ask for drives the limits
  /// clamp: a model of another amplifier's volts). Throws CommandError (bad_params, bad_model,
  /// io_error); nothing changes then.
  nlohmann::json load_stored(const std::string& name);
  nlohmann::json load_document(const std::string& name, const nlohmann::json& document);
  /// model.get: {path, model}. Throws CommandError no_model without one.
  nlohmann::json get() const;
  /// status' "model": {type, path, operators}, or null.
  nlohmann::json summary() const;
  /// model.list and model.delete over the folder; `active_paths` are never deleted.
  nlohmann::json list(std::span<const std::string> active_paths) const;
  nlohmann::json remove(const std::string& name, std::span<const std::string> active_paths);

  /// The responses a feedback is designed on: the active model's, else the last measured; null.
  const compensation::StageResponses* design_responses() const noexcept;
  /// The responses measured last (frf, identify), null when none.
  const compensation::StageResponses* measured_responses() const noexcept {
    return responses_ ? &*responses_ : nullptr;
  }
  /// Keeps responses identify measured for the model it adopts next.
  void set_measured_responses(compensation::StageResponses r) { responses_ = std::move(r); }
  /// Keeps responses frf measured: with the bench, and with the active model, whose file is
  /// saved again. Writes "kept_in" or "save_error" into `report`.
  void keep_frf_responses(compensation::StageResponses r, nlohmann::json& report);

 private:
  /// Adopts a model the folder gave; load's reply.
  nlohmann::json adopt_loaded(FolderModel m);

  std::string folder_;
  double u_min_, u_max_;
  std::optional<compensation::ModelFile> model_;
  std::string path_;
  std::uint64_t generation_ = 0;
  std::optional<compensation::StageResponses> responses_;
};

}  // namespace hystbench::daemon::details

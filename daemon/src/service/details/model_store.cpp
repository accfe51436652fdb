#include "service/details/model_store.hpp"

#include <cmath>
#include <filesystem>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::daemon::details {

namespace hc = compensation;
using nlohmann::json;

void ModelStore::adopt(hc::ModelFile file, std::string path) {
  model_ = std::move(file);
  path_ = std::move(path);
  ++generation_;
}

json ModelStore::load_stored(const std::string& name) {
  return adopt_loaded(load_stored_model(folder_, name));
}

json ModelStore::load_document(const std::string& name, const json& document) {
  return adopt_loaded(keep_model_document(folder_, name, document));
}

void check_input_range(const hc::ActuatorModel& model, double u_min, double u_max, json& reply) {
  const bool known = model.input_max > model.input_min;
  const bool limited = std::isfinite(u_min) && std::isfinite(u_max) && u_max > u_min;
  reply["input_range"] = {
      {"model", known ? json::array({model.input_min, model.input_max}) : json(nullptr)},
      {"limits", limited ? json::array({u_min, u_max}) : json(nullptr)}};
  std::string warning;
  const double tolerance = limited ? 0.01 * (u_max - u_min) : 0.0;
  if (known && limited &&
      (model.input_min < u_min - tolerance || model.input_max > u_max + tolerance)) {
    warning = "the model was identified on drives of [" + hc::significant(model.input_min, 4) +
              ", " + hc::significant(model.input_max, 4) + "] " + model.units.input +
              ", beyond this bench's output limits [" + hc::significant(u_min, 4) + ", " +
              hc::significant(u_max, 4) +
              "] V: its inverse asks for drives the limits clamp (a model of another "
              "amplifier's range?)";
  }
  if (model.units.input != "V") {
    warning += (warning.empty() ? "the model's" : "; its") + std::string(" input is in ") +
               model.units.input + ", the bench drives volts";
  }
  if (!warning.empty()) reply["warning"] = warning;
}

json ModelStore::adopt_loaded(FolderModel m) {
  const auto inv = m.file.model.hysteresis().invertibility();
  const std::string file_name = std::filesystem::path(m.path).filename().string();
  adopt(std::move(m.file), m.path);
  json reply = {{"path", path_},
                {"name", file_name},
                {"type", std::string(hc::to_string(model_->model.hysteresis().kind()))},
                {"invertible", inv.invertible},
                {"reason", inv.reason}};
  check_input_range(model_->model, u_min_, u_max_, reply);
  return reply;
}

json ModelStore::get() const {
  if (!model_) {
    throw common::CommandError("no_model", "no active model (identify or model.load first)");
  }
  return {{"path", path_}, {"model", hc::to_json(*model_)}};
}

json ModelStore::summary() const {
  if (!model_) return nullptr;
  return {{"type", std::string(hc::to_string(model_->model.hysteresis().kind()))},
          {"path", path_},
          {"operators", model_->model.hysteresis().operator_count()}};
}

json ModelStore::list(std::span<const std::string> active_paths) const {
  return list_model_folder(folder_, active_paths);
}

json ModelStore::remove(const std::string& name, std::span<const std::string> active_paths) {
  return delete_from_model_folder(folder_, name, active_paths);
}

const hc::StageResponses* ModelStore::design_responses() const noexcept {
  if (model_ && model_->responses) return &*model_->responses;
  return measured_responses();
}

void ModelStore::keep_frf_responses(hc::StageResponses r, json& report) {
  responses_ = r;
  if (!model_) return;
  model_->responses = std::move(r);
  try {
    if (!path_.empty()) common::save_model_file(path_, *model_);
    report["kept_in"] = path_;
  } catch (const std::exception& e) {
    report["save_error"] = e.what();
  }
}

}  // namespace hystbench::daemon::details

#pragma once
// The daemon's model folder (BenchSettings::model_dir): models a client names, never a path a
// client gives; a name is letters, digits, '.', '_', '-' (at most 128, not starting with '.'),
// ".json" appended when missing. Errors are CommandError naming the key (bad_params,
// bad_model, io_error). File I/O: control thread only, not real-time safe.
#include <nlohmann/json.hpp>
#include <span>
#include <string>

#include "hystbench/compensation/model_file.hpp"
#include "runs/details/folder_name.hpp"

namespace hystbench::daemon::details {

struct FolderModel {
  compensation::ModelFile file;
  std::string path;  ///< in the model folder
};

/// The stored model `name` (model.load's "stored").
FolderModel load_stored_model(const std::string& dir, const std::string& name);
/// A model document (model.load's "model") checked and kept under `name` (its "name"), so
/// `model load --stored` finds it after a restart.
FolderModel keep_model_document(const std::string& dir, const std::string& name,
                                const nlohmann::json& document);
/// model.list: {"folder", "models": [{name, bytes, type, operators, active}]} by name;
/// `active_paths` are the active models' paths (one; a stage's, one per axis) ("type":
/// "unreadable" for a file that is not one).
nlohmann::json list_model_folder(const std::string& dir, std::span<const std::string> active_paths);
/// model.delete: removes model `name` from the folder, or a learned drive (RUN-learned.json and
/// its CSV); {"deleted": [file names]}. Refuses (bad_params) a name that is not there and an
/// active model (`active_paths`).
nlohmann::json delete_from_model_folder(const std::string& dir, const std::string& name,
                                        std::span<const std::string> active_paths);

}  // namespace hystbench::daemon::details

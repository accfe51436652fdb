#pragma once
// The daemon's model folder (BenchSettings::model_dir): models a client names, never a path a
// client gives; a name is letters, digits, '.', '_', '-' (at most 128, not starting with '.'),
// ".json" appended when missing. Errors are CommandError naming the key (bad_params,
// bad_model, io_error). File I/O: control thread only, not real-time safe.
#include <nlohmann/json.hpp>
#include <string>

#include "hystbench/compensation/model_file.hpp"

namespace hystbench::daemon::details {

/// True for a name a client may give for a file in the model folder (see above).
bool is_folder_name(const std::string& name);

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
/// `active_path` is the active model's path ("type": "unreadable" for a file that is not one).
nlohmann::json list_model_folder(const std::string& dir, const std::string& active_path);
/// model.delete: removes model `name` from the folder, or a learned drive (RUN-learned.json and
/// its CSV); {"deleted": [file names]}. Refuses (bad_params) a name that is not there and the
/// active model (`active_path`).
nlohmann::json delete_from_model_folder(const std::string& dir, const std::string& name,
                                        const std::string& active_path);

}  // namespace hystbench::daemon::details

#include "service/details/model_folder.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <vector>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "runs/details/folder_name.hpp"
#include "runs/details/learned_drive.hpp"

namespace hystbench::daemon::details {

namespace fs = std::filesystem;
namespace hc = compensation;
using nlohmann::json;

namespace {

// The file name of model `name` given as request key `key`; never a path.
std::string model_file_name(const std::string& key, const std::string& name) {
  if (!is_folder_name(name)) {
    throw common::CommandError("bad_params",
                               key +
                                   ": a model name (letters, digits, '.', '_', '-'; not a "
                                   "path), as `hystbench model list` shows");
  }
  const bool has_json = name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0;
  return has_json ? name : name + ".json";
}

}  // namespace

FolderModel load_stored_model(const std::string& dir, const std::string& name) {
  const std::string file_name = model_file_name("stored", name);
  const fs::path path = fs::path(dir) / file_name;
  if (!fs::is_regular_file(fs::symlink_status(path))) {
    throw common::CommandError(
        "bad_params",
        "stored: no model '" + file_name + "' in the daemon's model folder (hystbench model list)");
  }
  try {
    return {common::load_model_file(path.string()), path.string()};
  } catch (const std::exception& e) {
    throw common::CommandError("bad_model", e.what());
  }
}

FolderModel keep_model_document(const std::string& dir, const std::string& name,
                                const json& document) {
  const std::string file_name = model_file_name("name", name);
  FolderModel m;
  try {
    m.file = hc::model_file_from_json(document);
  } catch (const std::exception& e) {
    throw common::CommandError("bad_model", std::string("model: ") + e.what());
  }
  m.path = (fs::path(dir) / file_name).string();
  try {
    fs::create_directories(dir);
    common::save_model_file(m.path, m.file);
  } catch (const std::exception& e) {
    throw common::CommandError(
        "io_error", "cannot keep the model in the model folder: " + std::string(e.what()));
  }
  return m;
}

namespace {

bool is_active(const fs::path& path, std::span<const std::string> active_paths) {
  return std::find(active_paths.begin(), active_paths.end(), path.string()) != active_paths.end();
}

}  // namespace

json list_model_folder(const std::string& dir, std::span<const std::string> active_paths) {
  std::error_code ec;
  std::vector<fs::directory_entry> entries;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.is_regular_file() && e.path().extension() == ".json") entries.push_back(e);
  }
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.path().filename() < b.path().filename(); });
  json models = json::array();
  for (const auto& e : entries) {
    json m = {{"name", e.path().filename().string()}, {"bytes", e.file_size()}};
    if (is_learned_drive_file(e.path().filename().string())) {
      m["type"] = "learned_drive";  // track --learned takes it, not model.load
      m["active"] = false;
      models.push_back(std::move(m));
      continue;
    }
    try {
      const hc::ModelFile f = common::load_model_file(e.path().string());
      m["type"] = std::string(hc::to_string(f.model.hysteresis().kind()));
      m["operators"] = f.model.hysteresis().operator_count();
    } catch (const std::exception&) {
      m["type"] = "unreadable";  // never the file's text
    }
    m["active"] = is_active(e.path(), active_paths);
    models.push_back(std::move(m));
  }
  return {{"folder", fs::path(dir).string()}, {"models", models}};
}

json delete_from_model_folder(const std::string& dir, const std::string& name,
                              std::span<const std::string> active_paths) {
  const std::string file_name = model_file_name("name", name);
  const fs::path path = fs::path(dir) / file_name;
  if (!fs::is_regular_file(fs::symlink_status(path))) {
    throw common::CommandError("bad_params",
                               "name: no model or learned drive '" + file_name +
                                   "' in the daemon's model folder (hystbench model list)");
  }
  if (is_active(path, active_paths)) {
    throw common::CommandError(
        "bad_params", "name: '" + file_name + "' is the active model; load another one first");
  }
  // A learned drive is its JSON and the CSV beside it.
  std::vector<fs::path> files{path};
  if (is_learned_drive_file(file_name)) files.push_back(fs::path(path).replace_extension(".csv"));
  json deleted = json::array();
  for (const fs::path& f : files) {
    std::error_code ec;
    if (!fs::remove(f, ec) && ec) {
      throw common::CommandError("io_error", "cannot delete " + f.filename().string() + ": " +
                                                 ec.message() +
                                                 (deleted.empty() ? "; nothing deleted" : ""));
    }
    if (!ec) deleted.push_back(f.filename().string());
  }
  return {{"deleted", deleted}};
}

}  // namespace hystbench::daemon::details

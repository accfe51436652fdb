#pragma once
// Model files on disk: read, checked and written atomically, for the daemon's model folder and
// the CLI's offline commands. Errors are std::runtime_error naming the file and the fault.
// Not real-time safe (file I/O, allocation).
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "hystbench/compensation/mimo_model_file.hpp"
#include "hystbench/compensation/model_file.hpp"

namespace hystbench::common {

/// Reads and validates a model file; throws std::runtime_error naming the file and field.
compensation::ModelFile load_model_file(const std::string& path);
/// Writes a model file atomically (temp file + rename).
void save_model_file(const std::string& path, const compensation::ModelFile& file);
/// Reads and checks a model file on the client side for `model load`: its JSON document, which
/// is what travels to the daemon. Throws std::runtime_error naming the file and the fault (at
/// most 60 KB: a request line must fit the daemon's 64 KiB limit).
nlohmann::json read_model_document(const std::string& path);

/// Reads a model file of several inputs (type mimo_hammerstein); nullopt for another type.
/// Throws std::runtime_error naming the file and the fault.
std::optional<compensation::MimoModelFile> load_mimo_model_file(const std::string& path);
/// Writes one atomically.
void save_mimo_model_file(const std::string& path, const compensation::MimoModelFile& file);

/// Writes any JSON document atomically (temp file + rename), indented; throws
/// std::runtime_error naming the file.
void save_json_document(const std::string& path, const nlohmann::json& doc);

}  // namespace hystbench::common
